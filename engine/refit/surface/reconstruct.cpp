// From agents back to vertices (paper eq. 4 and beyond): each vertex's agents
// within reach and their blend weights (bound once), anchored agents following
// their solved neighbours, the smoothing of the solved displacements, the
// re-emission of every vertex from its agents' rotations, and eq. 14 for the
// vertices that touch body B.
#include <refit/body/centre_tree.hpp>
#include <refit/core/parallel.hpp>
#include <refit/surface/agents.hpp>
#include <refit/surface/surface.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace refit {

namespace {
constexpr std::size_t kVertexGrain = 1024;
}  // namespace

VertexBlends SurfaceBinding::vertex_blends(const Points& positions, std::span<const std::uint32_t> vertex_layer) const {
  const std::size_t n = agent_count(), nv = static_cast<std::size_t>(positions.rows());
  VertexBlends out;
  // Each vertex's nearest agents within reach (a bounded k-nearest query), and the
  // nearest agent (for vertices with none).
  const std::size_t kmax = options_.max_reach_agents;
  out.nearest.assign(nv, 0);
  if (n > 0) {
    // A vertex of a layer blends its own layer's agents only.
    const LayerTrees tree(original_agents_, layer_);
    const double reach2 = std::pow(options_.reach_voxels * h_, 2);
    std::vector<std::uint8_t> capped(nv, 0);
    std::vector<std::uint8_t> count(nv, 0);
    UninitVector<Index> idx_all(nv * kmax);  // slots past a vertex's count stay unset and unread
    UninitVector<float> w_all(options_.smooth_blend ? nv * kmax : 0);
    parallel_for(0, nv, 2048, [&](std::size_t b, std::size_t e) {
      std::vector<Index> idx;
      std::vector<double> d2;
      // The previous vertex's agents (consecutive vertices are mostly near each
      // other) bound the search from the start: same answers, less search.
      std::vector<Vec3> hint;
      for (std::size_t v = b; v < e; ++v) {
        const Vec3 p = row3(positions, Index(v));
        const std::uint32_t layer = vertex_layer.empty() ? 0u : vertex_layer[v];
        if (v > b && layer != (vertex_layer.empty() ? 0u : vertex_layer[v - 1])) hint.clear();
        tree.knn(layer, p, kmax + 1, idx, d2, hint);
        hint.clear();
        for (Index i : idx) hint.push_back(row3(original_agents_, i));
        std::size_t m = 0;
        while (m < idx.size() && m < kmax && d2[m] < reach2) ++m;
        capped[v] = m == kmax && idx.size() > m && d2[m] < reach2;
        out.nearest[v] = idx.empty() ? 0 : idx.front();
        count[v] = static_cast<std::uint8_t>(m);
        std::copy(idx.begin(), idx.begin() + std::ptrdiff_t(m), idx_all.begin() + std::ptrdiff_t(v * kmax));
        if (options_.smooth_blend && m > 0) {
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
    Csr& reach = out.reach;
    reach.offsets.assign(nv + 1, 0);
    for (std::size_t v = 0; v < nv; ++v) reach.offsets[v + 1] = reach.offsets[v] + count[v];
    reach.indices.resize(reach.offsets[nv]);
    if (options_.smooth_blend) out.weight.resize(reach.offsets[nv]);
    parallel_for(0, nv, 8192, [&](std::size_t b, std::size_t e) {
      for (std::size_t v = b; v < e; ++v)
        for (std::size_t j = 0; j < count[v]; ++j) {
          reach.indices[reach.offsets[v] + j] = idx_all[v * kmax + j];
          if (options_.smooth_blend) out.weight[reach.offsets[v] + j] = w_all[v * kmax + j];
        }
    });
    out.capped = std::accumulate(capped.begin(), capped.end(), std::size_t{0});
    for (std::size_t v = 0; v < nv; ++v) out.without_agent += count[v] == 0;
  } else {
    out.reach.offsets.assign(nv + 1, 0);
  }
  return out;
}

// Beyond the paper: an anchored agent (its group has nothing fixed: a layer of
// its own with no feature and nowhere near body B, such as a loose overskirt
// over a fitted one) moves with the step's correction of the solved agents
// within reach (inverse squared distance blend of the 4 nearest), so it keeps to
// the layer beneath instead of staying where the warp put it; one with none
// within reach stays as warped.
std::size_t SurfaceBinding::follow_anchored(const Points& before, const std::vector<std::uint8_t>& fixed,
                                            const std::vector<std::uint8_t>& fr, Points& x,
                                            std::vector<std::uint8_t>& anchored_kept) const {
  const std::size_t n = agent_count();
  std::vector<std::uint8_t> solved(n, 0);
  for (std::size_t a = 0; a < n; ++a) {
    solved[a] = fixed[a] || fr[a];
    anchored_kept[a] = !solved[a];
  }
  if (std::count(solved.begin(), solved.end(), 1) > 0) {
    const PointTree tree(before, solved);
    const double reach2 = std::pow(options_.reach_voxels * h_, 2);
    const Points correction = x - before;
    parallel_for(0, n, kVertexGrain, [&](std::size_t b, std::size_t e) {
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
  std::size_t followed = 0;
  for (std::size_t a = 0; a < n; ++a) followed += !fixed[a] && !fr[a] && !anchored_kept[a];
  return followed;
}

// Beyond the paper: the solution on irregular agents carries agent-scale noise
// in its displacement (each h is exact only for its own original ring), which
// the reconstruction shows as waviness. A few Jacobi passes move each free
// agent's displacement (from the state its vertices are re-emitted from)
// halfway to its ring's mean: fixed and anchored agents stay, A = B stays
// exact (zero displacement), and the result is the same for any thread count.
void SurfaceBinding::smooth_displacements(const Points& before, const std::vector<std::uint8_t>& fr, Points& x) const {
  const std::size_t n = agent_count();
  for (int pass = 0; pass < options_.smooth_passes; ++pass) {
    const Points d = x - (options_.emit_from_original && !options_.encode_on_warped ? original_agents_ : before);
    Points nx = x;
    parallel_for(0, n, kVertexGrain, [&](std::size_t b, std::size_t e) {
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
}

// emit_from_original (beyond the paper, which re-emits the warped vertices from
// the warped agents' frames): each vertex keeps its original offsets to its
// agents, turned by the agents' rotations from the original to the result.
// The warp's own detail finer than the agent spacing (its creases where the
// body's triangles change) is then replaced by the garment's original detail,
// which is what this step restores; coarser warp changes live in the agents.
// With encode_on_warped the target shape is the warp's, so its detail stays.
// Anchored agents that had no solved agent within reach hand their vertices back as warped.
std::vector<Eigen::Matrix3d> SurfaceBinding::rotations(const Points& before, const Points& x,
                                                       const std::vector<Eigen::Matrix3d>& stretch) const {
  const bool orig = options_.emit_from_original && !options_.encode_on_warped;
  const Points& from = orig ? original_agents_ : before;
  std::vector<Eigen::Matrix3d> rot;
  if (options_.fit_rotations) {
    rot = ring_rotations(from, x, ring_);
  } else {
    rot = frame_rotations(agent_frames(from, ring_, ring_open_, flip_), agent_frames(x, ring_, ring_open_, flip_));
  }
  // The original offsets to the agents stretch as the encoding did.
  if (orig && !stretch.empty())
    for (std::size_t a = 0; a < rot.size(); ++a) rot[a] = rot[a] * stretch[a];
  return rot;
}

Points SurfaceBinding::emit_vertices(const AgentSolution& sol, const Points& original, const Points& warped,
                                     const VertexBlends& blends, std::span<const std::uint8_t> carries_feature,
                                     const NearBody& near_body_b, std::vector<float>& held,
                                     SurfaceStats& stats) const {
  held.clear();
  if (agent_count() == 0) return warped;
  const bool orig = options_.emit_from_original && !options_.encode_on_warped;
  Points out = reconstruct_rotations(orig ? original : warped, orig ? original_agents_ : sol.before, sol.x, sol.rotation,
                                     blends.reach, blends.weight, blends.nearest, sol.keep, &warped);
  if (options_.keep_near_vertices) {
    held = keep_near_vertices(sol, warped, blends, carries_feature, near_body_b, out);
    stats.vertices_kept += std::size_t(std::count(held.begin(), held.end(), 1.0f));
  }
  return out;
}

// Eq. 14 for the vertices too: blending frames of nearby free agents must not
// pull a vertex that touches the body. Only vertices the nearest agent's
// distance cannot rule out are queried: d(v) >= d(a) - |v - a|. Next to the
// feature zone a vertex takes the warp only by its blend's share outside the
// zone (SurfaceOptions::zone_edge_blend): the blend weights vary smoothly with
// the vertex, so the zone's edge is a slope at any mesh resolution. Beside the
// features it takes the warp only by its blend's share of what the slid agents
// do not keep (SurfaceOptions::feature_slide_rings).
std::vector<float> SurfaceBinding::keep_near_vertices(const AgentSolution& sol, const Points& warped,
                                                      const VertexBlends& blends,
                                                      std::span<const std::uint8_t> carries_feature,
                                                      const NearBody& near_body_b, Points& positions) const {
  const std::size_t nv = static_cast<std::size_t>(warped.rows());
  const Points& before = sol.before;
  const std::vector<double>& body_distance = sol.body_distance;
  const bool zone = !near_feature_.empty();
  const double blend = options_.zone_edge_blend;
  const bool eased = zone && blend > 0.0 && !blends.weight.empty();
  // How much of the warp vertex v takes: all or nothing by its nearest agent, or eased by its share outside the zone.
  const auto warp_share = [&](std::size_t v) {
    if (!eased) return zone && near_feature_[blends.nearest[v]] ? 0.0 : 1.0;
    double outside = 0.0;
    for (std::size_t j = blends.reach.offsets[v]; j < blends.reach.offsets[v + 1]; ++j)
      if (!near_feature_[blends.reach.indices[j]]) outside += blends.weight[j];
    if (outside >= 0.5 + blend - 1e-6) return 1.0;  // the weights' float sum: all outside is all
    const double t = std::clamp((outside - (0.5 - blend)) / (2.0 * blend), 0.0, 1.0);
    return smoothstep(t);
  };
  // How much of the agents' solution v keeps beside the features (feature_slide_rings): its blend's share of it.
  const auto slide_share = [&](std::size_t v) {
    if (sol.slide.empty()) return 0.0;
    if (blends.weight.empty()) return double(sol.slide[blends.nearest[v]]);
    double kept = 0.0;
    for (std::size_t j = blends.reach.offsets[v]; j < blends.reach.offsets[v + 1]; ++j)
      kept += blends.weight[j] * double(sol.slide[blends.reach.indices[j]]);
    return std::clamp(kept, 0.0, 1.0);
  };
  std::vector<float> held(nv, 0.0f);
  parallel_for(0, nv, 1024, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      const Index a = blends.nearest[v];
      if (zone && carries_feature[v]) continue;
      const bool slides = !sol.slide.empty() && sol.slide[a] > 0.0f;
      if (!sol.banded.empty() && sol.banded[a] && !slides) continue;
      const Vec3 p = row3(warped, Index(v));
      if (feature_of_[a] < 0 && body_distance[a] - (p - row3(before, a)).norm() >= options_.epsilon) continue;
      const double share = warp_share(v) * (1.0 - slide_share(v));
      if (!(share > 0.0) || !near_body_b(p)) continue;
      if (share < 1.0)
        positions.row(Eigen::Index(v)) += share * (warped.row(Eigen::Index(v)) - positions.row(Eigen::Index(v)));
      else
        positions.row(Eigen::Index(v)) = warped.row(Eigen::Index(v));
      held[v] = float(share);
    }
  });
  return held;
}

}  // namespace refit
