// The surface step per body B (SurfaceBinding::apply): the constraints (eqs.
// 14-15), the coarse-to-fine start, the solve of eq. 13 with the clearance
// rounds, and the way back to vertices (reconstruct.cpp) and through the
// optimised curves (feature_snap.cpp). Binding: bind.cpp; solvers: solver.cpp.
#include <refit/body/centre_tree.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/progress.hpp>
#include <refit/surface/agents.hpp>
#include <refit/surface/clearance.hpp>
#include <refit/surface/feature_bend.hpp>
#include <refit/surface/feature_snap.hpp>
#include <refit/surface/surface.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace refit {

namespace {
constexpr std::size_t kSurfaceGrain = 1024;

// h of eq. 13 for the agents of `r`, each turned by its agent's rotation in
// `turn` (rotate_encoding; empty: as encoded). agent: fine slot of each row.
Points turned_h(const AgentRows& r, const std::vector<Index>* agent, const std::vector<Eigen::Matrix3d>& turn) {
  Points h = r.h;
  if (!turn.empty())
    parallel_for(0, r.size(), kSurfaceGrain, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const Index a = agent ? (*agent)[i] : Index(i);
        h.row(Eigen::Index(i)) = (turn[a] * row3(r.h, Index(i))).transpose();
      }
    });
  return h;
}

// Free agents of a level: not fixed, and in a group (of the level's one-ring
// graph) with a fixed agent; a group with none has no unique solution: it is
// anchored where the warp put it. agent: fine slot of each row (null: fine).
std::vector<std::uint8_t> free_agents(const AgentRows& r, const std::vector<Index>& group,
                                      const std::vector<Index>* agent, const std::vector<std::uint8_t>& fixed,
                                      std::size_t* anchored = nullptr, std::size_t* anchored_groups = nullptr) {

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
}

}  // namespace

Points SurfaceBinding::agent_positions(const Points& x, const Points* fp) const {
  return agent_positions_of([&x](Index v) { return row3(x, v); }, fp);
}

std::vector<Index> SurfaceBinding::agent_vertices() const {
  std::vector<Index> ids;
  for (std::size_t a = 0; a < agent_count(); ++a)
    if (feature_of_[a] < 0) ids.insert(ids.end(), src_vertex_[a].begin(), src_vertex_[a].end());
  for (const auto& v : feature_attachment_.vertex) ids.insert(ids.end(), v.begin(), v.end());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

Points SurfaceBinding::agent_positions(const Points& vertices, const std::vector<Index>& ids, const Points* fp) const {
  return agent_positions_of(
      [&](Index v) { return row3(vertices, Index(std::lower_bound(ids.begin(), ids.end(), v) - ids.begin())); }, fp);
}

template <class Vertex>
Points SurfaceBinding::agent_positions_of(const Vertex& x, const Points* fp) const {
  const std::size_t n = agent_count();
  Points out(static_cast<Eigen::Index>(n), 3);
  parallel_for(0, n, kSurfaceGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      Vec3 p = Vec3::Zero();
      const std::int32_t k = feature_of_[a];
      if (k < 0) {
        for (int j = 0; j < 3; ++j) p += src_weight_[a][j] * x(src_vertex_[a][j]);
      } else if (fp) {
        p = row3(*fp, Index(k));
      } else if (!feature_attachment_.vertex.empty()) {
        // carry_one's sum
        const auto s = static_cast<std::size_t>(k);
        p = row3(feature_attachment_.offset, Index(k));
        for (int j = 0; j < 3; ++j) p += feature_attachment_.weight[s][j] * x(feature_attachment_.vertex[s][j]);
      } else {
        p = row3(original_agents_, Index(a));  // no garment vertex at all: nothing moved
      }
      out.row(static_cast<Eigen::Index>(a)) = p.transpose();
    }
  });
  return out;
}

