#include <refit/features/curve_metrics.hpp>

#include <refit/core/error.hpp>
#include <refit/features/bspline.hpp>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <string>

namespace refit {
namespace {

void check_pair(const Points& a, const Points& b, Eigen::Index min_rows, const char* what) {
  if (a.rows() != b.rows())
    throw Error(std::string(what) + ": curves have different sample counts (" + std::to_string(a.rows()) + " and " +
                std::to_string(b.rows()) + ")");
  if (a.rows() < min_rows) throw Error(std::string(what) + ": need at least " + std::to_string(min_rows) + " samples");
}

double turn(const Points& p, Eigen::Index prev, Eigen::Index i, Eigen::Index next) {
  const Vec3 a = (p.row(i) - p.row(prev)).transpose();
  const Vec3 b = (p.row(next) - p.row(i)).transpose();
  const double na = a.norm(), nb = b.norm();
  if (na == 0.0 || nb == 0.0) return 0.0;
  // atan2 of |a x b| and a.b keeps precision for small angles (acos does not).
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

}  // namespace

double shape_error(const Points& curve, const Points& original, bool closed) {
  check_pair(curve, original, 2, "shape error");
  const double length = polyline_length(original, closed);
  if (!(length > 0.0)) throw Error("shape error: the original curve has zero length");
  const Eigen::Matrix3Xd src = original.transpose();
  const Eigen::Matrix3Xd dst = curve.transpose();
  const Eigen::Matrix4d T = Eigen::umeyama(src, dst, true);
  const Eigen::Matrix3Xd aligned = (T.topLeftCorner<3, 3>() * src).colwise() + T.topRightCorner<3, 1>();
  const double rms = std::sqrt((aligned - dst).colwise().squaredNorm().mean());
  return rms / length;
}

double similarity_scale(const Points& original, const Points& curve) {
  check_pair(curve, original, 2, "similarity scale");
  const Eigen::Matrix3Xd src = original.transpose();
  const Eigen::Matrix3Xd dst = curve.transpose();
  return Eigen::umeyama(src, dst, true).topLeftCorner<3, 3>().col(0).norm();
}

double turning_angle_change_deg(const Points& curve, const Points& original, bool closed) {
  check_pair(curve, original, 3, "turning angle");
  const Eigen::Index m = curve.rows();
  double sum = 0.0;
  Eigen::Index count = 0;
  for (Eigen::Index i = closed ? 0 : 1; i < (closed ? m : m - 1); ++i) {
    const Eigen::Index prev = (i + m - 1) % m, next = (i + 1) % m;
    sum += std::abs(turn(curve, prev, i, next) - turn(original, prev, i, next));
    ++count;
  }
  return sum / static_cast<double>(count) * 180.0 / std::numbers::pi;
}

}  // namespace refit
