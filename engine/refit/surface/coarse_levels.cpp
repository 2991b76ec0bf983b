#include <refit/core/parallel.hpp>
#include <refit/surface/agents.hpp>
#include <refit/surface/coarse_levels.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <tuple>

namespace refit {

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

OrderedAgents order_agents(const Points& natural, const std::vector<std::uint64_t>& morton,
                           const std::vector<std::uint32_t>& layer, double radius, double min_width) {
  OrderedAgents o;
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

namespace {

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

std::vector<CoarseLevel> build_coarse_levels(const Points& agents, const std::vector<std::uint32_t>& layer,
                                             const std::vector<std::int32_t>& feature_of, double h, int max_levels,
                                             std::size_t min_agents, double ring_radius_voxels, double block_voxels) {
  std::vector<CoarseLevel> levels;
  const std::size_t n = static_cast<std::size_t>(agents.rows());
  std::vector<Index> finer_agents(n);
  std::iota(finer_agents.begin(), finer_agents.end(), Index{0});
  for (int l = 1; l <= max_levels && finer_agents.size() / 4 >= min_agents; ++l) {
    const double hl = h * std::ldexp(1.0, l);
    const std::size_t nfin = finer_agents.size();
    Points pf(static_cast<Eigen::Index>(nfin), 3);
    for (std::size_t k = 0; k < nfin; ++k) pf.row(Eigen::Index(k)) = agents.row(finer_agents[k]);
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
      finer_layer[k] = layer[finer_agents[k]];
      keys[k] = Key{VoxelGrid::morton(c), finer_layer[k], feature_of[finer_agents[k]] >= 0 ? 0 : 1,
                    (p - cg.centre(c)).squaredNorm(), Index(k)};
    }
    std::sort(keys.begin(), keys.end());
    std::vector<Index> kept;  // indices into finer_agents
    std::vector<std::uint64_t> kept_voxel;
    std::vector<std::uint32_t> kept_layer;
    for (std::size_t i = 0; i < nfin; ++i) {
      const bool first = i == 0 || keys[i].voxel != keys[i - 1].voxel || keys[i].layer != keys[i - 1].layer;
      if (keys[i].garment == 0 || first) {
        kept.push_back(keys[i].k);
        kept_voxel.push_back(keys[i].voxel);
        kept_layer.push_back(keys[i].layer);
      }
    }
    if (kept.size() * 4 > nfin * 3) break;  // hardly coarser: no use
    Points natural_l(static_cast<Eigen::Index>(kept.size()), 3);
    for (std::size_t i = 0; i < kept.size(); ++i) natural_l.row(Eigen::Index(i)) = pf.row(kept[i]);
    OrderedAgents ol = order_agents(natural_l, kept_voxel, kept_layer, ring_radius_voxels * hl, block_voxels * hl);
    CoarseLevel lv;
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
    levels.push_back(std::move(lv));
  }
  return levels;
}

}  // namespace refit
