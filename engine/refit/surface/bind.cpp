// Binding the surface step on the original garment: samples and agents, their
// one-rings and storage order, the features' zone, the encoding (eqs. 10-12)
// and the coarse levels. The vertex blends are bound in reconstruct.cpp.
#include <refit/core/error.hpp>
#include <refit/core/progress.hpp>
#include <refit/surface/agents.hpp>
#include <refit/surface/coarse_levels.hpp>
#include <refit/surface/surface.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace refit {

namespace {

}  // namespace

void check_surface_options(const SurfaceOptions& o) {
  auto bad = [](const std::string& m) { return Error("surface: " + m); };
  if (!(o.voxel >= 0.0) || !std::isfinite(o.voxel)) throw bad("voxel size must be 0 (auto) or positive");
  if (o.voxel == 0.0 && o.agent_budget == 0) throw bad("agent budget must be at least 1");
  if (!(o.epsilon >= 0.0)) throw bad("epsilon must be non-negative");
  if (o.max_iterations < 0) throw bad("max iterations must be non-negative");
  if (!(o.tolerance >= 0.0)) throw bad("tolerance must be non-negative");
  if (!(o.relaxation > 0.0 && o.relaxation < 2.0)) throw bad("relaxation must lie in (0, 2)");
  if (!(o.reach_voxels > 0.0) || !std::isfinite(o.reach_voxels)) throw bad("reach must be positive");
  if (!(o.ring_radius_voxels > 0.0) || !std::isfinite(o.ring_radius_voxels)) throw bad("one-ring radius must be positive");
  if (!(o.block_voxels > 0.0) || !std::isfinite(o.block_voxels)) throw bad("block size must be positive");
  if (o.smooth_passes < 0) throw bad("smooth passes must be non-negative");
  if (o.multigrid_sweeps < 1 || o.coarsest_sweeps < 1 || o.krylov_cycle_sweeps < 1)
    throw bad("multigrid sweeps must be at least 1");
  if (!(o.tolerance_rms >= 0.0)) throw bad("RMS tolerance must be non-negative");
  if (o.coarse_start_sweeps < 1) throw bad("coarse start sweeps must be at least 1");
  if (!(o.multigrid_overcorrection > 0.0 && o.multigrid_overcorrection < 2.0))
    throw bad("multigrid over-correction must lie in (0, 2)");
  if (o.max_reach_agents == 0 || o.max_reach_agents > 255) throw bad("max reach agents must be 1 to 255");
  if (o.feature_zone_rings < 0 || o.feature_zone_rings > 16) throw bad("feature zone must be 0 to 16 one-ring steps");
  if (!(o.zone_edge_blend >= 0.0 && o.zone_edge_blend <= 0.5)) throw bad("zone edge blend must be 0 to 0.5");
  if (o.feature_slide_rings < 0 || o.feature_slide_rings > 64) throw bad("feature slide must be 0 to 64 one-ring steps");
  if (!(o.snap_radius >= 0.0) || !std::isfinite(o.snap_radius)) throw bad("snap radius must be 0 or positive");
  if (!(o.snap_remainder_share > 0.0 && o.snap_remainder_share <= 1.0)) throw bad("snap remainder share must be in (0, 1]");
  if (!(o.snap_regularisation > 0.0) || !std::isfinite(o.snap_regularisation))
    throw bad("snap regularisation must be positive");
}

double surface_voxel(const Garment& g, const SurfaceOptions& options) {
  if (options.voxel != 0.0) return options.voxel;
  // More agents than vertices adds no detail the reconstruction could show; it only slows the solve.
  return auto_voxel_size(g, std::min(options.agent_budget, std::max<std::size_t>(g.vertex_count(), 1000)));
}

// A voxel size far below the garment's detail makes billions of agents (--voxel
// 0.01 grew past 21 GB, issue 17): refused before anything is allocated.
double agents_for_voxel(const Garment& g, double h) {
  const auto [area, length] = surface_measure(g);
  return 1.5 * (area / (h * h) + length / h);
}

void check_agent_count(const Garment& g, double h, std::size_t max_agents) {
  const auto [area, length] = surface_measure(g);
  const Vec3 extent = (g.positions.colwise().maxCoeff() - g.positions.colwise().minCoeff()).transpose();
  check_agent_count(area, length, extent, h, max_agents);
}

void check_agent_count(double area, double length, const Vec3& extent, double h, std::size_t max_agents) {
  const double agents = 1.5 * (area / (h * h) + length / h);
  if (agents <= static_cast<double>(max_agents)) return;
  char text[320];
  std::snprintf(text, sizeof text,
                "surface: voxel size %.4g on a garment of %.4g x %.4g x %.4g would need about %.3g agents (at most %zu): "
                "use a voxel size of at least %.3g, or 0 (automatic)",
                h, extent.x(), extent.y(), extent.z(), agents, max_agents, auto_voxel_size(area, length, extent, max_agents));
  throw Error(text);
}

std::vector<std::uint32_t> surface_layers(const Garment& g, const SurfaceOptions& options, double voxel) {
  if (!options.layers) return {};
  return garment_layers(g, options.layer_min_area * voxel * voxel, options.layer_join * voxel);
}

