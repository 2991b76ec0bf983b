#include <refit/attach/attachment.hpp>
#include <refit/body/centre_tree.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/progress.hpp>
#include <refit/surface/agents.hpp>
#include <refit/surface/feature_snap.hpp>
#include <refit/surface/surface.hpp>

#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <tuple>

namespace refit {

namespace {
constexpr std::size_t kGrain = 1024;

void check_finite(const Points& p, const std::string& what) {
  for (Eigen::Index i = 0; i < p.rows(); ++i)
    if (!p.row(i).allFinite()) throw Error("surface: " + what + " row " + std::to_string(i + 1) + " is not finite");
}

void check_options(const SurfaceOptions& o) {
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
  if (!(o.snap_regularisation > 0.0) || !std::isfinite(o.snap_regularisation))
    throw bad("snap regularisation must be positive");
}

// Connected groups of a one-ring graph: group[a] = the lowest agent of a's group.
std::vector<Index> ring_groups(const Csr& ring) {
  const std::size_t n = ring.rows();
  std::vector<Index> group(n);
  std::iota(group.begin(), group.end(), Index{0});
  auto root = [&](Index a) {
    while (group[a] != a) a = group[a] = group[group[a]];
    return a;
  };
  for (std::size_t a = 0; a < n; ++a)
    for (Index b : ring.row(a)) {
      const Index ra = root(Index(a)), rb = root(b);
      if (ra != rb) group[std::max(ra, rb)] = std::min(ra, rb);
    }
  for (std::size_t a = 0; a < n; ++a) group[a] = root(Index(a));
  return group;
}

// One-rings of `natural`, then the storage order block by block (blocks wider than
// the longest one-ring edge, so rings come first). Returns order (order[k] = the
// natural index stored at k), the ring in storage indices and the block width.
struct Ordered {
  std::vector<Index> order;
  Csr ring;
  double width = 0.0;
};
Ordered order_agents(const Points& natural, const std::vector<std::uint64_t>& morton, const std::vector<std::uint32_t>& layer,
                     double radius, double min_width) {
  Ordered o;
  const std::size_t n = static_cast<std::size_t>(natural.rows());
  const Csr ring0 = build_one_rings(natural, radius, layer);
  // Wider than the longest edge keeps same-colour blocks apart; a few voxels wide
  // gives each parallel task enough agents to pay for itself.
  o.width = std::max(longest_edge(natural, ring0) * (1.0 + 1e-6), min_width);
  o.order = make_block_order(natural, morton, o.width);
  std::vector<Index> slot_of(n);
  for (std::size_t k = 0; k < n; ++k) slot_of[o.order[k]] = Index(k);
  o.ring.offsets.reserve(n + 1);
  o.ring.indices.reserve(ring0.indices.size());
  for (std::size_t k = 0; k < n; ++k) {
    for (Index q : ring0.row(o.order[k])) o.ring.indices.push_back(slot_of[q]);
    o.ring.offsets.push_back(Index(o.ring.indices.size()));
  }
  return o;
}

// Per point of `fine`: its k nearest points of `coarse` of the same layer (see
// LayerTrees) with normalised inverse squared distance weights (a point on a
// coarse one gets all the weight).
void interpolation(const Points& fine, const std::vector<std::uint32_t>& fine_layer, const Points& coarse,
                   const std::vector<std::uint32_t>& coarse_layer, std::size_t k, double tiny, Csr& out,
                   std::vector<float>& weight) {
  const LayerTrees tree(coarse, coarse_layer);
  const std::size_t n = static_cast<std::size_t>(fine.rows());
  out.offsets.assign(n + 1, 0);
  std::vector<Index> cnt(n, 0);
  std::vector<std::array<Index, 8>> idx_all(n);
  std::vector<std::array<float, 8>> w_all(n);
  k = std::min<std::size_t>(k, 8);
  parallel_for(0, n, 1024, [&](std::size_t b, std::size_t e) {
    std::vector<Index> idx;
    std::vector<double> d2;
    for (std::size_t i = b; i < e; ++i) {
      tree.knn(fine_layer.empty() ? 0u : fine_layer[i], row3(fine, Index(i)), k, idx, d2);
      double sum = 0.0;
      std::array<double, 8> w{};
      for (std::size_t j = 0; j < idx.size(); ++j) sum += w[j] = 1.0 / (d2[j] + tiny);
      for (std::size_t j = 0; j < idx.size(); ++j) {
        idx_all[i][j] = idx[j];
        w_all[i][j] = static_cast<float>(w[j] / sum);
      }
      cnt[i] = Index(idx.size());
    }
  });
  for (std::size_t i = 0; i < n; ++i) out.offsets[i + 1] = out.offsets[i] + cnt[i];
  out.indices.resize(out.offsets[n]);
  weight.resize(out.offsets[n]);
  for (std::size_t i = 0; i < n; ++i)
    for (Index j = 0; j < cnt[i]; ++j) {
      out.indices[out.offsets[i] + j] = idx_all[i][j];
      weight[out.offsets[i] + j] = w_all[i][j];
    }
}

}  // namespace

double surface_voxel(const Garment& g, const SurfaceOptions& options) {
  if (options.voxel != 0.0) return options.voxel;
  // More agents than vertices adds no detail the reconstruction could show; it only slows the solve.
  return auto_voxel_size(g, std::min(options.agent_budget, std::max<std::size_t>(g.vertex_count(), 1000)));
}

std::vector<std::uint32_t> surface_layers(const Garment& g, const SurfaceOptions& options, double voxel) {
  if (!options.layers) return {};
  return garment_layers(g, options.layer_min_area * voxel * voxel, options.layer_join * voxel);
}

SurfaceBinding SurfaceBinding::bind(const Garment& g, const Points& features, const SurfaceOptions& options,
                                    const SurfaceAttachment* feature_attachment) {
  check_options(options);
  check_finite(features, "feature sample");
  SurfaceBinding s;
  s.options_ = options;
  s.vertex_count_ = g.vertex_count();
  SurfaceStats& st = s.stats_;
  Stopwatch clock;

  // Everything here is bound on the ORIGINAL garment, not on the warped one as in
  // the paper: agents, rings and encoding then serve every body B, and the
  // encoding is the original local shape the step restores (DESIGN.md).
  st.voxel_was_auto = options.voxel == 0.0;
  s.h_ = surface_voxel(g, options);
  st.voxel = s.h_;
  const VoxelGrid grid = make_voxel_grid(g, features, s.h_);
  const std::size_t nf = static_cast<std::size_t>(features.rows());
  const std::size_t nv = g.vertex_count();
  // Feature samples move with the garment where they sit (when they have no
  // warped position) and belong to its layer there.
  if (nf > 0 && nv > 0) {
    if (feature_attachment && feature_attachment->vertex.size() != nf)
      throw Error("surface: the feature attachment has " + std::to_string(feature_attachment->vertex.size()) +
                  " samples, the features " + std::to_string(nf));
    s.feature_attachment_ = feature_attachment ? *feature_attachment : attach_points(g, features);
  }
  const std::vector<std::uint32_t> vertex_layer = surface_layers(g, options, s.h_);
  std::vector<std::uint32_t> feature_layer(nf, 0);
  if (!vertex_layer.empty() && !s.feature_attachment_.vertex.empty())
    for (std::size_t k = 0; k < nf; ++k) {
      const auto& w = s.feature_attachment_.weight[k];
      const int j = int(std::max_element(w.begin(), w.end()) - w.begin());
      feature_layer[k] = vertex_layer[s.feature_attachment_.vertex[k][j]];
    }
  std::vector<std::uint64_t> feature_voxel(nf);
  std::vector<VoxelLayer> skip(nf);
  for (std::size_t k = 0; k < nf; ++k) {
    feature_voxel[k] = VoxelGrid::morton(grid.cell(row3(features, Index(k))));
    skip[k] = {feature_voxel[k], feature_layer[k]};
  }
  std::sort(skip.begin(), skip.end());
  skip.erase(std::unique(skip.begin(), skip.end()), skip.end());
  st.ms.sample = clock.ms();
  clock.reset();

  GarmentAgents ga = select_agents(g, grid, skip, vertex_layer);
  const std::size_t ng = ga.size(), n = ng + nf;
  st.samples = ga.samples;
  st.garment_agents = ng;
  st.feature_agents = nf;
  st.agents = n;
  Points natural(static_cast<Eigen::Index>(n), 3);
  if (ng > 0) natural.topRows(static_cast<Eigen::Index>(ng)) = ga.positions(g.positions);
  if (nf > 0) natural.bottomRows(static_cast<Eigen::Index>(nf)) = features;
  std::vector<std::uint64_t> morton = ga.voxel;
  morton.insert(morton.end(), feature_voxel.begin(), feature_voxel.end());
  std::vector<std::uint32_t> natural_layer = ga.layer;
  natural_layer.insert(natural_layer.end(), feature_layer.begin(), feature_layer.end());
  st.layers = vertex_layer.empty() ? 0 : *std::max_element(vertex_layer.begin(), vertex_layer.end());
  st.ms.agents = clock.ms();
  clock.reset();

  Ordered ord = order_agents(natural, morton, natural_layer, options.ring_radius_voxels * s.h_, options.block_voxels * s.h_);
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

  // Coarse levels: subsets of the agents, so the body distances, feature targets
  // and rotations of the fine agents serve them too (no garment resampling).
  std::vector<Index> finer_agents(n);
  std::iota(finer_agents.begin(), finer_agents.end(), Index{0});
  for (int l = 1; l <= options.coarse_levels && finer_agents.size() / 4 >= options.coarse_min_agents; ++l) {
    const double hl = s.h_ * std::ldexp(1.0, l);
    const std::size_t nfin = finer_agents.size();
    Points pf(static_cast<Eigen::Index>(nfin), 3);
    for (std::size_t k = 0; k < nfin; ++k) pf.row(Eigen::Index(k)) = s.original_agents_.row(finer_agents[k]);
    VoxelGrid cg;
    cg.h = hl;
    cg.origin = pf.colwise().minCoeff().transpose();
    struct Key {
      std::uint64_t voxel;
      std::uint32_t layer;
      int garment;  // 0: feature agent (always kept)
      double d2;
      Index k;
      bool operator<(const Key& o) const {
        return std::tie(voxel, layer, garment, d2, k) < std::tie(o.voxel, o.layer, o.garment, o.d2, o.k);
      }
    };
    std::vector<Key> keys(nfin);
    std::vector<std::uint32_t> finer_layer(nfin);
    for (std::size_t k = 0; k < nfin; ++k) {
      const Vec3 p = row3(pf, Index(k));
      const auto c = cg.cell(p);
      finer_layer[k] = s.layer_[finer_agents[k]];
      keys[k] = Key{VoxelGrid::morton(c), finer_layer[k], s.feature_of_[finer_agents[k]] >= 0 ? 0 : 1,
                    (p - cg.centre(c)).squaredNorm(), Index(k)};
    }
    std::sort(keys.begin(), keys.end());
    std::vector<Index> kept;  // indices into finer_agents
    std::vector<std::uint64_t> kept_voxel;
    std::vector<std::uint32_t> kept_layer;
    for (std::size_t i = 0; i < nfin; ++i) {
      const bool first = i == 0 || keys[i].voxel != keys[i - 1].voxel || keys[i].layer != keys[i - 1].layer;
      if (keys[i].garment == 0 || (first)) {
        kept.push_back(keys[i].k);
        kept_voxel.push_back(keys[i].voxel);
        kept_layer.push_back(keys[i].layer);
      }
    }
    if (kept.size() * 4 > nfin * 3) break;  // hardly coarser: no use
    Points natural_l(static_cast<Eigen::Index>(kept.size()), 3);
    for (std::size_t i = 0; i < kept.size(); ++i) natural_l.row(Eigen::Index(i)) = pf.row(kept[i]);
    Ordered ol = order_agents(natural_l, kept_voxel, kept_layer, options.ring_radius_voxels * hl, options.block_voxels * hl);
    Level lv;
    lv.agent.resize(kept.size());
    Points pos(static_cast<Eigen::Index>(kept.size()), 3);
    std::vector<std::uint32_t> pos_layer(kept.size());
    for (std::size_t i = 0; i < kept.size(); ++i) {
      lv.agent[i] = finer_agents[kept[ol.order[i]]];
      pos.row(Eigen::Index(i)) = natural_l.row(ol.order[i]);
      pos_layer[i] = kept_layer[ol.order[i]];
    }
    lv.rows = encode_agents(pos, ol.ring);
    lv.ring = lv.rows.ring;
    lv.schedule = make_schedule(pos, lv.ring, ol.width);
    lv.group = ring_groups(lv.ring);
    interpolation(pf, finer_layer, pos, pos_layer, 4, 1e-12 * hl * hl, lv.up, lv.up_weight);
    finer_agents = lv.agent;
    s.levels_.push_back(std::move(lv));
  }
  st.levels = 1 + int(s.levels_.size());
  st.ms.encode += clock.ms();
  clock.reset();

  // Each vertex's nearest agents within reach (a bounded k-nearest query), and the
  // nearest agent (for vertices with none).
  const std::size_t kmax = options.max_reach_agents;
  s.nearest_.assign(nv, 0);
  if (n > 0) {
    // A vertex of a layer blends its own layer's agents only.
    const LayerTrees tree(s.original_agents_, s.layer_);
    const double reach2 = std::pow(options.reach_voxels * s.h_, 2);
    std::vector<std::uint8_t> capped(nv, 0);
    std::vector<std::uint8_t> count(nv, 0);
    UninitVector<Index> idx_all(nv * kmax);  // slots past a vertex's count stay unset and unread
    UninitVector<float> w_all(options.smooth_blend ? nv * kmax : 0);
    parallel_for(0, nv, 2048, [&](std::size_t b, std::size_t e) {
      std::vector<Index> idx;
      std::vector<double> d2;
      for (std::size_t v = b; v < e; ++v) {
        const Vec3 p = row3(g.positions, Index(v));
        tree.knn(vertex_layer.empty() ? 0u : vertex_layer[v], p, kmax + 1, idx, d2);
        std::size_t m = 0;
        while (m < idx.size() && m < kmax && d2[m] < reach2) ++m;
        capped[v] = m == kmax && idx.size() > m && d2[m] < reach2;
        s.nearest_[v] = idx.empty() ? 0 : idx.front();
        count[v] = static_cast<std::uint8_t>(m);
        std::copy(idx.begin(), idx.begin() + std::ptrdiff_t(m), idx_all.begin() + std::ptrdiff_t(v * kmax));
        if (options.smooth_blend && m > 0) {
          // Beyond the paper: eq. 4's 1/|local|^3 interpolates each agent (flat
          // spots at the agents, steep changes between them: the neighbours' small
          // differences in motion show as ripples at the agent spacing). A smooth
          // kernel (1 - d^2/R^2)^2 whose radius R is the distance to the first agent
          // left out (or the reach) varies smoothly with the vertex, so the blend is
          // smooth. Bound on the original: every body B blends alike.
          const double r2 = m < idx.size() ? std::min(d2[m], reach2) : reach2;
          double sum = 0.0;
          std::array<double, 256> w{};
          for (std::size_t j = 0; j < m; ++j) {
            const double t = std::max(0.0, 1.0 - d2[j] / r2);
            sum += w[j] = t * t;
          }
          if (!(sum > 1e-12)) {
            w.fill(0.0);
            w[0] = sum = 1.0;
          }
          for (std::size_t j = 0; j < m; ++j) w_all[v * kmax + j] = static_cast<float>(w[j] / sum);
        }
      }
    });
    s.reach_.offsets.assign(nv + 1, 0);
    for (std::size_t v = 0; v < nv; ++v) s.reach_.offsets[v + 1] = s.reach_.offsets[v] + count[v];
    s.reach_.indices.resize(s.reach_.offsets[nv]);
    if (options.smooth_blend) s.reach_weight_.resize(s.reach_.offsets[nv]);
    parallel_for(0, nv, 8192, [&](std::size_t b, std::size_t e) {
      for (std::size_t v = b; v < e; ++v)
        for (std::size_t j = 0; j < count[v]; ++j) {
          s.reach_.indices[s.reach_.offsets[v] + j] = idx_all[v * kmax + j];
          if (options.smooth_blend) s.reach_weight_[s.reach_.offsets[v] + j] = w_all[v * kmax + j];
        }
    });
    st.vertices_capped = std::accumulate(capped.begin(), capped.end(), std::size_t{0});
    for (std::size_t v = 0; v < nv; ++v) st.vertices_without_agent += count[v] == 0;
  } else {
    s.reach_.offsets.assign(nv + 1, 0);
  }
  if (options.feature_zone_rings > 0) {
    s.carries_feature_.assign(nv, 0);
    for (std::size_t k = 0; k < s.feature_attachment_.vertex.size(); ++k)
      for (int j = 0; j < 3; ++j)
        if (s.feature_attachment_.weight[k][j] != 0.0) s.carries_feature_[s.feature_attachment_.vertex[k][j]] = 1;
  }
  if (options.emit_from_original && !options.encode_on_warped) s.original_vertices_ = g.positions;
  st.ms.reconstruct = clock.ms();  // bind share of the reconstruction (vertex lists)
  return s;
}

Points SurfaceBinding::agent_positions(const Points& x, const Points* fp) const {
  const std::size_t n = agent_count();
  Points out(static_cast<Eigen::Index>(n), 3);
  parallel_for(0, n, kGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      Vec3 p = Vec3::Zero();
      const std::int32_t k = feature_of_[a];
      if (k < 0) {
        for (int j = 0; j < 3; ++j) p += src_weight_[a][j] * row3(x, src_vertex_[a][j]);
      } else if (fp) {
        p = row3(*fp, Index(k));
      } else if (!feature_attachment_.vertex.empty()) {
        p = carry_one(feature_attachment_, x, k);
      } else {
        p = row3(original_agents_, Index(a));  // no garment vertex at all: nothing moved
      }
      out.row(static_cast<Eigen::Index>(a)) = p.transpose();
    }
  });
  return out;
}