// Coarse to fine: solve the coarsest subset from the warp, then start each finer
// level from the coarser solution's displacement, interpolated; the fine agents
// free in `fine_free` start from the finest level's solution the same way.
Points SurfaceBinding::coarse_to_fine_start(const Points& before, const Points& target_of,
                                            const std::vector<std::uint8_t>& fixed,
                                            const std::vector<Eigen::Matrix3d>& turn,
                                            const std::vector<std::uint8_t>& fine_free, const SolveOptions& solve,
                                            int& coarse_iterations) const {
  const std::size_t n = agent_count();
  Points x_coarse;  // solution of the level below the current one (its own order)
  for (std::size_t l = levels_.size(); l-- > 0;) {
    const CoarseLevel& lv = levels_[l];
    const std::size_t m = lv.agent.size();
    Points x(static_cast<Eigen::Index>(m), 3);
    Points b_l(static_cast<Eigen::Index>(m), 3);
    for (std::size_t i = 0; i < m; ++i) b_l.row(Eigen::Index(i)) = before.row(lv.agent[i]);
    if (l + 1 == levels_.size()) {
      x = b_l;
    } else {
      const CoarseLevel& below = levels_[l + 1];
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
    const std::vector<std::uint8_t> level_free = free_agents(lv.rows, lv.group, &lv.agent, fixed);
    AgentRows warped_level;
    if (options_.encode_on_warped) warped_level = encode_agents(b_l, lv.ring);
    const AgentRows& r = options_.encode_on_warped ? warped_level : lv.rows;
    // With multigrid the start only has to be smooth: measured on the 1M dress
    // at 910k agents, 500 sweeps per start level (2,000 in all, mostly on the
    // 241k-agent level: 3-5 s) and 30 per level gave 199 and 180 fine sweeps.
    SolveOptions start = solve;
    if (options_.multigrid) start.max_iterations = std::min(start.max_iterations, options_.coarse_start_sweeps);
    const SolveReport rep = gauss_seidel(r, turned_h(r, &lv.agent, turn), lv.schedule, level_free, x, start);
    coarse_iterations += rep.iterations;
    x_coarse = std::move(x);
  }

  Points x = before;
  if (!levels_.empty()) {
    const CoarseLevel& below = levels_.front();
    parallel_for(0, n, kSurfaceGrain, [&](std::size_t b, std::size_t e) {
      for (std::size_t a = b; a < e; ++a) {
        if (!fine_free[a]) continue;
        Vec3 d = Vec3::Zero();
        auto r = below.up.row(a);
        for (std::size_t j = 0; j < r.size(); ++j)
          d += double(below.up_weight[below.up.offsets[a] + j]) * (row3(x_coarse, r[j]) - row3(before, below.agent[r[j]]));
        x.row(Eigen::Index(a)) += d.transpose();
      }
    });
  }
  return x;
}

SurfaceResult SurfaceBinding::apply(const Points& warped, const Points& targets,
                                    const std::function<double(const Vec3&)>& distance, const Points* fwarped,
                                    SurfaceSystem* system) const {
  const NearBody near = [&](const Vec3& p) { return distance(p) < options_.epsilon; };
  return apply(warped, targets, distance, near, fwarped, system);
}

SurfaceResult SurfaceBinding::apply(const Points& warped, const Points& targets,
                                    const std::function<double(const Vec3&)>& distance, const NearBody& near,
                                    const Points* fwarped, SurfaceSystem* system) const {
  const std::size_t nf = feature_count();
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

  Stopwatch clock;
  AgentSolution sol = solve_agents(agent_positions(warped, fwarped), targets, distance, system);
  SurfaceResult res;
  res.stats = sol.stats;
  SurfaceStats& st = res.stats;
  clock.reset();
  std::vector<float> held;
  res.positions = emit_vertices(sol, original_vertices_, warped, blends_, carries_feature_, near, held, st);
  const FeatureSnapReport snapped = snap(res.positions, targets, held);
  st.feature_gap_before_snap = snapped.gap_before;
  st.feature_gap = snapped.gap_after;
  st.vertices_snapped = snapped.vertices_moved;
  res.held = std::move(held);
  res.agents = std::move(sol.x);
  st.ms.reconstruct = clock.ms();
  return res;
}

SnapReach SurfaceBinding::snap_reach(const Points& positions, std::span<const std::uint32_t> layer) const {
  SnapReach out;
  const std::size_t nv = std::size_t(positions.rows()), nf = feature_slot_.size();
  out.reach.offsets.assign(nv + 1, 0);
  const double r2 = std::pow(options_.snap_radius * h_, 2);
  if (nf == 0 || !(r2 > 0.0)) return out;
  Points samples(Eigen::Index(nf), 3);
  for (std::size_t k = 0; k < nf; ++k) samples.row(Eigen::Index(k)) = original_agents_.row(feature_slot_[k]);
  const PointTree tree(samples);
  // Fixed blocks, each with its own lists, joined in block order: the same for any thread count.
  const std::size_t blocks = (nv + kSurfaceGrain - 1) / kSurfaceGrain;
  std::vector<std::vector<Index>> slots(blocks);
  std::vector<std::vector<float>> weights(blocks);
  parallel_for(0, blocks, 1, [&](std::size_t b, std::size_t e) {
    std::vector<std::pair<Index, double>> near;
    for (std::size_t blk = b; blk < e; ++blk)
      for (std::size_t v = blk * kSurfaceGrain; v < std::min(nv, (blk + 1) * kSurfaceGrain); ++v) {
        // A vertex of a layer is moved by its own layer's feature agents only (as it blends its own layer's agents).
        const std::uint32_t own = layer.empty() ? 0u : layer[v];
        tree.within(row3(positions, Index(v)), r2, near);
        for (const auto& [k, d2] : near) {
          const Index slot = feature_slot_[k];
          const double t = 1.0 - d2 / r2;
          if ((own != 0 && layer_[slot] != own) || !(t > 0.0)) continue;
          slots[blk].push_back(slot);
          weights[blk].push_back(static_cast<float>(t * t));
          ++out.reach.offsets[v + 1];
        }
      }
  });
  for (std::size_t v = 0; v < nv; ++v) out.reach.offsets[v + 1] += out.reach.offsets[v];
  for (std::size_t blk = 0; blk < blocks; ++blk) {
    out.reach.indices.insert(out.reach.indices.end(), slots[blk].begin(), slots[blk].end());
    out.weight.insert(out.weight.end(), weights[blk].begin(), weights[blk].end());
  }
  return out;
}

bool SurfaceBinding::snaps() const {
  return options_.snap_to_features && !near_feature_.empty() && feature_count() > 0 && !feature_attachment_.vertex.empty();
}

SurfaceBinding::AgentSolution SurfaceBinding::solve_agents(Points before_in, const Points& targets,
                                                           const std::function<double(const Vec3&)>& distance,
                                                           SurfaceSystem* system) const {
  const std::size_t n = agent_count(), nf = feature_count();
  AgentSolution sol;
  sol.before = std::move(before_in);
  const Points& before = sol.before;
  sol.stats = stats_;
  SurfaceStats& st = sol.stats;
  st.ms.encode = 0.0;
  Stopwatch clock;

  // Constraints: eq. 15 for feature agents, eq. 14 within epsilon of body B
  // (or inside it: the distance is signed) except in the features' zone (see
  // SurfaceOptions::feature_zone_rings). fixed: 2 feature, 1 body, 3 clearance,
  // 4 band: with near_body_band, eq. 14's agents on a hanging piece with features
  // get a ceiling instead (hold_near_body), applied with the clearance rounds.
  std::vector<std::uint8_t> fixed(n, 0), near(n, 0);
  std::vector<double> body_distance(n, 0.0);
  parallel_for(0, n, 256, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      if (feature_of_[a] >= 0) {
        fixed[a] = 2;
      } else {
        body_distance[a] = distance(row3(before, Index(a)));
        near[a] = body_distance[a] < options_.epsilon && (near_feature_.empty() || !near_feature_[a]);
      }
    }
  });
  std::vector<std::uint8_t> banded;
  std::vector<double> ceiling;
  if (options_.near_body_band > 0.0 && options_.keep_clear_of_body && options_.clearance_rounds > 0) {
    // Per piece: its agents, those on the body (the features' own and their zone
    // counted: how much of the piece lies on the body) and its feature agents.
    std::vector<std::size_t> agents_of(n, 0), near_of(n, 0), features_of(n, 0);
    for (std::size_t a = 0; a < n; ++a) {
      const Index g = group_[a];
      ++agents_of[g];
      near_of[g] += feature_of_[a] < 0 && body_distance[a] < options_.epsilon;
      features_of[g] += feature_of_[a] >= 0;
    }
    banded.assign(n, 0);
    ceiling.assign(n, std::numeric_limits<double>::infinity());
    for (std::size_t a = 0; a < n; ++a) {
      const Index g = group_[a];
      // A piece without features has nothing to keep its shape towards (and no fixed agent without eq. 14).
      if (!near[a] || features_of[g] == 0 || double(near_of[g]) > options_.near_body_band_share * double(agents_of[g]))
        continue;
      banded[a] = 1;
      ++st.banded;
      near[a] = 0;
      ceiling[a] = std::max(body_distance[a], options_.clearance) + options_.near_body_band;
    }
  }
  // Near the features (SurfaceOptions::feature_slide_rings) eq. 14's agents
  // join the band with a ceiling at their own distance, and a share that fades
  // with their ring steps from the nearest feature agent.
  const bool clear = options_.keep_clear_of_body && options_.clearance_rounds > 0;
  if (options_.feature_slide_rings > 0 && options_.feature_zone_rings > 0 && nf > 0 && clear) {
    const int rings = options_.feature_slide_rings;
    const std::vector<int> depth = feature_depth(ring_, fixed, rings);
    for (std::size_t a = 0; a < n; ++a) {
      if (!near[a] || depth[a] <= 0) continue;
      if (banded.empty()) {
        banded.assign(n, 0);
        ceiling.assign(n, std::numeric_limits<double>::infinity());
      }
      if (sol.slide.empty()) sol.slide.assign(n, 0.0f);
      const double t = double(rings + 1 - depth[a]) / double(rings);
      sol.slide[a] = float(smoothstep(t));
      banded[a] = 1;
      near[a] = 0;
      ceiling[a] = std::max(body_distance[a], options_.clearance);
      ++st.feature_slid;
    }
  }
  for (std::size_t a = 0; a < n; ++a)
    if (near[a]) fixed[a] = 1;
  const bool band = !banded.empty();
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
  // Body-proportional size (group_stretches): h scaled by each piece's stretch
  // from the original to the warp. The paper's encoding keeps the absolute size.
  std::vector<Eigen::Matrix3d> stretch;
  if (options_.follow_body_scale && !options_.encode_on_warped) {
    stretch = group_stretches(original_agents_, before, group_);
    if (turn.empty()) turn = stretch;
    else for (std::size_t a = 0; a < n; ++a) turn[a] = turn[a] * stretch[a];
  }
  const AgentRows& rows = options_.encode_on_warped ? warped_rows : rows_;
  st.ms.encode = clock.ms();
  clock.reset();

  const SolveOptions solve{options_.max_iterations, options_.tolerance, options_.relaxation};

  std::vector<std::uint8_t> fr = free_agents(rows, group_, nullptr, fixed, &st.anchored, &st.anchored_groups);
  Points x = coarse_to_fine_start(before, target_of, fixed, turn, fr, solve, st.coarse_iterations);
  for (std::size_t k = 0; k < nf; ++k) x.row(feature_slot_[k]) = targets.row(Eigen::Index(k));
  const Points h_fine = turned_h(rows, nullptr, turn);
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
  // Clearance rounds (clearance.hpp): free agents the solve sinks into body B
  // are held clear of it and the system is solved again.
  const double step = 1e-3 * h_;
  auto hold_band = [&](const std::vector<std::uint8_t>& solved) {
    const std::size_t held = band ? hold_near_body(distance, ceiling, step, solved, before, x, fixed) : 0;
    st.fixed_band += held;
    return held;
  };
  auto hold_clear = [&] {
    return hold_clear_of_body(distance, options_.clearance, step, fr, before, x, fixed) + hold_band(fr);
  };
  // The first solve only finds which agents sink: it stops at 100 times the
  // tolerance (measured on the 1M dress: 172 fine sweeps in all -> 112). The
  // solves after it go to the tolerance, and agents they sink start another round.
  bool tight = !clear;
  st.iterations = 0;
  solve_fine(tight ? 1.0 : 100.0);
  for (st.clearance_rounds = 0;;) {
    const std::size_t added = clear && st.clearance_rounds < options_.clearance_rounds ? hold_clear() : 0;
    if (added > 0) {
      st.fixed_clearance += added;
      ++st.clearance_rounds;
      fr = free_agents(rows, group_, nullptr, fixed);
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
      if (fixed[a] >= 3) system->start.row(Eigen::Index(a)) = x.row(Eigen::Index(a));  // held where the rounds put it
  }
  if (options_.feature_bend_radius > 0.0 && nf > 0 && h_ > 0.0) {
    st.feature_bend_rings = int(std::min(64.0, std::round(options_.feature_bend_radius / h_)));
    std::function<std::size_t(const std::vector<std::uint8_t>&)> hold;
    if (clear)
      hold = [&](const std::vector<std::uint8_t>& solved) {
        return hold_clear_of_body(distance, options_.clearance, step, solved, before, x, fixed) + hold_band(solved);
      };
    const FeatureBendReport bend = bend_around_features(rows, h_fine, st.feature_bend_rings, fr, fixed, x,
                                                        options_.clearance_rounds, hold);
    st.feature_bend_agents = bend.agents;
    st.feature_bend_rounds = bend.rounds;
  }
  std::vector<std::uint8_t> anchored_kept(n, 0);
  if (st.anchored > 0) st.anchored_followed = follow_anchored(before, fixed, fr, x, anchored_kept);
  smooth_displacements(before, fr, x);
  for (std::size_t a = 0; a < sol.slide.size(); ++a)
    if (sol.slide[a] > 0.0f)
      x.row(Eigen::Index(a)) = before.row(Eigen::Index(a)) + double(sol.slide[a]) * (x.row(Eigen::Index(a)) - before.row(Eigen::Index(a)));
  st.ms.solve = clock.ms();
  if (n > 0) sol.rotation = rotations(before, x, stretch);
  if (options_.emit_from_original && !options_.encode_on_warped && st.anchored > st.anchored_followed)
    sol.keep = std::move(anchored_kept);
  sol.body_distance = std::move(body_distance);
  sol.banded = std::move(banded);
  sol.x = std::move(x);
  return sol;
}