double estimated_agent_count(const Garment& g, const SurfaceOptions& options) {
  if (options.voxel == 0.0) return static_cast<double>(std::min(options.agent_budget, std::max<std::size_t>(g.vertex_count(), 1000)));
  check_agent_count(g, options.voxel, options.max_agents);
  return agents_for_voxel(g, options.voxel);
}

std::vector<std::uint32_t> feature_layers(std::size_t nf, const SurfaceAttachment& at,
                                          const std::function<std::uint32_t(Index)>& vertex_layer) {
  std::vector<std::uint32_t> feature_layer(nf, 0);
  if (vertex_layer && !at.vertex.empty())
    for (std::size_t k = 0; k < nf; ++k) {
      const auto& w = at.weight[k];
      const int j = int(std::max_element(w.begin(), w.end()) - w.begin());
      feature_layer[k] = vertex_layer(at.vertex[k][j]);
    }
  return feature_layer;
}

std::vector<VoxelLayer> feature_skip(const VoxelGrid& grid, const Points& features,
                                     const std::vector<std::uint32_t>& feature_layer) {
  std::vector<VoxelLayer> skip(feature_layer.size());
  for (std::size_t k = 0; k < skip.size(); ++k)
    skip[k] = {VoxelGrid::morton(grid.cell(row3(features, Index(k)))), feature_layer[k]};
  std::sort(skip.begin(), skip.end());
  skip.erase(std::unique(skip.begin(), skip.end()), skip.end());
  return skip;
}

SurfaceBinding SurfaceBinding::bind(const Garment& g, const Points& features, const SurfaceOptions& options,
                                    const SurfaceAttachment* feature_attachment) {
  check_surface_options(options);
  check_finite(features, "feature sample");
  Stopwatch clock;

  // Everything here is bound on the ORIGINAL garment, not on the warped one as in
  // the paper: agents, rings and encoding then serve every body B, and the
  // encoding is the original local shape the step restores (DESIGN.md).
  SurfaceGarmentPart part;
  part.voxel_auto = options.voxel == 0.0;
  part.voxel = surface_voxel(g, options);
  check_agent_count(g, part.voxel, options.max_agents);
  part.grid = make_voxel_grid(g, features, part.voxel);
  part.vertex_count = g.vertex_count();
  const std::size_t nf = static_cast<std::size_t>(features.rows());
  // Feature samples move with the garment where they sit (when they have no
  // warped position) and belong to its layer there.
  SurfaceAttachment attachment;
  if (nf > 0 && part.vertex_count > 0) {
    if (feature_attachment && feature_attachment->vertex.size() != nf)
      throw Error("surface: the feature attachment has " + std::to_string(feature_attachment->vertex.size()) +
                  " samples, the features " + std::to_string(nf));
    attachment = feature_attachment ? *feature_attachment : attach_points(g, features);
  }
  const std::vector<std::uint32_t> vertex_layer = surface_layers(g, options, part.voxel);
  part.layers = vertex_layer.empty() ? 0 : *std::max_element(vertex_layer.begin(), vertex_layer.end());
  std::function<std::uint32_t(Index)> layer_of;
  if (!vertex_layer.empty()) layer_of = [&](Index v) { return vertex_layer[v]; };
  part.feature_layer = feature_layers(nf, attachment, layer_of);
  part.ms.sample = clock.ms();
  clock.reset();
  part.agents = select_agents(g, part.grid, feature_skip(part.grid, features, part.feature_layer), vertex_layer);
  part.agent_positions = part.agents.positions(g.positions);
  part.ms.agents = clock.ms();

  SurfaceBinding s = bind_agents(std::move(part), features, options, std::move(attachment));
  clock.reset();
  s.blends_ = s.vertex_blends(g.positions, vertex_layer);
  s.vertex_layer_ = vertex_layer;
  if (s.snaps()) s.snap_reach_ = s.snap_reach(g.positions, vertex_layer);
  s.stats_.vertices_capped = s.blends_.capped;
  s.stats_.vertices_without_agent = s.blends_.without_agent;
  if (options.feature_zone_rings > 0) {
    s.carries_feature_.assign(s.vertex_count_, 0);
    for (std::size_t k = 0; k < s.feature_attachment_.vertex.size(); ++k)
      for (int j = 0; j < 3; ++j)
        if (s.feature_attachment_.weight[k][j] != 0.0) s.carries_feature_[s.feature_attachment_.vertex[k][j]] = 1;
  }
  if (options.emit_from_original && !options.encode_on_warped) s.original_vertices_ = g.positions;
  s.stats_.ms.reconstruct = clock.ms();  // bind share of the reconstruction (vertex lists)
  return s;
}