namespace {

using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// Eq. 13's matrix on the free agents (rows and columns of fixed agents empty:
// their correction is zero).
RowMatrix free_matrix(const AgentRows& rows, const std::vector<std::uint8_t>& free) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(rows.ring.indices.size() + rows.size());
  for (std::size_t a = 0; a < rows.size(); ++a) {
    if (!free[a]) continue;
    t.emplace_back(Eigen::Index(a), Eigen::Index(a), rows.diag[a]);
    auto r = rows.ring.row(a);
    for (std::size_t i = 0; i < r.size(); ++i)
      if (free[r[i]]) t.emplace_back(Eigen::Index(a), Eigen::Index(r[i]), -rows.weight[rows.ring.offsets[a] + i]);
  }
  RowMatrix m(Eigen::Index(rows.size()), Eigen::Index(rows.size()));
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

// A sparse matrix back in row form (diagonal, neighbours, weights = minus the
// off-diagonal entries); free where the diagonal is positive.
AgentRows matrix_rows(const RowMatrix& m, std::vector<std::uint8_t>& free) {
  AgentRows rows;
  const std::size_t n = std::size_t(m.rows());
  rows.diag.assign(n, 0.0);
  free.assign(n, 0);
  rows.ring.offsets.reserve(n + 1);
  for (std::size_t a = 0; a < n; ++a) {
    for (RowMatrix::InnerIterator it(m, Eigen::Index(a)); it; ++it) {
      if (std::size_t(it.col()) == a) {
        rows.diag[a] = it.value();
      } else if (it.value() != 0.0) {
        rows.ring.indices.push_back(Index(it.col()));
        rows.weight.push_back(-it.value());
      }
    }
    rows.ring.offsets.push_back(Index(rows.ring.indices.size()));
    free[a] = rows.diag[a] > 0.0;
  }
  rows.h = Points::Zero(Eigen::Index(n), 3);
  return rows;
}

}  // namespace

