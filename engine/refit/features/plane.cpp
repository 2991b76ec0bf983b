#include <refit/features/plane.hpp>

#include <refit/core/error.hpp>

#include <Eigen/Eigenvalues>
#include <cmath>

namespace refit {

FeaturePlane FeaturePlane::from_point_normal(const Vec3& point, const Vec3& normal) {
  const double len = normal.norm();
  if (!(len > 0.0) || !std::isfinite(len)) throw Error("feature plane: the normal is zero or not finite");
  FeaturePlane p;
  p.point = point;
  p.normal = normal / len;
  // The world axis least aligned with the normal gives a well-conditioned axis_u.
  Eigen::Index k = 0;
  p.normal.cwiseAbs().minCoeff(&k);
  const Vec3 e = Vec3::Unit(k);
  p.axis_u = (e - e.dot(p.normal) * p.normal).normalized();
  p.axis_v = p.normal.cross(p.axis_u);
  return p;
}

FeaturePlane pca_plane(const Points& a, const Points& b) {
  const Eigen::Index n = a.rows() + b.rows();
  if (n < 3) throw Error("PCA plane: need at least 3 points");
  Vec3 c = Vec3::Zero();
  if (a.rows()) c += a.colwise().sum().transpose();
  if (b.rows()) c += b.colwise().sum().transpose();
  c /= static_cast<double>(n);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  auto add = [&](const Points& p) {
    if (!p.rows()) return;
    const Points d = p.rowwise() - c.transpose();
    cov += d.transpose() * d;
  };
  add(a);
  add(b);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);  // eigenvalues ascending
  FeaturePlane p;
  p.point = c;
  p.normal = eig.eigenvectors().col(0).normalized();
  p.axis_u = eig.eigenvectors().col(2).normalized();
  p.axis_v = p.normal.cross(p.axis_u);
  return p;
}

}  // namespace refit
