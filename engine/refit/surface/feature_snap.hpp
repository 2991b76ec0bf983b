#pragma once
// Beyond the paper: the last step of the surface stage makes the written
// garment pass through the optimised feature curves.
//
// The reconstruction re-emits each vertex as a blend of its nearby agents, so
// a feature sample carried on the output's faces lands near, not on, its
// optimised position. The paper's surface interpolates the feature agents; a
// mesh only does when its vertices are corrected. The correction is carried by
// the feature agents: vertex v moves by sum_a w(v, a) c_a over the feature
// agents a in its snap reach (SurfaceBinding::snap_reach: those within
// SurfaceOptions::snap_radius voxels, w = (1 - d^2/r^2)^2; or, with radius 0,
// the reconstruction's own blend reach and weights), and the c solve one small
// least-squares problem (one row per feature sample, Tikhonov-regularised) so
// the carried samples reach their targets. The correction is smooth (it fades
// with w) and zero where the reconstruction already hit the targets (A = B).
//
// The passes after the first fit what the first leaves, which varies from sample
// to sample; spread over the whole kernel those small corrections alternate from
// sample to sample and show as diamonds on a fine mesh (the 1M dress: a pattern
// 1.5 cm wide beside each side profile). They take a kernel narrowed to a share
// of the radius (SnapKernel), never so narrow that it misses the corners of its
// own sample's face.
#include <refit/attach/attachment.hpp>
#include <refit/core/types.hpp>

#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

namespace refit {

struct FeatureSnapReport {
  double gap_before = 0.0;       // largest distance from a carried feature sample to its target (samples not on a
  double gap_after = 0.0;        // held vertex), before and after the correction (what remains: samples in conflict)
  std::size_t samples_held = 0;  // samples on a (wholly) held vertex: they stay where they are
  std::size_t vertices_moved = 0;
};

/// A vertex a feature sample sits on, as the snap sees it.
struct SnapVertex {
  Vec3 position = Vec3::Zero();  // after the reconstruction
  float held = 0.0f;             // the share of the correction it does not take (1: must not move)
  std::vector<Index> reach;      // its agents within reach
  std::vector<float> weight;     // ... and their blend weights
};
/// Every vertex of the attachment (all three of each sample, weight 0 too), by vertex.
using SnapVertices = std::unordered_map<Index, SnapVertex>;

/// The weights a pass uses: the reach's own, or each feature agent's narrowed
/// to a share of the radius (`scale`, per feature sample: empty, the reach's own).
struct SnapKernel {
  std::vector<double> scale;
  float weight(float w, std::int32_t feature) const;
  /// How much of feature sample `feature`'s correction a vertex with blend
  /// weight `w` takes when it is `held` (SnapVertex::held) where it is.
  double share(float w, std::int32_t feature, float held) const {
    return (1.0 - double(held)) * double(weight(w, feature));
  }
};

/// The narrowed kernel of the passes after the first: per feature sample, the
/// share of the radius its agent keeps, `share` or more where the farthest
/// corner of the sample's face (read off its weight there, (1 - d^2/r^2)^2)
/// needs it (1: a corner out of reach).
SnapKernel narrowed_kernel(const SurfaceAttachment& attachment, const SnapVertices& vertices,
                           const std::vector<std::int32_t>& feature_of, double share);

/// The snap's solution: a correction per feature agent (its sample's row), nf x 3.
struct FeatureSnap {
  Eigen::MatrixXd correction;  // empty: nothing to correct
  FeatureSnapReport report;
};

/// The corrections that carry the samples to `targets` (see above), from the
/// sample vertices alone; report.gap_after and vertices_moved are left to the caller.
FeatureSnap solve_feature_snap(const Points& targets, const SurfaceAttachment& attachment, const SnapVertices& vertices,
                               const std::vector<std::int32_t>& feature_of, bool blend_weights, double regularisation,
                               const SnapKernel& kernel = {});

/// Moves rows of `positions` (all vertices or a chunk; `reach`, `reach_weight`
/// and `held` theirs) by the corrections, each vertex by the share it is not
/// held; returns how many moved.
std::size_t apply_feature_snap(const FeatureSnap& snap, Points& positions, const Csr& reach,
                               const std::vector<float>& reach_weight, const std::vector<std::int32_t>& feature_of,
                               std::span<const float> held, const SnapKernel& kernel = {});

/// Largest distance from a carried sample to its target over the samples not
/// on a held vertex, with the sample vertices moved by the corrections.
double snapped_gap(const FeatureSnap& snap, const Points& targets, const SurfaceAttachment& attachment,
                   const SnapVertices& vertices, const std::vector<std::int32_t>& feature_of, const SnapKernel& kernel = {});

/// Corrects `positions` (every garment vertex) so that the feature samples
/// attached by `attachment` reach `targets`. `reach`/`reach_weight`: each
/// vertex's agents and their weights (the snap reach or the blends, above); `feature_of`: per agent, its
/// feature sample or -1; `held`: per vertex, the share of its correction it
/// does not take (1: must not move; empty: none held).
/// `regularisation`: Tikhonov weight relative to the mean diagonal of the
/// normal equations. `narrow`: the kernel narrowed to this share (narrowed_kernel;
/// 1: the weights as given). Deterministic for any thread count.
FeatureSnapReport snap_to_features(Points& positions, const Points& targets, const SurfaceAttachment& attachment,
                                   const Csr& reach, const std::vector<float>& reach_weight,
                                   const std::vector<std::int32_t>& feature_of, const std::vector<float>& held,
                                   double regularisation, double narrow = 1.0);

}  // namespace refit