SolveReport SurfaceBinding::solve_multigrid(const AgentRows& rows, const Points& h, const std::vector<std::uint8_t>& free,
                                            Points& x, const SolveOptions& solve, bool krylov,
                                            int* krylov_iterations) const {
  // Beyond the paper: V-cycles. Gauss-Seidel removes the error at the agent
  // spacing in a few sweeps but its smooth part only over thousands (the 40k
  // demo dress needed 7,600 sweeps to reach the 1e-5 update); the coarser agent
  // subsets remove that part. Their operators are Galerkin products P^T A P of
  // this body's free system (P: the levels' interpolation), so the coarse
  // correction has the right scale whatever eq. 13's weights do across scales
  // (the levels' own encodings over-correct by 2-4x and diverge). The fixed
  // point is the same; the stopping rule is the paper's, on the fine sweeps.
  struct Galerkin {
    RowMatrix p;  // finer level's agents x this level's
    AgentRows rows;
    std::vector<std::uint8_t> free;
    BlockSchedule schedule;
  };
  std::vector<Galerkin> g(levels_.size());
  RowMatrix a = free_matrix(rows, free);
  const std::vector<std::uint8_t>* finer_free = &free;
  for (std::size_t l = 0; l < levels_.size(); ++l) {
    const Level& lv = levels_[l];
    // Aggregation: each agent of the finer level belongs to its nearest agent of
    // this level (P has one 1 per row). P^T A P of eq. 13's M-matrix (weights
    // lambda (1 - cos theta) >= 0, diagonal their sum) is again weakly diagonally
    // dominant with non-negative weights, so Gauss-Seidel is as safe on it as on
    // the fine rows; the levels' smooth 4-agent interpolation gives coarse rows
    // far from dominant (measured: off-diagonal up to 27x the diagonal) on which
    // the sweeps diverge.
    std::vector<Eigen::Triplet<double>> t;
    for (std::size_t r = 0; r < lv.up.rows(); ++r) {
      if (!(*finer_free)[r]) continue;
      auto up = lv.up.row(r);
      if (!up.empty()) t.emplace_back(Eigen::Index(r), Eigen::Index(up[0]), 1.0);
    }
    g[l].p.resize(Eigen::Index(lv.up.rows()), Eigen::Index(lv.agent.size()));
    g[l].p.setFromTriplets(t.begin(), t.end());
    const RowMatrix pt = g[l].p.transpose();
    RowMatrix coarse = pt * a * g[l].p;
    coarse.prune(0.0);
    g[l].rows = matrix_rows(coarse, g[l].free);
    // The level's storage order is blocked for its own rings; the wider Galerkin
    // stencil only adds agents swept alone (make_schedule finds them).
    Points pos(Eigen::Index(lv.agent.size()), 3);
    for (std::size_t i = 0; i < lv.agent.size(); ++i) pos.row(Eigen::Index(i)) = original_agents_.row(lv.agent[i]);
    g[l].schedule = make_schedule(pos, g[l].rows.ring, lv.schedule.block_width);
    a = std::move(coarse);
    finer_free = &g[l].free;
  }

  const int nu = std::max(1, options_.multigrid_sweeps);
  const SolveOptions smooth{nu, 0.0, options_.relaxation};
  // Correction on the level finer than l for its residual r.
  std::function<Points(std::size_t, const Points&)> correction = [&](std::size_t l, const Points& r) -> Points {
    const Galerkin& gl = g[l];
    const Points rc = gl.p.transpose() * r;
    Points e = Points::Zero(rc.rows(), 3);
    if (l + 1 == g.size()) {
      gauss_seidel(gl.rows, rc, gl.schedule, gl.free, e, {options_.coarsest_sweeps, 0.0, options_.relaxation});
    } else {
      gauss_seidel(gl.rows, rc, gl.schedule, gl.free, e, smooth);
      e += options_.multigrid_overcorrection * correction(l + 1, row_residual(gl.rows, rc, gl.free, e));
      gauss_seidel(gl.rows, rc, gl.schedule, gl.free, e, smooth);
    }
    return gl.p * e;
  };
  // BiCGSTAB (right-preconditioned, van der Vorst) on the free rows, each
  // coordinate with its own scalars but one shared sweep: Eigen's BiCGSTAB takes
  // one vector, and three separate solves would read the rows three times.
  // Measured (bench/README.md): the bare V-cycles reduce the residual by 0.80 per
  // cycle at 10k agents and 0.97 at 95k, even with an exact coarsest solve and
  // W-cycles (0.93-0.95): a few slow modes spread over large free regions (the
  // bodice between clearance-held and feature agents). A Krylov method removes
  // such isolated modes in a few iterations; the V-cycle removes the rest.
  auto krylov_solve = [&]() -> SolveReport {
    using Col = Eigen::Array<double, 1, 3>;
    const int kn = options_.krylov_cycle_sweeps;
    const SolveOptions cycle_sweeps{kn, 0.0, options_.relaxation};
    SolveReport rep;
    const Points zero = Points::Zero(x.rows(), 3);
    auto dot = [](const Points& a, const Points& b) -> Col { return (a.array() * b.array()).colwise().sum(); };
    auto ratio = [](const Col& num, const Col& den) -> Col { return (den != 0.0).select(num / den, 0.0); };
    // One V-cycle from zero for A e = r: a fixed linear map, as BiCGSTAB needs.
    auto precondition = [&](const Points& r) -> Points {
      Points e = Points::Zero(r.rows(), 3);
      gauss_seidel(rows, r, schedule_, free, e, cycle_sweeps);
      if (!g.empty()) e += options_.multigrid_overcorrection * correction(0, row_residual(rows, r, free, e));
      gauss_seidel(rows, r, schedule_, free, e, cycle_sweeps);
      rep.iterations += 2 * kn;
      return e;
    };
    auto product = [&](const Points& v) -> Points { return -row_residual(rows, zero, free, v); };
    // The update a Jacobi sweep would make: the sweeps' own measure of the residual.
    auto jacobi_update = [&](const Points& r) {
      double t = 0.0;
      for (std::size_t a = 0; a < rows.size(); ++a)
        if (free[a]) t += r.row(Eigen::Index(a)).squaredNorm() / (rows.diag[a] * rows.diag[a]);
      return std::sqrt(t);
    };
    bool krylov = true;
    while (rep.iterations < solve.max_iterations) {
      if (krylov) {
        // A (re)start: BiCGSTAB until the residual's Jacobi update is below the
        // tolerance, the budget is spent, or it breaks down (then plain sweeps).
        Points r = row_residual(rows, h, free, x), rhat = r, p = zero, v = zero;
        Col rho_old = Col::Ones(), alpha = Col::Ones(), omega = Col::Ones();
        const Points x_start = x;
        const double r_start = r.norm();
        int its = 0;
        while (rep.iterations < solve.max_iterations && jacobi_update(r) >= solve.tolerance) {
          const Col rho = dot(rhat, r);
          const Col beta = ratio(rho, rho_old) * ratio(alpha, omega);
          rho_old = rho;
          for (int c = 0; c < 3; ++c) p.col(c) = r.col(c) + beta[c] * (p.col(c) - omega[c] * v.col(c));
          const Points ph = precondition(p);
          v = product(ph);
          alpha = ratio(rho, dot(rhat, v));
          Points s = r;
          for (int c = 0; c < 3; ++c) s.col(c) -= alpha[c] * v.col(c);
          const Points sh = precondition(s);
          const Points t = product(sh);
          omega = ratio(dot(t, s), dot(t, t));
          for (int c = 0; c < 3; ++c) {
            x.col(c) += alpha[c] * ph.col(c) + omega[c] * sh.col(c);
            r.col(c) = s.col(c) - omega[c] * t.col(c);
          }
          if (krylov_iterations) ++*krylov_iterations;
          rep.reduction = std::pow(r.norm() / r_start, 1.0 / ++its);
          if (!x.allFinite() || !r.allFinite()) {
            x = x_start;
            krylov = false;
            break;
          }
          // A breakdown (rho or omega zero while that coordinate still has a
          // residual) makes no further progress: restart. A coordinate already
          // solved has zero scalars (ratio) and stays put.
          const Col unsolved = dot(r, r);
          if (((rho == 0.0 || omega == 0.0) && unsolved > 0.0).any()) break;
        }
      }
      // The paper's stopping rule, on real sweeps: the result is only called
      // converged when a fine sweep's update is below the tolerance.
      const int left = solve.max_iterations - rep.iterations;
      if (left <= 0) break;
      const SolveReport r1 =
          gauss_seidel(rows, h, schedule_, free, x, {krylov ? std::min(left, 2) : left, solve.tolerance, solve.relaxation});
      rep.iterations += r1.iterations;
      rep.final_update = r1.final_update;
      if (r1.converged || !krylov) break;
    }
    rep.converged = rep.final_update < solve.tolerance && rep.iterations > 0;
    return rep;
  };

  if (krylov) return krylov_solve();

  SolveReport rep;
  bool cycles = true;
  double last_residual = std::numeric_limits<double>::infinity();
  Points x_before;  // the state before the last correction
  while (rep.iterations < solve.max_iterations) {
    SolveOptions pre = smooth;
    pre.max_iterations = std::min(nu, solve.max_iterations - rep.iterations);
    if (!cycles) pre = {solve.max_iterations - rep.iterations, solve.tolerance, solve.relaxation};
    const SolveReport r1 = gauss_seidel(rows, h, schedule_, free, x, pre);
    rep.iterations += r1.iterations;
    rep.final_update = r1.final_update;
    if (r1.final_update < solve.tolerance || rep.iterations >= solve.max_iterations || !cycles) break;
    const Points r = row_residual(rows, h, free, x);
    // Safety net: a cycle that did not reduce the residual is undone and ends the
    // cycles; plain sweeps (the paper's solver) finish the job.
    const double norm = r.norm();
    if (!(norm < last_residual)) {
      x = x_before;
      cycles = false;
      continue;
    }
    if (std::isfinite(last_residual)) rep.reduction = norm / last_residual;
    last_residual = norm;
    x_before = x;
    x += options_.multigrid_overcorrection * correction(0, r);
  }
  rep.converged = rep.final_update < solve.tolerance;
  return rep;
}

