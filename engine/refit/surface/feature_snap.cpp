#include <refit/core/parallel.hpp>
#include <refit/surface/feature_snap.hpp>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>

namespace refit {

namespace {

// Sample k carried on the sample vertices' positions (moved by the corrections when given): carry_one's sums.
Vec3 carried(const SurfaceAttachment& at, const SnapVertices& vs, Index k, const FeatureSnap* snap,
             const std::vector<std::int32_t>* feature_of, const SnapKernel& kernel) {
  const auto s = static_cast<std::size_t>(k);
  Vec3 q = row3(at.offset, k);
  for (int j = 0; j < 3; ++j) {
    const SnapVertex& v = vs.at(at.vertex[s][j]);
    Vec3 p = v.position;
    if (snap && v.held < 1.0f)
      for (std::size_t r = 0; r < v.reach.size(); ++r) {
        const std::int32_t f = (*feature_of)[v.reach[r]];
        if (f >= 0) p += (kernel.share(v.weight[r], f, v.held) * snap->correction.row(f)).transpose();
      }
    q += at.weight[s][j] * p;
  }
  return q;
}

std::vector<std::uint8_t> samples_on_held(const SurfaceAttachment& at, const SnapVertices& vs, std::size_t nf) {
  std::vector<std::uint8_t> on_held(nf, 0);
  for (std::size_t k = 0; k < nf; ++k)
    for (int j = 0; j < 3; ++j) on_held[k] |= at.weight[k][j] != 0.0 && vs.at(at.vertex[k][j]).held >= 1.0f;
  return on_held;
}

double largest_gap(const Points& targets, const SurfaceAttachment& at, const SnapVertices& vs,
                   const std::vector<std::uint8_t>& on_held, const FeatureSnap* snap,
                   const std::vector<std::int32_t>* feature_of, const SnapKernel& kernel) {
  double gap = 0.0;
  for (Eigen::Index k = 0; k < targets.rows(); ++k)
    if (!on_held[std::size_t(k)])
      gap = std::max(gap, (row3(targets, Index(k)) - carried(at, vs, Index(k), snap, feature_of, kernel)).norm());
  return gap;
}

}  // namespace

float SnapKernel::weight(float w, std::int32_t feature) const {
  if (scale.empty()) return w;
  const double q = scale[std::size_t(feature)];
  if (q >= 1.0) return w;
  // w = (1 - d^2/r^2)^2, so d^2/r^2 = 1 - sqrt(w); within the radius q r: (1 - d^2/(q r)^2)^2.
  const double t = (1.0 - std::sqrt(double(w))) / (q * q);
  return t < 1.0 ? float((1.0 - t) * (1.0 - t)) : 0.0f;
}

SnapKernel narrowed_kernel(const SurfaceAttachment& at, const SnapVertices& vs, const std::vector<std::int32_t>& feature_of,
                           double share) {
  SnapKernel kernel;
  if (!(share < 1.0)) return kernel;
  const std::size_t nf = at.vertex.size();
  kernel.scale.assign(nf, share);
  // The narrowed kernel reaches three times as far as the farthest corner of the
  // sample's face: on a coarse face (the shared garments' 2 cm against a 5 cm
  // radius) the kernel stays whole, as only a fine mesh shows the alternation.
  constexpr double kCornerMargin = 3.0;
  for (std::size_t k = 0; k < nf; ++k)
    for (int j = 0; j < 3; ++j) {
      if (at.weight[k][j] == 0.0) continue;
      const SnapVertex& v = vs.at(at.vertex[k][j]);
      if (v.held >= 1.0f) continue;
      double d = 1.0;  // a corner out of the agent's reach: the whole radius
      for (std::size_t r = 0; r < v.reach.size() && r < v.weight.size(); ++r)
        if (feature_of[v.reach[r]] == std::int32_t(k)) d = std::sqrt(std::max(0.0, 1.0 - std::sqrt(double(v.weight[r]))));
      kernel.scale[k] = std::min(1.0, std::max(kernel.scale[k], kCornerMargin * d));
    }
  return kernel;
}

FeatureSnap solve_feature_snap(const Points& targets, const SurfaceAttachment& at, const SnapVertices& vs,
                               const std::vector<std::int32_t>& feature_of, bool blend_weights, double regularisation,
                               const SnapKernel& kernel) {
  FeatureSnap snap;
  FeatureSnapReport& rep = snap.report;
  const auto nf = static_cast<Eigen::Index>(targets.rows());
  // A sample on a held vertex asks to stay where it is: snapping the free rest of
  // its curve alone would leave a step where the held part begins.
  const std::vector<std::uint8_t> on_held = samples_on_held(at, vs, std::size_t(nf));
  rep.samples_held = std::size_t(std::count(on_held.begin(), on_held.end(), 1));
  rep.gap_before = rep.gap_after = largest_gap(targets, at, vs, on_held, nullptr, nullptr, kernel);
  if (nf == 0 || !blend_weights || !(rep.gap_before > 0.0)) return snap;
  // Row k: how sample k's carried position moves with each feature agent's correction.
  Eigen::MatrixXd residual(nf, 3);
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index k = 0; k < nf; ++k) {
    residual.row(k) = on_held[std::size_t(k)] ? Eigen::RowVector3d::Zero()
                              : Eigen::RowVector3d(targets.row(k) - carried(at, vs, Index(k), nullptr, nullptr, kernel).transpose());
    for (int j = 0; j < 3; ++j) {
      const Index v = at.vertex[std::size_t(k)][j];
      const double w = at.weight[std::size_t(k)][j];
      const SnapVertex& sv = vs.at(v);
      if (w == 0.0 || sv.held >= 1.0f) continue;
      for (std::size_t q = 0; q < sv.reach.size(); ++q)
        if (const std::int32_t f = feature_of[sv.reach[q]]; f >= 0)
          entries.emplace_back(k, f, w * kernel.share(sv.weight[q], f, sv.held));
    }
  }
  Eigen::SparseMatrix<double> a(nf, nf);
  a.setFromTriplets(entries.begin(), entries.end());
  Eigen::SparseMatrix<double> normal = a.transpose() * a;
  const double mean_diagonal = normal.diagonal().sum() / double(nf);
  if (!(mean_diagonal > 0.0)) return snap;
  // The regularisation keeps corrections bounded where samples conflict (two
  // curves crossing one coarse face with slightly different targets) or where
  // a sample's vertices see a feature agent only faintly.
  Eigen::SparseMatrix<double> identity(nf, nf);
  identity.setIdentity();
  normal += (regularisation * mean_diagonal) * identity;
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(normal);
  if (ldlt.info() != Eigen::Success) return snap;
  snap.correction = ldlt.solve(Eigen::MatrixXd(a.transpose() * residual));
  return snap;
}