FeatureSnapReport SurfaceBinding::snap(Points& positions, const Points& targets, const std::vector<float>& held,
                                       int passes) const {
  FeatureSnapReport total;
  if (!snaps()) return total;
  if (static_cast<std::size_t>(targets.rows()) != feature_count() || static_cast<std::size_t>(positions.rows()) != vertex_count_)
    throw Error("surface: the snap's targets or positions do not match the binding");
  // (The chunked pipeline does the same passes: chunked_resize.cpp.)
  const bool kernel = options_.snap_radius > 0.0;
  const Csr& reach = kernel ? snap_reach_.reach : blends_.reach;
  const std::vector<float>& weight = kernel ? snap_reach_.weight : blends_.weight;
  for (int pass = 0; pass < std::max(1, passes > 0 ? passes : options_.snap_passes); ++pass) {
    const Points before = positions;
    const FeatureSnapReport r =
        snap_to_features(positions, targets, feature_attachment_, reach, weight, feature_of_, held,
                         options_.snap_regularisation, snap_share(pass));
    if (pass == 0) total = r;  // every pass moves the same vertices
    total.gap_after = r.gap_after;
    if (!(r.gap_after < r.gap_before)) {  // a pass that does not help is undone
      positions = before;
      total.gap_after = r.gap_before;
      if (pass == 0) total.vertices_moved = 0;
      break;
    }
  }
  return total;
}

}  // namespace refit