SolveReport SurfaceBinding::solve(const Points& h, const std::vector<std::uint8_t>& free, Points& x,
                                  const SolveOptions& o, FineSolver solver, int* krylov_iterations) const {
  if (h.rows() != x.rows() || std::size_t(x.rows()) != agent_count() || free.size() != agent_count())
    throw Error("surface: solve needs one row of h, x and free per agent");
  if (levels_.empty() || solver == FineSolver::sweeps) return gauss_seidel(rows_, h, schedule_, free, x, o);
  return solve_multigrid(rows_, h, free, x, o, solver == FineSolver::krylov, krylov_iterations);
}

SurfaceResult SurfaceBinding::apply(const Points& warped, const Points& targets,
                                    const std::function<double(const Vec3&)>& distance, const Points* fwarped,
                                    SurfaceSystem* system) const {
  const std::size_t n = agent_count(), nf = feature_count();
  if (static_cast<std::size_t>(warped.rows()) != vertex_count_)
    throw Error("surface: the warped garment has " + std::to_string(warped.rows()) + " vertices, the binding expects " +
                std::to_string(vertex_count_));
  if (static_cast<std::size_t>(targets.rows()) != nf)
    throw Error("surface: " + std::to_string(targets.rows()) + " feature targets given, the binding has " +
                std::to_string(nf) + " feature samples");
  if (fwarped && static_cast<std::size_t>(fwarped->rows()) != nf)
    throw Error("surface: " + std::to_string(fwarped->rows()) + " warped feature samples given, the binding has " +
                std::to_string(nf));
  check_finite(warped, "warped vertex");
  check_finite(targets, "feature target");
  if (fwarped) check_finite(*fwarped, "warped feature sample");

  SurfaceResult res;
  res.stats = stats_;
  SurfaceStats& st = res.stats;
  st.ms.encode = 0.0;
  Stopwatch clock;
  const Points before = agent_positions(warped, fwarped);

  // Constraints: eq. 15 for feature agents, eq. 14 within epsilon of body B
  // (or inside it: the distance is signed) except in the features' zone (see
  // SurfaceOptions::feature_zone_rings). fixed: 2 feature, 1 body, 3 clearance.
  std::vector<std::uint8_t> fixed(n, 0);
  std::vector<double> body_distance(n, 0.0);
  parallel_for(0, n, 256, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      if (feature_of_[a] >= 0) {
        fixed[a] = 2;
      } else {
        body_distance[a] = distance(row3(before, Index(a)));
        if (body_distance[a] < options_.epsilon && (near_feature_.empty() || !near_feature_[a])) fixed[a] = 1;
      }
    }
  });
  for (std::size_t a = 0; a < n; ++a) {
    st.fixed_feature += fixed[a] == 2;
    st.fixed_body += fixed[a] == 1;
  }
  // The start: warped positions, feature agents at their targets.
  Points target_of = before;
  for (std::size_t k = 0; k < nf; ++k) target_of.row(feature_slot_[k]) = targets.row(Eigen::Index(k));

  // The encoding: on the original; with encode_on_warped on the warped agents
  // (the paper). rotate_encoding turns each h by the agent's ring rotation from
  // the original to the warp (h is a vector in the original's orientation). Off
  // by default: measured on the 6k dress, per-agent rotations are not consistent
  // with each other, the turned h no longer integrate, and the held-out slices
  // got worse (1.4x and 0.7x instead of 3.9x and 3.0x), manifold and soup
  // results 0.89 cm apart instead of 0.16 cm.
  AgentRows warped_rows;
  std::vector<Eigen::Matrix3d> turn;
  if (options_.encode_on_warped) {
    warped_rows = encode_agents(before, ring_);
    st.degenerate_rows = warped_rows.degenerate;
  } else if (options_.rotate_encoding) {
    turn = ring_rotations(original_agents_, before, ring_);
  }
  const AgentRows& rows = options_.encode_on_warped ? warped_rows : rows_;
  auto turned_h = [&](const AgentRows& r, const std::vector<Index>* agent) {
    Points h = r.h;
    if (!turn.empty())
      parallel_for(0, r.size(), kGrain, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
          const Index a = agent ? (*agent)[i] : Index(i);
          h.row(Eigen::Index(i)) = (turn[a] * row3(r.h, Index(i))).transpose();
        }
      });
    return h;
  };
  st.ms.encode = clock.ms();
  clock.reset();

  // Free agents of a level: not fixed, and in a group (of the level's one-ring
  // graph) with a fixed agent; a group with none has no unique solution: it is
  // anchored where the warp put it.
  auto free_agents = [&](const AgentRows& r, const std::vector<Index>& group, const std::vector<Index>* agent,
                         std::size_t* anchored, std::size_t* anchored_groups) {
    const std::size_t m = r.size();
    std::vector<std::uint8_t> group_fixed(m, 0), out(m, 0);
    for (std::size_t i = 0; i < m; ++i)
      if (fixed[agent ? (*agent)[i] : i]) group_fixed[group[i]] = 1;
    for (std::size_t i = 0; i < m; ++i) {
      if (fixed[agent ? (*agent)[i] : i]) continue;
      if (!group_fixed[group[i]]) {
        if (anchored) ++*anchored;
        if (anchored_groups && group[i] == i) ++*anchored_groups;
      } else {
        out[i] = r.diag[i] > 0.0;
      }
    }
    return out;
  };
  const SolveOptions solve{options_.max_iterations, options_.tolerance, options_.relaxation};

  // Coarse to fine: solve the coarsest subset from the warp, then start each finer
  // level from the coarser solution's displacement, interpolated.
  Points x_coarse;  // solution of the level below the current one (its own order)
  for (std::size_t l = levels_.size(); l-- > 0;) {
    const Level& lv = levels_[l];
    const std::size_t m = lv.agent.size();
    Points x(static_cast<Eigen::Index>(m), 3);
    Points b_l(static_cast<Eigen::Index>(m), 3);
    for (std::size_t i = 0; i < m; ++i) b_l.row(Eigen::Index(i)) = before.row(lv.agent[i]);
    if (l + 1 == levels_.size()) {
      x = b_l;
    } else {
      const Level& below = levels_[l + 1];
      for (std::size_t i = 0; i < m; ++i) {
        Vec3 d = Vec3::Zero();
        auto r = below.up.row(i);
        for (std::size_t j = 0; j < r.size(); ++j)
          d += double(below.up_weight[below.up.offsets[i] + j]) *
               (row3(x_coarse, r[j]) - row3(before, below.agent[r[j]]));
        x.row(Eigen::Index(i)) = (row3(b_l, Index(i)) + d).transpose();
      }
    }
    for (std::size_t i = 0; i < m; ++i)
      if (fixed[lv.agent[i]]) x.row(Eigen::Index(i)) = target_of.row(lv.agent[i]);
    const std::vector<std::uint8_t> fr = free_agents(lv.rows, lv.group, &lv.agent, nullptr, nullptr);
    AgentRows warped_level;
    if (options_.encode_on_warped) warped_level = encode_agents(b_l, lv.ring);
    const AgentRows& r = options_.encode_on_warped ? warped_level : lv.rows;
    // With multigrid the start only has to be smooth: measured on the 1M dress
    // at 910k agents, 500 sweeps per start level (2,000 in all, mostly on the
    // 241k-agent level: 3-5 s) and 30 per level gave 199 and 180 fine sweeps.
    SolveOptions start = solve;
    if (options_.multigrid) start.max_iterations = std::min(start.max_iterations, options_.coarse_start_sweeps);
    const SolveReport rep = gauss_seidel(r, turned_h(r, &lv.agent), lv.schedule, fr, x, start);
    st.coarse_iterations += rep.iterations;
    x_coarse = std::move(x);
  }

  std::vector<std::uint8_t> fr = free_agents(rows, group_, nullptr, &st.anchored, &st.anchored_groups);
  Points x = before;
  if (!levels_.empty()) {
    const Level& below = levels_.front();
    parallel_for(0, n, kGrain, [&](std::size_t b, std::size_t e) {
      for (std::size_t a = b; a < e; ++a) {
        if (!fr[a]) continue;
        Vec3 d = Vec3::Zero();
        auto r = below.up.row(a);
        for (std::size_t j = 0; j < r.size(); ++j)
          d += double(below.up_weight[below.up.offsets[a] + j]) * (row3(x_coarse, r[j]) - row3(before, below.agent[r[j]]));
        x.row(Eigen::Index(a)) += d.transpose();
      }
    });
  }
  for (std::size_t k = 0; k < nf; ++k) x.row(feature_slot_[k]) = targets.row(Eigen::Index(k));
  const Points h_fine = turned_h(rows, nullptr);
  const Points x_start = system ? x : Points();
  // `loosen`: a factor on the tolerance (see the first solve below).
  auto solve_fine = [&](double loosen) {
    SolveOptions o = solve;
    if (options_.tolerance_rms > 0.0) {
      // RMS over the free agents: the same L2 rule with the tolerance scaled by sqrt(free count).
      const auto m = std::count(fr.begin(), fr.end(), std::uint8_t{1});
      o.tolerance = options_.tolerance_rms * std::sqrt(double(std::max<std::ptrdiff_t>(m, 1)));
    }
    st.tolerance = o.tolerance;
    o.tolerance *= loosen;
    const SolveReport rep = levels_.empty() || !options_.multigrid
                                ? gauss_seidel(rows, h_fine, schedule_, fr, x, o)
                                : solve_multigrid(rows, h_fine, fr, x, o, options_.krylov, &st.krylov_iterations);
    st.iterations += rep.iterations;
    st.final_update = rep.final_update;
    st.reduction = rep.reduction;
    st.converged = rep.converged || n == 0;
  };
  // Beyond the paper: eq. 14 holds only the agents the warp put within epsilon
  // of body B. A free region a little farther out (a bodice with 1.5 cm of ease
  // over a bigger bust, a skirt over bigger hips) returns to its original shape
  // and sinks into body B, and the collision step can only push vertices out
  // afterwards. So each free agent the solve leaves closer than the clearance
  // (or inside) is held at the nearest point that clears the body by it, and
  // the system is solved again from there (an active set, usually one round):
  // the rest of the surface bends around the contact by eq. 13 instead of by a
  // later smoothing. Measured on the 6k test dress (SurfaceDress tests): 92
  // vertices inside body B before collision -> 15, collision moves 179 vertices
  // instead of 470, the held-out slices 4.2x/3.6x -> 4.2x/3.2x after collision;
  // on the procedural 4M dress 323k vertices inside -> 0. Holding them at their
  // warped positions instead keeps only 1.9x/1.6x (the warp's bumps come back
  // around every held agent).
  // The nearest point at the clearance: Newton steps along the distance's
  // gradient (central differences); where that fails (an edge of the bounded
  // distance), the point on the way back to the warped position w.
  const double step = 1e-3 * h_;
  auto clear_point = [&](Vec3 p, const Vec3& w) -> Vec3 {
    const double c = options_.clearance;
    for (int k = 0; k < 4; ++k) {
      const double d = distance(p);
      if (d >= c && d < c + 1e-3 * step) return p;
      Vec3 g;
      for (int i = 0; i < 3; ++i) {
        Vec3 e = Vec3::Zero();
        e[i] = step;
        g[i] = (distance(p + e) - distance(p - e)) / (2.0 * step);
      }
      if (!(g.squaredNorm() > 0.25)) break;
      p += ((c - d) / g.squaredNorm()) * g;
    }
    if (distance(p) >= c) return p;
    double lo = 0.0, hi = 1.0;
    for (int k = 0; k < 16; ++k) {
      const double mid = 0.5 * (lo + hi);
      (distance(p + mid * (w - p)) >= c ? hi : lo) = mid;
    }
    return p + hi * (w - p);
  };
  auto hold_clear = [&] {
    std::vector<std::uint8_t> pin(n, 0);
    parallel_for(0, n, 256, [&](std::size_t b, std::size_t e) {
      for (std::size_t a = b; a < e; ++a) {
        if (!fr[a]) continue;
        const Vec3 p = row3(x, Index(a));
        if (distance(p) >= options_.clearance) continue;
        pin[a] = 1;
        x.row(Eigen::Index(a)) = clear_point(p, row3(before, Index(a))).transpose();
      }
    });
    const std::size_t added = std::accumulate(pin.begin(), pin.end(), std::size_t{0});
    for (std::size_t a = 0; a < n; ++a)
      if (pin[a]) fixed[a] = 3;
    return added;
  };
  // The first solve only finds which agents sink: it stops at 100 times the
  // tolerance (measured on the 1M dress: 172 fine sweeps in all -> 112). The
  // solves after it go to the tolerance, and agents they sink start another round.
  const bool clear = options_.keep_clear_of_body && options_.clearance_rounds > 0;
  bool tight = !clear;
  st.iterations = 0;
  solve_fine(tight ? 1.0 : 100.0);
  for (st.clearance_rounds = 0;;) {
    const std::size_t added = clear && st.clearance_rounds < options_.clearance_rounds ? hold_clear() : 0;
    if (added > 0) {
      st.fixed_clearance += added;
      ++st.clearance_rounds;
      fr = free_agents(rows, group_, nullptr, nullptr, nullptr);
      tight = true;
      solve_fine(1.0);
      continue;
    }
    if (tight) break;
    tight = true;
    solve_fine(1.0);
  }
  if (system) {
    system->h = h_fine;
    system->free = fr;
    system->start = x_start;
    for (std::size_t a = 0; a < n; ++a)
      if (fixed[a] == 3) system->start.row(Eigen::Index(a)) = x.row(Eigen::Index(a));  // held where the rounds put it
  }
  // Beyond the paper: an anchored agent (its group has nothing fixed: a layer
  // of its own with no feature and nowhere near body B, such as a loose
  // overskirt over a fitted one) moves with the step's correction of the solved
  // agents within reach (inverse squared distance blend of the 4 nearest), so
  // it keeps to the layer beneath instead of staying where the warp put it;
  // one with none within reach stays as warped.
  std::vector<std::uint8_t> anchored_kept(n, 0);
  if (st.anchored > 0) {
    std::vector<std::uint8_t> solved(n, 0);
    for (std::size_t a = 0; a < n; ++a) {
      solved[a] = fixed[a] || fr[a];
      anchored_kept[a] = !solved[a];
    }
    if (std::count(solved.begin(), solved.end(), 1) > 0) {
      const PointTree tree(before, solved);
      const double reach2 = std::pow(options_.reach_voxels * h_, 2);
      const Points correction = x - before;
      parallel_for(0, n, kGrain, [&](std::size_t b, std::size_t e) {
        std::vector<Index> idx;
        std::vector<double> d2;
        for (std::size_t a = b; a < e; ++a) {
          if (solved[a]) continue;
          tree.knn(row3(before, Index(a)), 4, idx, d2);
          Vec3 c = Vec3::Zero();
          double sum = 0.0;
          for (std::size_t j = 0; j < idx.size() && d2[j] < reach2; ++j) {
            const double w = 1.0 / (d2[j] + 1e-12 * reach2);
            c += w * row3(correction, idx[j]);
            sum += w;
          }
          if (sum == 0.0) continue;
          x.row(Eigen::Index(a)) += (c / sum).transpose();
          anchored_kept[a] = 0;
        }
      });
    }
    for (std::size_t a = 0; a < n; ++a) st.anchored_followed += !fixed[a] && !fr[a] && !anchored_kept[a];
  }
  // Beyond the paper: the solution on irregular agents carries agent-scale noise
  // in its displacement (each h is exact only for its own original ring), which
  // the reconstruction shows as waviness. A few Jacobi passes move each free
  // agent's displacement (from the state its vertices are re-emitted from)
  // halfway to its ring's mean: fixed and anchored agents stay, A = B stays
  // exact (zero displacement), and the result is the same for any thread count.
  for (int pass = 0; pass < options_.smooth_passes; ++pass) {
    const Points d = x - (options_.emit_from_original && !options_.encode_on_warped ? original_agents_ : before);
    Points nx = x;
    parallel_for(0, n, kGrain, [&](std::size_t b, std::size_t e) {
      for (std::size_t a = b; a < e; ++a) {
        if (!fr[a] || ring_.row_size(a) == 0) continue;
        Vec3 m = Vec3::Zero();
        for (Index q : ring_.row(a)) m += row3(d, q);
        m /= double(ring_.row_size(a));
        nx.row(Eigen::Index(a)) += (0.5 * (m - row3(d, Index(a)))).transpose();
      }
    });
    x = std::move(nx);
  }
  st.ms.solve = clock.ms();
  clock.reset();

  if (n == 0) {
    res.positions = warped;
  } else {
    // emit_from_original (beyond the paper, which re-emits the warped vertices from
    // the warped agents' frames): each vertex keeps its original offsets to its
    // agents, turned by the agents' rotations from the original to the result.
    // The warp's own detail finer than the agent spacing (its creases where the
    // body's triangles change) is then replaced by the garment's original detail,
    // which is what this step restores; coarser warp changes live in the agents.
    // With encode_on_warped the target shape is the warp's, so its detail stays.
    // Anchored agents that had no solved agent within reach hand their vertices back as warped.
    const bool orig = options_.emit_from_original && !options_.encode_on_warped;
    const Points& from = orig ? original_agents_ : before;
    std::vector<Eigen::Matrix3d> rot;
    if (options_.fit_rotations) {
      rot = ring_rotations(from, x, ring_);
    } else {
      rot = frame_rotations(agent_frames(from, ring_, ring_open_, flip_), agent_frames(x, ring_, ring_open_, flip_));
    }
    std::vector<std::uint8_t> keep;
    if (orig && st.anchored > st.anchored_followed) keep = anchored_kept;
    res.positions = reconstruct_rotations(orig ? original_vertices_ : warped, from, x, rot, reach_, reach_weight_,
                                          nearest_, keep, &warped);
  }
  std::vector<std::uint8_t> kept_vertex;
  if (options_.keep_near_vertices && n > 0) {
    // Eq. 14 for the vertices too: blending frames of nearby free agents must not
    // pull a vertex that touches the body. Only vertices the nearest agent's
    // distance cannot rule out are queried: d(v) >= d(a) - |v - a|.
    std::vector<std::uint8_t> kept(vertex_count_, 0);
    parallel_for(0, vertex_count_, 1024, [&](std::size_t b, std::size_t e) {
      for (std::size_t v = b; v < e; ++v) {
        const Index a = nearest_[v];
        if (!near_feature_.empty() && (near_feature_[a] || carries_feature_[v])) continue;
        const Vec3 p = row3(warped, Index(v));
        if (feature_of_[a] < 0 && body_distance[a] - (p - row3(before, a)).norm() >= options_.epsilon) continue;
        if (distance(p) < options_.epsilon) {
          res.positions.row(Eigen::Index(v)) = warped.row(Eigen::Index(v));
          kept[v] = 1;
        }
      }
    });
    st.vertices_kept = std::accumulate(kept.begin(), kept.end(), std::size_t{0});
    kept_vertex = std::move(kept);
  }
  if (options_.snap_to_features && !near_feature_.empty() && nf > 0 && !feature_attachment_.vertex.empty()) {
    const FeatureSnapReport snap = snap_to_features(res.positions, targets, feature_attachment_, reach_, reach_weight_,
                                                    feature_of_, kept_vertex, options_.snap_regularisation);
    st.feature_gap_before_snap = snap.gap_before;
    st.feature_gap = snap.gap_after;
    st.vertices_snapped = snap.vertices_moved;
  }
  res.agents = std::move(x);
  st.ms.reconstruct = clock.ms();
  return res;
}

}  // namespace refit
