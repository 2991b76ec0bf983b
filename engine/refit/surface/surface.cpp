#include <refit/body/centre_tree.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/progress.hpp>
#include <refit/surface/agents.hpp>
#include <refit/surface/surface.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>

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
  if (!(o.reach_voxels > 0.0) || !std::isfinite(o.reach_voxels)) throw bad("reach must be positive");
  if (!(o.ring_radius_voxels > 0.0) || !std::isfinite(o.ring_radius_voxels)) throw bad("one-ring radius must be positive");
  if (!(o.block_voxels > 0.0) || !std::isfinite(o.block_voxels)) throw bad("block size must be positive");
  if (o.max_reach_agents == 0) throw bad("max reach agents must be at least 1");
}

// Rows computed per fixed chunk (independent of TBB's split), then concatenated in order.
template <class RowFn>
Csr build_csr(std::size_t n, std::size_t chunk, RowFn&& row_fn) {
  const std::size_t chunks = (n + chunk - 1) / chunk;
  std::vector<Csr> parts(chunks);
  parallel_for(0, chunks, 1, [&](std::size_t b, std::size_t e) {
    std::vector<Index> row;
    for (std::size_t c = b; c < e; ++c)
      for (std::size_t i = c * chunk; i < std::min(n, (c + 1) * chunk); ++i) {
        row.clear();
        row_fn(i, row);
        parts[c].push_row(row);
      }
  });
  Csr out;
  out.offsets.reserve(n + 1);
  for (auto& p : parts) {
    const Index base = static_cast<Index>(out.indices.size());
    out.indices.insert(out.indices.end(), p.indices.begin(), p.indices.end());
    for (std::size_t r = 1; r < p.offsets.size(); ++r) out.offsets.push_back(base + p.offsets[r]);
    p.clear();
  }
  return out;
}
}  // namespace

SurfaceBinding SurfaceBinding::bind(const Garment& g, const Points& features, const SurfaceOptions& options) {
  return bind_level(g, features, options, nullptr);
}

