#pragma once
// A feature plane (paper section 4.2): a point, a unit normal and two in-plane
// unit axes with axis_v = normal x axis_u, so (axis_u, axis_v, normal) is a
// right-handed frame and 2D coordinates in it keep their orientation.
#include <refit/core/types.hpp>

namespace refit {

struct FeaturePlane {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();
  Vec3 axis_u = Vec3::UnitX();
  Vec3 axis_v = Vec3::UnitY();

  /// Plane through `point` with normal `normal` (normalised here; must be non-zero),
  /// axis_u chosen deterministically from the normal.
  static FeaturePlane from_point_normal(const Vec3& point, const Vec3& normal);
  /// Signed distance of p to the plane (positive on the normal's side).
  double signed_distance(const Vec3& p) const { return normal.dot(p - point); }
  /// 2D coordinates of p's projection.
  Eigen::Vector2d to_2d(const Vec3& p) const { return {axis_u.dot(p - point), axis_v.dot(p - point)}; }
  Vec3 to_3d(const Eigen::Vector2d& q) const { return point + q.x() * axis_u + q.y() * axis_v; }
  Vec3 project(const Vec3& p) const { return p - signed_distance(p) * normal; }
};

/// Least-squares (PCA) plane of the rows of `a` and `b` together: centroid and the
/// eigenvector of the smallest covariance eigenvalue. The normal's sign and the
/// in-plane axes are arbitrary but deterministic. Needs at least 3 rows in total.
FeaturePlane pca_plane(const Points& a, const Points& b = Points());

}  // namespace refit
