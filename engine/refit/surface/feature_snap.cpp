#include <refit/core/parallel.hpp>
#include <refit/surface/feature_snap.hpp>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>

namespace refit {

namespace {

// Largest distance from a sample carried on `positions` to its target, over the samples not on a held vertex.
double largest_gap(const Points& positions, const Points& targets, const SurfaceAttachment& at,
                   const std::vector<std::uint8_t>& on_held) {
  double gap = 0.0;
  for (Eigen::Index k = 0; k < targets.rows(); ++k)
    if (!on_held[std::size_t(k)]) gap = std::max(gap, (row3(targets, Index(k)) - carry_one(at, positions, Index(k))).norm());
  return gap;
}

}  // namespace

FeatureSnapReport snap_to_features(Points& positions, const Points& targets, const SurfaceAttachment& at,
                                   const Csr& reach, const std::vector<float>& reach_weight,
                                   const std::vector<std::int32_t>& feature_of, const std::vector<std::uint8_t>& held,
                                   double regularisation) {
  FeatureSnapReport rep;
  const auto nf = static_cast<Eigen::Index>(targets.rows());
  auto is_held = [&](Index v) { return !held.empty() && held[v]; };
  // A sample on a held vertex asks to stay where it is: snapping the free rest of
  // its curve alone would leave a step where the held part begins.
  std::vector<std::uint8_t> on_held(std::size_t(nf), 0);
  for (std::size_t k = 0; k < std::size_t(nf); ++k)
    for (int j = 0; j < 3; ++j) on_held[k] |= at.weight[k][j] != 0.0 && is_held(at.vertex[k][j]);
  rep.samples_held = std::size_t(std::count(on_held.begin(), on_held.end(), 1));
  rep.gap_before = rep.gap_after = largest_gap(positions, targets, at, on_held);
  if (nf == 0 || reach_weight.empty() || !(rep.gap_before > 0.0)) return rep;
  // Row k: how sample k's carried position moves with each feature agent's correction.
  Eigen::MatrixXd residual(nf, 3);
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index k = 0; k < nf; ++k) {
    residual.row(k) = on_held[std::size_t(k)] ? Eigen::RowVector3d::Zero()
                              : Eigen::RowVector3d(targets.row(k) - carry_one(at, positions, Index(k)).transpose());
    for (int j = 0; j < 3; ++j) {
      const Index v = at.vertex[std::size_t(k)][j];
      const double w = at.weight[std::size_t(k)][j];
      if (w == 0.0 || is_held(v)) continue;
      auto r = reach.row(v);
      for (std::size_t q = 0; q < r.size(); ++q)
        if (feature_of[r[q]] >= 0) entries.emplace_back(k, feature_of[r[q]], w * reach_weight[reach.offsets[v] + q]);
    }
  }
  Eigen::SparseMatrix<double> a(nf, nf);
  a.setFromTriplets(entries.begin(), entries.end());
  Eigen::SparseMatrix<double> normal = a.transpose() * a;
  const double mean_diagonal = normal.diagonal().sum() / double(nf);
  if (!(mean_diagonal > 0.0)) return rep;
  // The regularisation keeps corrections bounded where samples conflict (two
  // curves crossing one coarse face with slightly different targets) or where
  // a sample's vertices see a feature agent only faintly.
  Eigen::SparseMatrix<double> identity(nf, nf);
  identity.setIdentity();
  normal += (regularisation * mean_diagonal) * identity;
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(normal);
  if (ldlt.info() != Eigen::Success) return rep;
  const Eigen::MatrixXd c = ldlt.solve(Eigen::MatrixXd(a.transpose() * residual));
  std::vector<std::uint8_t> moved(positions.rows(), 0);
  parallel_for(0, std::size_t(positions.rows()), 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      if (is_held(Index(v))) continue;
      auto r = reach.row(v);
      for (std::size_t q = 0; q < r.size(); ++q) {
        const std::int32_t f = feature_of[r[q]];
        if (f < 0) continue;
        positions.row(Eigen::Index(v)) += double(reach_weight[reach.offsets[v] + q]) * c.row(f);
        moved[v] = 1;
      }
    }
  });
  for (std::uint8_t m : moved) rep.vertices_moved += m;
  rep.gap_after = largest_gap(positions, targets, at, on_held);
  return rep;
}

}  // namespace refit