SurfaceBinding SurfaceBinding::bind_level(const Garment& g, const Points& features, const SurfaceOptions& options,
                                          const SurfaceBinding* finer) {
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
  // More agents than vertices adds no detail the reconstruction could show; it only slows the solve.
  const std::size_t budget = std::min(options.agent_budget, std::max<std::size_t>(g.vertex_count(), 1000));
  s.h_ = st.voxel_was_auto ? auto_voxel_size(g, budget) : options.voxel;
  st.voxel = s.h_;
  const VoxelGrid grid = make_voxel_grid(g, features, s.h_);
  const std::size_t nf = static_cast<std::size_t>(features.rows());
  std::vector<std::uint64_t> feature_voxel(nf);
  for (std::size_t k = 0; k < nf; ++k) feature_voxel[k] = VoxelGrid::morton(grid.cell(row3(features, Index(k))));
  std::vector<std::uint64_t> skip = feature_voxel;
  std::sort(skip.begin(), skip.end());
  skip.erase(std::unique(skip.begin(), skip.end()), skip.end());
  st.ms.sample = clock.ms();
  clock.reset();

  GarmentAgents ga = select_agents(g, grid, skip);
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
  st.ms.agents = clock.ms();
  clock.reset();

  // One-rings, then storage order block by block (the block must be wider than the
  // longest one-ring edge, so rings come first).
  Csr ring0 = build_one_rings(natural, options.ring_radius_voxels * s.h_);
  const double longest = longest_edge(natural, ring0);
  // Wider than the longest edge keeps same-colour blocks apart; a few voxels wide
  // gives each parallel task enough agents to pay for itself.
  const double width = std::max(longest * (1.0 + 1e-6), options.block_voxels * s.h_);
  const std::vector<Index> order = make_block_order(natural, morton, width);
  std::vector<Index> slot_of(n);
  for (std::size_t k = 0; k < n; ++k) slot_of[order[k]] = Index(k);
  s.original_agents_.resize(static_cast<Eigen::Index>(n), 3);
  s.src_vertex_.resize(n);
  s.src_weight_.resize(n);
  s.feature_of_.assign(n, -1);
  s.feature_slot_.resize(nf);
  for (std::size_t k = 0; k < n; ++k) {
    const Index old = order[k];
    s.original_agents_.row(static_cast<Eigen::Index>(k)) = natural.row(old);
    if (old < ng) {
      s.src_vertex_[k] = ga.vertex[old];
      s.src_weight_[k] = ga.weight[old];
    } else {
      s.feature_of_[k] = static_cast<std::int32_t>(old - ng);
      s.feature_slot_[old - ng] = Index(k);
    }
  }
  for (std::size_t k = 0; k < n; ++k) {
    std::vector<Index> r(ring0.row(order[k]).begin(), ring0.row(order[k]).end());
    for (Index& q : r) q = slot_of[q];
    s.ring_.push_row(r);
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
  s.flip_ = orient_normals(fan_normals(s.original_agents_, s.ring_, s.ring_open_), s.ring_);
  // Connected groups of the one-ring graph (for anchoring).
  s.group_.resize(n);
  std::iota(s.group_.begin(), s.group_.end(), Index{0});
  auto root = [&](Index a) {
    while (s.group_[a] != a) a = s.group_[a] = s.group_[s.group_[a]];
    return a;
  };
  for (std::size_t a = 0; a < n; ++a)
    for (Index b : s.ring_.row(a)) {
      const Index ra = root(Index(a)), rb = root(b);
      if (ra != rb) s.group_[std::max(ra, rb)] = std::min(ra, rb);
    }
  for (std::size_t a = 0; a < n; ++a) s.group_[a] = root(Index(a));
  s.groups_ = 0;
  for (std::size_t a = 0; a < n; ++a) s.groups_ += s.group_[a] == a;
  st.ms.one_ring = clock.ms();
  clock.reset();

  if (!options.encode_on_warped) {
    s.rows_ = encode_agents(s.original_agents_, s.ring_);
    st.degenerate_rows = s.rows_.degenerate;
  }
  st.ms.encode = clock.ms();
  clock.reset();

  // Each vertex's agents within reach, and the nearest agent (for vertices with none).
  const std::size_t nv = g.vertex_count();
  s.nearest_.assign(nv, 0);
  if (n > 0) {
    const PointTree tree(s.original_agents_);
    const double r2 = std::pow(options.reach_voxels * s.h_, 2);
    std::vector<std::uint8_t> capped(nv, 0);
    // The nearest max_reach_agents, then the reach radius: a bounded k-nearest
    // query costs far less than collecting every agent within reach and cutting.
    s.reach_ = build_csr(nv, 4096, [&](std::size_t v, std::vector<Index>& row) {
      thread_local std::vector<Index> idx;
      thread_local std::vector<double> d2;
      const Vec3 p = row3(g.positions, Index(v));
      tree.knn(p, options.max_reach_agents + 1, idx, d2);
      std::size_t m = 0;
      while (m < idx.size() && m < options.max_reach_agents && d2[m] < r2) ++m;
      capped[v] = m == options.max_reach_agents && idx.size() > m && d2[m] < r2;
      row.insert(row.end(), idx.begin(), idx.begin() + static_cast<std::ptrdiff_t>(m));
      s.nearest_[v] = idx.empty() ? 0 : idx.front();
    });
    st.vertices_capped = std::accumulate(capped.begin(), capped.end(), std::size_t{0});
    for (std::size_t v = 0; v < nv; ++v) st.vertices_without_agent += s.reach_.row_size(v) == 0;
    // Feature samples without a warped position move with their nearest vertex.
    if (finer) {  // the same garment and samples: reuse the finer level's attachment
      s.feature_vertex_ = finer->feature_vertex_;
      s.feature_offset_ = finer->feature_offset_;
    } else if (nf > 0 && nv > 0) {
      const PointTree vtree(g.positions);
      s.feature_vertex_.resize(nf);
      s.feature_offset_.resize(static_cast<Eigen::Index>(nf), 3);
      for (std::size_t k = 0; k < nf; ++k) {
        const Index v = vtree.nearest(row3(features, Index(k))).first;
        s.feature_vertex_[k] = v;
        s.feature_offset_.row(static_cast<Eigen::Index>(k)) = features.row(Eigen::Index(k)) - g.positions.row(v);
      }
    }
  } else {
    s.reach_.offsets.assign(nv + 1, 0);
  }
  st.ms.reconstruct = clock.ms();  // bind share of the reconstruction (vertex lists)
  if (options.coarse_levels > 0 && n / 4 >= options.coarse_min_agents) {
    SurfaceOptions co = options;
    co.voxel = 2.0 * s.h_;
    co.coarse_levels = options.coarse_levels - 1;
    co.keep_near_vertices = false;  // only the agents' start matters,
    co.max_reach_agents = std::min<std::size_t>(options.max_reach_agents, 4);  // so a rough blend will do
    s.coarse_ = std::make_shared<const SurfaceBinding>(bind_level(g, features, co, &s));
    st.levels = 1 + s.coarse_->stats_.levels;
  }
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
      } else if (!feature_vertex_.empty()) {
        p = row3(x, feature_vertex_[k]) + row3(feature_offset_, Index(k));
      } else {
        p = row3(original_agents_, Index(a));  // no garment vertex at all: nothing moved
      }
      out.row(static_cast<Eigen::Index>(a)) = p.transpose();
    }
  });
  return out;
}

