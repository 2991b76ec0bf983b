#pragma once
// Paper section 5.3, controlled reconstruction: a local frame at every agent
// from its one-ring fan, orientation made consistent over the agents by
// minimal-spanning-tree propagation (Hoppe et al.), and garment vertices
// re-emitted from the frames and blended as eq. 4.
#include <refit/core/types.hpp>

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace refit {

/// Sorts each ring (in place) by angle around a least-squares normal of the ring
/// at `x`, so that consecutive neighbours span the fan triangles (a, a_i, a_{i+1}).
/// open[a] = 1 when the largest angular gap exceeds pi (a boundary agent): its row
/// then starts after that gap and the fan does not wrap round.
void order_rings(const Points& x, Csr& ring, std::vector<std::uint8_t>& open);

/// Fan normal of every agent: the sum of the normals (a_i - a) x (a_{i+1} - a) of its
/// fan (area-weighted average), normalised; zero when the fan is degenerate.
Points fan_normals(const Points& x, const Csr& ring, const std::vector<std::uint8_t>& open);

/// Per agent +1 or -1 so that sign * normal is consistent along a minimal spanning
/// tree of the one-ring graph with edge cost 1 - |n_a . n_b| (Hoppe-style
/// propagation); the root of each connected group keeps its sign. Deterministic.
std::vector<std::int8_t> orient_normals(const Points& normals, const Csr& ring);

/// Orthonormal frame per agent: columns (tangent, normal, tangent x normal); the
/// tangent is a_1 - a projected on the tangent plane (the next neighbour if that
/// vanishes). valid = 0 where the fan has no normal.
struct AgentFrames {
  Points origin;
  std::vector<Eigen::Matrix3d> axes;
  std::vector<std::uint8_t> valid;
};

/// Frames at `x` with ring order and flips from order_rings and orient_normals.
AgentFrames agent_frames(const Points& x, const Csr& ring, const std::vector<std::uint8_t>& open,
                         const std::vector<std::int8_t>& flip);

/// Per agent the rotation that best carries its one-ring from `from` to `to`
/// (least squares over the ring edges a_i - a, Kabsch: SVD of the 3x3 covariance,
/// determinant fixed to +1). An improvement over the paper's fan frames (section
/// 5.3): the fan normal and the single-neighbour tangent of an irregular agent
/// ring are noisy, and their noise times the distance to a vertex shows as
/// texture; the fit uses every neighbour. Identity where the ring has fewer than
/// two non-collinear edges. Exactly the identity (to rounding) when from == to.
std::vector<Eigen::Matrix3d> ring_rotations(const Points& from, const Points& to, const Csr& ring);

/// Per agent the stretch S (symmetric, positive) of the least-squares affine map
/// A = R S that carries its whole group (agents with the same `group` id: a
/// connected piece) from `from` to `to`. Beyond the paper: the surface step
/// scales the local shape encoding by it, so the garment keeps its shape but
/// follows the body's change of size and proportions (a 9 % shorter body gives a
/// 9 % shorter jacket); a uniform affine change of the warp is then reproduced
/// exactly. One map per piece, not per agent: a local fit would copy the body's
/// bumps that the surface step is there to remove. Identity for pieces of fewer
/// than `min_agents` agents or with a flat or degenerate spread.
std::vector<Eigen::Matrix3d> group_stretches(const Points& from, const Points& to, const std::vector<Index>& group,
                                             std::size_t min_agents = 10);

/// Rotation from `before` to `after` frames per agent (after.axes * before.axes^T;
/// identity where either frame is invalid): the paper's fan frames as rotations,
/// so reconstruct_rotations with these and empty weights is the paper's eq.-4
/// re-emission (local coordinates in the frame before, emitted from the frame after).
std::vector<Eigen::Matrix3d> frame_rotations(const AgentFrames& before, const AgentFrames& after);

/// Re-emits every vertex (rows of `vertices`, on the `before` state) from the
/// agents reach.row(v): q = sum_j w_j (after_j + R_j (p - before_j)) / sum_j w_j.
/// With `weights` (parallel to reach.indices) those weights are used; with an
/// empty `weights` the eq.-4 weights w = 1/(1e-8 + |p - before_j|^3) (|local| of
/// eq. 4: a rotation keeps the length). A vertex with an empty list moves with
/// agent nearest[v] (translation only). An agent with keep[j] != 0 (keep non-empty)
/// contributes the vertex's row of `kept` instead (an agent that did not move).
/// Deterministic, parallel.
Points reconstruct_rotations(const Points& vertices, const Points& before, const Points& after,
                             const std::vector<Eigen::Matrix3d>& rotation, const Csr& reach,
                             const std::vector<float>& weights, const std::vector<Index>& nearest,
                             const std::vector<std::uint8_t>& keep = {}, const Points* kept = nullptr);

}  // namespace refit
