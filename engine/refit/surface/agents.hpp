#pragma once
// Paper section 5.1: sampling of a discrete surface, the voxel grid that turns
// the samples into agents, and the one-ring of every agent. Works on any
// garment (polygon soups, non-manifold faces, `l` polylines, `p` points and
// unreferenced vertices alike).
#include <refit/core/garment.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace refit {

/// Voxel grid over a box: voxel (i, j, k) covers origin + h * [i, i+1) x [j, j+1) x [k, k+1).
struct VoxelGrid {
  Vec3 origin = Vec3::Zero();
  double h = 1.0;
  /// Integer voxel coordinates of p (clamped at 0; at most 2^21 - 1 per axis).
  std::array<std::uint32_t, 3> cell(const Vec3& p) const;
  Vec3 centre(const std::array<std::uint32_t, 3>& c) const;
  /// 63-bit Morton (Z-order) key of a cell.
  static std::uint64_t morton(const std::array<std::uint32_t, 3>& c);
};

/// Garment agents: each is a linear combination of up to three garment vertices
/// (vertex, point on a hanging edge, point in a face), so its position is known
/// on any state of the garment (original or warped) with the same vertices.
struct GarmentAgents {
  std::vector<std::array<Index, 3>> vertex;  // the combined vertices
  std::vector<std::array<double, 3>> weight;  // their weights (sum 1)
  std::vector<std::uint64_t> voxel;           // Morton key of the agent's voxel
  std::size_t samples = 0;                    // samples considered (vertices + edge + face samples)

  std::size_t size() const { return vertex.size(); }
  /// Positions of the agents on a state of the garment (rows = garment vertices).
  Points positions(const Points& garment_vertices) const;
};

/// Sum of the face areas (polygons fan-triangulated) and of the `l` segment lengths.
/// Throws refit::Error when a position is not finite or an index is out of range.
std::pair<double, double> surface_measure(const Garment& g);

/// Default voxel size: the h with face_area / h^2 + line_length / h about
/// budget / 1.5 agents (a surface crossing a voxel grid touches about 1.5 times
/// more voxels than its area / h^2), or the bounding box diagonal / cbrt(budget)
/// for a garment of points only.
double auto_voxel_size(const Garment& g, std::size_t agent_budget);

/// The grid of voxel size h over the bounding box of `g`'s positions and of `extra` points.
/// Throws refit::Error when h is not positive and finite or the box needs more than 2^21 voxels per axis.
VoxelGrid make_voxel_grid(const Garment& g, const Points& extra, double h);

/// Samples every vertex, every `l` segment by length and every face (fan
/// triangles) by area at spacing about h/2, all on the positions of `g`, and
/// keeps per voxel the sample nearest the voxel centre (ties: the lower sample
/// number). Voxels listed in `skip_voxels` (sorted Morton keys, for example
/// those of feature agents) get no garment agent. Agents come out in Morton
/// order of their voxels. Parallel and deterministic.
GarmentAgents select_agents(const Garment& g, const VoxelGrid& grid, const std::vector<std::uint64_t>& skip_voxels = {});

/// One-ring of every point (section 5.1): repeatedly take the nearest remaining
/// candidate a_c within `radius` as a neighbour and drop every candidate p with
/// (p - a_c).(a_c - a) >= 0. Candidates closer than 1e-9 * radius (coincident
/// points) are ignored. Rows are in the order found (nearest first). Parallel,
/// deterministic.
Csr build_one_rings(const Points& agents, double radius);

}  // namespace refit