SurfaceResult SurfaceBinding::apply(const Points& warped, const Points& targets,
                                    const std::function<double(const Vec3&)>& distance, const Points* fwarped) const {
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
  Stopwatch clock;
  const Points before = agent_positions(warped, fwarped);

  AgentRows warped_rows;
  if (options_.encode_on_warped) {
    warped_rows = encode_agents(before, ring_);
    st.degenerate_rows = warped_rows.degenerate;
    st.ms.encode = clock.ms();
    clock.reset();
  }
  const AgentRows& rows = options_.encode_on_warped ? warped_rows : rows_;

  // Constraints: eq. 15 for feature agents, eq. 14 within epsilon of body B.
  std::vector<std::uint8_t> fixed(n, 0);
  parallel_for(0, n, 256, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      if (feature_of_[a] >= 0) fixed[a] = 2;
      else if (distance(row3(before, Index(a))) < options_.epsilon) fixed[a] = 1;
    }
  });
  std::vector<std::uint8_t> group_fixed(n, 0);
  for (std::size_t a = 0; a < n; ++a) {
    st.fixed_feature += fixed[a] == 2;
    st.fixed_body += fixed[a] == 1;
    if (fixed[a]) group_fixed[group_[a]] = 1;
  }
  // A group with no fixed agent has no unique solution: anchor it where the warp put it.
  std::vector<std::uint8_t> free(n, 0);
  for (std::size_t a = 0; a < n; ++a) {
    if (fixed[a]) continue;
    if (!group_fixed[group_[a]]) {
      ++st.anchored;
      if (group_[a] == a) ++st.anchored_groups;
    } else {
      free[a] = rows.diag[a] > 0.0;
    }
  }
  Points x = before;
  if (coarse_) {
    const SurfaceResult cr = coarse_->apply(warped, targets, distance, fwarped);
    st.coarse_iterations = cr.stats.iterations + cr.stats.coarse_iterations;
    const Points start = agent_positions(cr.positions, fwarped);
    for (std::size_t a = 0; a < n; ++a)
      if (free[a]) x.row(Eigen::Index(a)) = start.row(Eigen::Index(a));
  }
  for (std::size_t k = 0; k < nf; ++k) x.row(feature_slot_[k]) = targets.row(Eigen::Index(k));
  const SolveReport rep = gauss_seidel(rows, schedule_, free, x, {options_.max_iterations, options_.tolerance});
  st.iterations = rep.iterations;
  st.final_update = rep.final_update;
  st.converged = rep.converged || n == 0;
  st.ms.solve = clock.ms();
  clock.reset();

  const AgentFrames fb = agent_frames(before, ring_, ring_open_, flip_);
  const AgentFrames fa = agent_frames(x, ring_, ring_open_, flip_);
  res.positions = n > 0 ? reconstruct(warped, fb, fa, reach_, nearest_) : warped;
  if (options_.keep_near_vertices) {
    // Eq. 14 for the vertices too: blending frames of nearby free agents must not
    // pull a vertex that touches the body.
    std::vector<std::uint8_t> kept(vertex_count_, 0);
    parallel_for(0, vertex_count_, 256, [&](std::size_t b, std::size_t e) {
      for (std::size_t v = b; v < e; ++v)
        if (distance(row3(warped, Index(v))) < options_.epsilon) {
          res.positions.row(Eigen::Index(v)) = warped.row(Eigen::Index(v));
          kept[v] = 1;
        }
    });
    st.vertices_kept = std::accumulate(kept.begin(), kept.end(), std::size_t{0});
  }
  res.agents = std::move(x);
  st.ms.reconstruct = clock.ms();
  return res;
}

}  // namespace refit