std::size_t apply_feature_snap(const FeatureSnap& snap, Points& positions, const Csr& reach,
                               const std::vector<float>& reach_weight, const std::vector<std::int32_t>& feature_of,
                               std::span<const float> held, const SnapKernel& kernel) {
  if (snap.correction.size() == 0) return 0;
  const Eigen::MatrixXd& c = snap.correction;
  std::vector<std::uint8_t> moved(positions.rows(), 0);
  parallel_for(0, std::size_t(positions.rows()), 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      const float h = held.empty() ? 0.0f : held[v];
      if (!(h < 1.0f)) continue;
      auto r = reach.row(v);
      for (std::size_t q = 0; q < r.size(); ++q) {
        const std::int32_t f = feature_of[r[q]];
        if (f < 0) continue;
        positions.row(Eigen::Index(v)) += kernel.share(reach_weight[reach.offsets[v] + q], f, h) * c.row(f);
        moved[v] = 1;
      }
    }
  });
  std::size_t count = 0;
  for (std::uint8_t m : moved) count += m;
  return count;
}

double snapped_gap(const FeatureSnap& snap, const Points& targets, const SurfaceAttachment& at, const SnapVertices& vs,
                   const std::vector<std::int32_t>& feature_of, const SnapKernel& kernel) {
  if (snap.correction.size() == 0) return snap.report.gap_after;
  return largest_gap(targets, at, vs, samples_on_held(at, vs, std::size_t(targets.rows())), &snap, &feature_of, kernel);
}

FeatureSnapReport snap_to_features(Points& positions, const Points& targets, const SurfaceAttachment& at,
                                   const Csr& reach, const std::vector<float>& reach_weight,
                                   const std::vector<std::int32_t>& feature_of, const std::vector<float>& held,
                                   double regularisation, double narrow) {
  SnapVertices vs;
  for (const auto& corners : at.vertex)
    for (Index v : corners) {
      if (vs.count(v)) continue;
      SnapVertex& sv = vs[v];
      sv.position = row3(positions, v);
      sv.held = held.empty() ? 0.0f : held[v];
      const auto r = reach.row(v);
      sv.reach.assign(r.begin(), r.end());
      if (!reach_weight.empty())
        sv.weight.assign(reach_weight.begin() + reach.offsets[v], reach_weight.begin() + reach.offsets[v + 1]);
    }
  const SnapKernel kernel = narrowed_kernel(at, vs, feature_of, narrow);
  FeatureSnap snap = solve_feature_snap(targets, at, vs, feature_of, !reach_weight.empty(), regularisation, kernel);
  snap.report.vertices_moved = apply_feature_snap(snap, positions, reach, reach_weight, feature_of, held, kernel);
  snap.report.gap_after = snapped_gap(snap, targets, at, vs, feature_of, kernel);
  return snap.report;
}

}  // namespace refit