SurfaceBinding SurfaceBinding::bind_agents(SurfaceGarmentPart part, const Points& features, const SurfaceOptions& options,
                                           SurfaceAttachment feature_attachment) {
  check_surface_options(options);
  check_finite(features, "feature sample");
  SurfaceBinding s;
  s.options_ = options;
  s.vertex_count_ = part.vertex_count;
  s.h_ = part.voxel;
  s.feature_attachment_ = std::move(feature_attachment);
  SurfaceStats& st = s.stats_;
  st.voxel_was_auto = part.voxel_auto;
  st.voxel = s.h_;
  st.ms.sample = part.ms.sample;
  Stopwatch clock;
  const std::size_t nf = static_cast<std::size_t>(features.rows());
  GarmentAgents& ga = part.agents;
  const std::size_t ng = ga.size(), n = ng + nf;
  st.samples = ga.samples;
  st.garment_agents = ng;
  st.feature_agents = nf;
  st.agents = n;
  Points natural(static_cast<Eigen::Index>(n), 3);
  if (ng > 0) natural.topRows(static_cast<Eigen::Index>(ng)) = part.agent_positions;
  if (nf > 0) natural.bottomRows(static_cast<Eigen::Index>(nf)) = features;
  std::vector<std::uint64_t> morton = ga.voxel;
  for (std::size_t k = 0; k < nf; ++k) morton.push_back(VoxelGrid::morton(part.grid.cell(row3(features, Index(k)))));
  std::vector<std::uint32_t> natural_layer = ga.layer;
  natural_layer.insert(natural_layer.end(), part.feature_layer.begin(), part.feature_layer.end());
  st.layers = part.layers;
  st.ms.agents = part.ms.agents + clock.ms();
  clock.reset();
  OrderedAgents ord =
      order_agents(natural, morton, natural_layer, options.ring_radius_voxels * s.h_, options.block_voxels * s.h_);
  const std::vector<Index>& order = ord.order;
  const double width = ord.width;
  s.ring_ = std::move(ord.ring);
  s.original_agents_.resize(static_cast<Eigen::Index>(n), 3);
  s.src_vertex_.resize(n);
  s.src_weight_.resize(n);
  s.feature_of_.assign(n, -1);
  s.feature_slot_.resize(nf);
  s.layer_.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Index old = order[k];
    s.original_agents_.row(static_cast<Eigen::Index>(k)) = natural.row(old);
    s.layer_[k] = natural_layer[old];
    if (old < ng) {
      s.src_vertex_[k] = ga.vertex[old];
      s.src_weight_[k] = ga.weight[old];
    } else {
      s.feature_of_[k] = static_cast<std::int32_t>(old - ng);
      s.feature_slot_[old - ng] = Index(k);
    }
  }
  order_rings(s.original_agents_, s.ring_, s.ring_open_);
  s.schedule_ = make_schedule(s.original_agents_, s.ring_, width);
  st.blocks = s.schedule_.blocks();
  st.sequential_agents = s.schedule_.sequential_agents.size();
  st.block_width = width;
  for (std::size_t a = 0; a < n; ++a) st.ring_degree_max = std::max(st.ring_degree_max, s.ring_.row_size(a));
  st.ring_degree_mean = n ? double(s.ring_.indices.size()) / double(n) : 0.0;
  // Normal orientation, bound on the original: a frame flipped in both states
  // re-emits the same point, so this only has to be consistent, not B-specific.
  if (!options.fit_rotations) s.flip_ = orient_normals(fan_normals(s.original_agents_, s.ring_, s.ring_open_), s.ring_);
  s.group_ = ring_groups(s.ring_);
  // The features' zone: agents within feature_zone_rings one-ring steps (either
  // direction) of a feature agent.
  if (options.feature_zone_rings > 0) {
    s.near_feature_.assign(n, 0);
    for (std::size_t a = 0; a < n; ++a) s.near_feature_[a] = s.feature_of_[a] >= 0;
    for (int k = 0; k < options.feature_zone_rings; ++k) {
      std::vector<std::uint8_t> grown = s.near_feature_;
      for (std::size_t a = 0; a < n; ++a)
        for (Index q : s.ring_.row(a))
          if (s.near_feature_[a] || s.near_feature_[q]) grown[a] = grown[q] = 1;
      if (grown == s.near_feature_) break;  // the zone covers the features' groups
      s.near_feature_ = std::move(grown);
    }
    st.feature_zone_agents = std::size_t(std::count(s.near_feature_.begin(), s.near_feature_.end(), 1));
  }
  s.groups_ = 0;
  for (std::size_t a = 0; a < n; ++a) s.groups_ += s.group_[a] == a;
  st.ms.one_ring = clock.ms();
  clock.reset();

  // Encoded on the original always (the rings are needed either way); with
  // encode_on_warped apply encodes again on the warped agents.
  s.rows_ = encode_agents(s.original_agents_, s.ring_);
  st.degenerate_rows = s.rows_.degenerate;
  st.ms.encode = clock.ms();
  clock.reset();

  s.levels_ = build_coarse_levels(s.original_agents_, s.layer_, s.feature_of_, s.h_, options.coarse_levels,
                                  options.coarse_min_agents, options.ring_radius_voxels, options.block_voxels);
  st.levels = 1 + int(s.levels_.size());
  st.ms.encode += clock.ms();
  clock.reset();

  return s;
}

}  // namespace refit
