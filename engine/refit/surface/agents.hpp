#pragma once
// Paper section 5.1: sampling of a discrete surface, the voxel grid that turns
// the samples into agents, and the one-ring of every agent. Works on any
// garment (polygon soups, non-manifold faces, `l` polylines, `p` points and
// unreferenced vertices alike).
#include <refit/core/garment.hpp>
#include <refit/surface/samples.hpp>

#include <array>
#include <compare>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
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

/// The key by which select_agents elects, per voxel and layer, the sample at
/// `p` (sample number `id`) nearest the voxel's centre (the smallest key wins).
sampling::SampleKey sample_key(const VoxelGrid& grid, const Vec3& p, std::uint64_t id, std::uint32_t layer);

/// Garment agents: each is a linear combination of up to three garment vertices
/// (vertex, point on a hanging edge, point in a face), so its position is known
/// on any state of the garment (original or warped) with the same vertices.
struct GarmentAgents {
  std::vector<std::array<Index, 3>> vertex;  // the combined vertices
  std::vector<std::array<double, 3>> weight;  // their weights (sum 1)
  std::vector<std::uint64_t> voxel;           // Morton key of the agent's voxel
  std::vector<std::uint32_t> layer;           // the agent's layer (see garment_layers)
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
/// The same from the garment's face area, line length and bounding box extent (none: no vertex).
double auto_voxel_size(double area, double length, const std::optional<Vec3>& extent, std::size_t agent_budget);

/// The grid of voxel size h over the bounding box of `g`'s positions and of `extra` points.
/// Throws refit::Error when h is not positive and finite or the box needs more than 2^21 voxels per axis.
VoxelGrid make_voxel_grid(const Garment& g, const Points& extra, double h);
/// The same over the box [lo, hi] (a garment's positions' box) and `extra`.
VoxelGrid make_voxel_grid(Vec3 lo, Vec3 hi, const Points& extra, double h);

/// Layers of a garment (beyond the paper, which samples all of a garment into
/// one voxel grid: where two layers lie closer than a voxel, such as a dress
/// over trousers or a slip, a voxel's one agent stands on either, and each
/// layer follows the other's motion). The pieces of the garment's faces, lines
/// and points, connected through shared vertices after welding coincident ones
/// (1e-6 of the bounding box diagonal: soups and split seams stay one piece),
/// and pieces whose face boundaries come within `join_distance` of each other
/// (panels cut apart with a small gap between them) joined; a piece whose face
/// area is at least `min_area` is a layer, numbered 1, 2, ... in the order of
/// its first vertex (a line or point sharing a vertex with a layer's faces is
/// part of it). Everything else (small pieces, points and lines on their own,
/// unreferenced vertices) is layer 0, "loose": it belongs to no layer and moves
/// with whatever surface is near it. Per vertex.
std::vector<std::uint32_t> garment_layers(const Garment& g, double min_area, double join_distance);

/// A voxel of one layer.
struct VoxelLayer {
  std::uint64_t voxel = 0;  // Morton key
  std::uint32_t layer = 0;
  auto operator<=>(const VoxelLayer&) const = default;
};

/// Samples every vertex, every `l` segment by length and every face (fan
/// triangles) by area at spacing about h/2, all on the positions of `g`, and
/// keeps per voxel and layer (`vertex_layer`, per vertex; empty: all layer 0)
/// the sample nearest the voxel centre (ties: the lower sample number). Pairs
/// listed in `skip` (sorted; for example those of feature agents) get no
/// garment agent. Agents come out in Morton order of their voxels, then by
/// layer. Parallel and deterministic.
GarmentAgents select_agents(const Garment& g, const VoxelGrid& grid, const std::vector<VoxelLayer>& skip = {},
                            const std::vector<std::uint32_t>& vertex_layer = {});

/// One-ring of every point (section 5.1): repeatedly take the nearest remaining
/// candidate a_c within `radius` as a neighbour and drop every candidate p with
/// (p - a_c).(a_c - a) >= 0. Candidates closer than 1e-9 * radius (coincident
/// points) are ignored. Rows are in the order found (nearest first). Parallel,
/// deterministic.
///
/// With `layer` (per point; see garment_layers), a point of a layer takes
/// candidates of its own layer only; a loose point (layer 0) takes any.
Csr build_one_rings(const Points& agents, double radius, const std::vector<std::uint32_t>& layer = {});

/// k nearest points of the same layer (loose queries: of any layer).
/// Throws refit::Error("surface: WHAT row N is not finite") for the first row of
/// `points` that is not finite.
void check_finite(const Points& points, const std::string& what);

class LayerTrees {
 public:
  LayerTrees(const Points& points, const std::vector<std::uint32_t>& layer);
  ~LayerTrees();
  /// The k nearest points of layer `layer` (0: of all), closest first, as indices into the points.
  /// `hint`: as PointTree::knn's, points of that layer (e.g. the previous query's answer).
  void knn(std::uint32_t layer, const Vec3& p, std::size_t k, std::vector<Index>& idx, std::vector<double>& dist2,
           std::span<const Vec3> hint = {}) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace refit
