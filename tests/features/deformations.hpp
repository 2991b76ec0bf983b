#pragma once
// Deformations of curve samples for the feature tests.
#include <refit/core/types.hpp>

#include <cmath>
#include <functional>

namespace refit::test {

/// A smooth, non-similar deformation: what a warp around a changed body does.
inline Vec3 bend(const Vec3& p) {
  return Vec3(p.x() + 0.05 * p.y() * p.y(), p.y() + 0.8 * std::sin(0.3 * p.x()), p.z() + 0.02 * p.x() * p.x());
}

/// Every row of p moved by f.
inline Points map_rows(const Points& p, const std::function<Vec3(const Vec3&)>& f) {
  Points out(p.rows(), 3);
  for (Eigen::Index i = 0; i < p.rows(); ++i) out.row(i) = f(row3(p, Index(i))).transpose();
  return out;
}

}  // namespace refit::test
