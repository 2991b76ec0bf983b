// Measures of a flattened piece; see measures.hpp.
#include <refit/patterns/measures.hpp>

#include <refit/patterns/lengths.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>

namespace refit {

std::array<double, 2> face_singular_values(const Points& xyz, const Points2& uv) {
  const Eigen::RowVector3d c = xyz.colwise().mean();
  const Points d = xyz.rowwise() - c;
  // The face's plane: the two main directions of its corners, oriented by the corners' winding (Newell normal).
  Vec3 normal = Vec3::Zero();
  for (Eigen::Index i = 0; i < xyz.rows(); ++i) normal += row3(xyz, static_cast<Index>(i)).cross(row3(xyz, static_cast<Index>((i + 1) % xyz.rows())));
  if (!(normal.norm() > 0)) return {0.0, 0.0};
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(d.transpose() * d);
  Vec3 e1 = pca.eigenvectors().col(2);
  Vec3 e2 = normal.normalized().cross(e1);
  e1 = e2.cross(normal.normalized());
  Eigen::Matrix<double, Eigen::Dynamic, 2> x(xyz.rows(), 2);
  x.col(0) = d * e1;
  x.col(1) = d * e2;
  const Points2 q = uv.rowwise() - uv.colwise().mean();
  const Eigen::Matrix2d xx = x.transpose() * x;
  if (!(std::abs(xx.determinant()) > 1e-30 * xx.squaredNorm())) return {0.0, 0.0};
  const Eigen::Matrix2d J = (q.transpose() * x) * xx.inverse();
  // Closed-form 2x2 singular values; the second negative when J turns over.
  const double E = 0.5 * (J(0, 0) + J(1, 1)), F = 0.5 * (J(0, 0) - J(1, 1));
  const double G = 0.5 * (J(1, 0) + J(0, 1)), H = 0.5 * (J(1, 0) - J(0, 1));
  const double a = std::hypot(E, H), b = std::hypot(F, G);
  return {a + b, a - b};
}

double log_stretch(const std::array<double, 2>& s) {
  if (s[0] == 0 && s[1] == 0) return 0.0;  // no area in 3D: nothing to stretch
  // A face turned over is counted apart (PieceStretch::flipped); a collapsed one stays finite.
  const auto log_of = [](double x) { return std::abs(std::log(std::max(std::abs(x), 1e-12))); };
  return std::max(log_of(s[0]), log_of(s[1]));
}

PieceStretch measure_piece(const Garment& g, const PanelSet& set, std::size_t k, const Points& xyz, const Points2& uv) {
  const Panel& panel = set.panels[k];
  PieceStretch out;
  const auto gather = [&](auto rows, Points& p3, Points2& p2) {
    p3.resize(static_cast<Eigen::Index>(rows.size()), 3);
    p2.resize(static_cast<Eigen::Index>(rows.size()), 2);
    for (std::size_t i = 0; i < rows.size(); ++i) {
      p3.row(static_cast<Eigen::Index>(i)) = xyz.row(rows[i]);
      p2.row(static_cast<Eigen::Index>(i)) = uv.row(rows[i]);
    }
  };
  Points p3;
  Points2 p2;
  out.face.reserve(panel.faces.size());
  std::size_t t = 0;
  std::vector<Index> corners;
  for (Index f : panel.faces) {
    const Index c0 = g.faces.offsets[f];
    corners.assign(set.corner_vertex.begin() + c0, set.corner_vertex.begin() + c0 + g.faces.row_size(f));
    // In the panel's winding: a face the panel turned (panels.cpp) has its fan reversed.
    if (t < panel.triangles.size() && corners.size() >= 3 && panel.triangles[t][1] != corners[1])
      std::reverse(corners.begin() + 1, corners.end());
    gather(corners, p3, p2);
    const std::array<double, 2> s = face_singular_values(p3, p2);
    out.face.push_back(log_stretch(s));
    out.flipped += s[1] < 0;
    for (; t < panel.triangles.size() && panel.triangle_face[t] == f; ++t) {
      const Triangle& tri = panel.triangles[t];
      gather(std::span<const Index>(tri), p3, p2);
      out.triangle.push_back(log_stretch(face_singular_values(p3, p2)));
      const Vec3 a = row3(xyz, tri[0]), b = row3(xyz, tri[1]), c = row3(xyz, tri[2]);
      out.area_3d += 0.5 * (b - a).cross(c - a).norm();
      const Eigen::Vector2d e = uv.row(tri[1]) - uv.row(tri[0]), h = uv.row(tri[2]) - uv.row(tri[0]);
      out.area_2d += 0.5 * (e.x() * h.y() - e.y() * h.x());
    }
  }
  for (const auto& loop : panel.loops) {
    out.perimeter_3d += indexed_length(xyz, loop, true);
    out.perimeter_2d += indexed_length(uv, loop, true);
  }
  return out;
}

}  // namespace refit
