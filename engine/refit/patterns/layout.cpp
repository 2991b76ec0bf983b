// Grain orientation and shelf packing of pattern pieces.
#include <refit/patterns/layout.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace refit {

double grain_rotation(const Points& xyz, const Points2& uv, std::span<const Triangle> tris, const Vec3& up) {
  Eigen::Vector2d sum(0, 0);
  for (const Triangle& t : tris) {
    const Vec3 e1 = row3(xyz, t[1]) - row3(xyz, t[0]), e2 = row3(xyz, t[2]) - row3(xyz, t[0]);
    const double area = e1.cross(e2).norm();
    if (!(area > 0)) continue;
    // up's projection on the triangle as a e1 + b e2, carried to the plane by the same combination.
    Eigen::Matrix2d gram;
    gram << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
    const Eigen::Vector2d ab = gram.ldlt().solve(Eigen::Vector2d(e1.dot(up), e2.dot(up)));
    const Eigen::Vector2d q1 = (uv.row(t[1]) - uv.row(t[0])).transpose(), q2 = (uv.row(t[2]) - uv.row(t[0])).transpose();
    sum += area * (ab[0] * q1 + ab[1] * q2);
  }
  if (!(sum.norm() > 0)) return 0.0;
  return std::atan2(sum.x(), sum.y());  // turns `sum` onto +y
}

Points2 rotated(const Points2& uv, double angle) {
  const Eigen::Matrix2d r = Eigen::Rotation2Dd(angle).toRotationMatrix();
  return uv * r.transpose();
}

Packing pack_boxes(std::span<const Box> boxes, double margin) {
  Packing out;
  out.corner.assign(boxes.size(), Eigen::Vector2d::Zero());
  if (boxes.empty()) return out;
  double area = 0, widest = 0;
  for (const Box& b : boxes) {
    area += (b.width + margin) * (b.height + margin);
    widest = std::max(widest, b.width);
  }
  const double row_width = std::max(widest, 1.5 * std::sqrt(area));
  std::vector<std::size_t> order(boxes.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return boxes[a].height > boxes[b].height; });
  // Rows go downwards from y = 0; shifted up at the end so the sheet starts at 0.
  double x = 0, top = 0, row_height = 0;
  for (std::size_t i : order) {
    const Box& b = boxes[i];
    if (x > 0 && x + b.width > row_width) {
      top -= row_height + margin;
      x = 0, row_height = 0;
    }
    out.corner[i] = Eigen::Vector2d(x, top - b.height);
    x += b.width + margin;
    row_height = std::max(row_height, b.height);
    out.width = std::max(out.width, x - margin);
  }
  const double bottom = top - row_height;
  for (auto& c : out.corner) c.y() -= bottom;
  out.height = -bottom;
  return out;
}

}  // namespace refit
