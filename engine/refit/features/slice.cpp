#include <refit/features/slice.hpp>

#include <refit/core/parallel.hpp>
#include <refit/core/weld.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <unordered_map>

namespace refit {
namespace {

struct Segment {
  Vec3 a, b;
};

bool lex_less(const Points& p, Index i, Index j) {
  for (int c = 0; c < 3; ++c) {
    if (p(i, c) != p(j, c)) return p(i, c) < p(j, c);
  }
  return i < j;
}

// Crossing point of edge (i, j), computed from the endpoints in coordinate order
// so the same geometric edge always gives the same bits.
Vec3 crossing(const Points& p, const std::vector<double>& s, Index i, Index j) {
  if (lex_less(p, j, i)) std::swap(i, j);
  const double t = s[i] / (s[i] - s[j]);
  return row3(p, i) + t * (row3(p, j) - row3(p, i));
}


}  // namespace



SliceResult slice_garment(const Garment& g, const FeaturePlane& plane, double weld_tolerance) {
  const Points& P = g.positions;
  const std::size_t n = g.vertex_count();
  if (!(weld_tolerance > 0.0)) weld_tolerance = 1e-6 * bounding_box_diagonal(P);
  std::vector<double> s(n);
  parallel_for(0, n, 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) s[i] = plane.signed_distance(row3(P, static_cast<Index>(i)));
  });
  auto above = [&](Index i) { return s[i] >= 0.0; };

  // The segments in face order, whatever the thread count.
  const std::vector<Segment> segments =
      gather_in_blocks<Segment>(g.faces.rows(), 1 << 13, [&](std::size_t first, std::size_t last, std::vector<Segment>& out) {
        std::vector<std::pair<double, Vec3>> cuts;
        for (std::size_t f = first; f < last; ++f) {
          const auto row = g.faces.row(f);
          const std::size_t k = row.size();
          bool any_up = false, any_down = false;
          for (Index v : row) (above(v) ? any_up : any_down) = true;
          if (!(any_up && any_down)) continue;
          cuts.clear();
          for (std::size_t c = 0; c < k; ++c) {
            const Index a = row[c], bb = row[(c + 1) % k];
            if (above(a) != above(bb)) cuts.emplace_back(0.0, crossing(P, s, a, bb));
          }
          if (cuts.size() > 2) {
            // Non-convex polygon: order the crossings along the cut line (plane
            // normal x Newell face normal) and pair them up.
            Vec3 fn = Vec3::Zero();
            for (std::size_t c = 0; c < k; ++c) fn += row3(P, row[c]).cross(row3(P, row[(c + 1) % k]));
            const Vec3 dir = plane.normal.cross(fn);
            for (auto& [key, q] : cuts) key = dir.dot(q);
            std::stable_sort(cuts.begin(), cuts.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
          }
          for (std::size_t c = 0; c + 1 < cuts.size(); c += 2) out.push_back({cuts[c].second, cuts[c + 1].second});
        }
      });

  SliceResult result;
  // Hanging edges cross in single points.
  std::vector<Vec3> lp;
  for (std::size_t r = 0; r < g.lines.rows(); ++r) {
    const auto row = g.lines.row(r);
    for (std::size_t c = 0; c + 1 < row.size(); ++c)
      if (above(row[c]) != above(row[c + 1])) lp.push_back(crossing(P, s, row[c], row[c + 1]));
  }
  result.line_points.resize(static_cast<Eigen::Index>(lp.size()), 3);
  for (std::size_t i = 0; i < lp.size(); ++i) result.line_points.row(static_cast<Eigen::Index>(i)) = lp[i].transpose();

  const std::size_t total = segments.size();
  Points ends(static_cast<Eigen::Index>(2 * total), 3);
  for (std::size_t i = 0; i < total; ++i) {
    ends.row(Eigen::Index(2 * i)) = segments[i].a.transpose();
    ends.row(Eigen::Index(2 * i + 1)) = segments[i].b.transpose();
  }
  const std::vector<Index> rep = weld_points(ends, weld_tolerance);
  // Node ids in order of first appearance.
  std::vector<Index> node_of(rep.size());
  std::vector<Index> node_point;
  {
    std::vector<Index> id(rep.size(), ~Index(0));
    for (std::size_t i = 0; i < rep.size(); ++i) {
      if (id[rep[i]] == ~Index(0)) {
        id[rep[i]] = static_cast<Index>(node_point.size());
        node_point.push_back(rep[i]);
      }
      node_of[i] = id[rep[i]];
    }
  }
  // Segments between distinct nodes, duplicates (coincident faces) once.
  std::vector<std::pair<Index, Index>> segs;
  segs.reserve(total);
  for (std::size_t i = 0; i < total; ++i) {
    Index a = node_of[2 * i], b = node_of[2 * i + 1];
    if (a == b) continue;
    segs.emplace_back(std::min(a, b), std::max(a, b));
  }
  std::sort(segs.begin(), segs.end());
  segs.erase(std::unique(segs.begin(), segs.end()), segs.end());
  result.segments = segs.size();

  const std::size_t nodes = node_point.size();
  std::vector<Index> deg_off(nodes + 1, 0), adj(2 * segs.size());
  for (const auto& [a, b] : segs) ++deg_off[a + 1], ++deg_off[b + 1];
  for (std::size_t i = 0; i < nodes; ++i) deg_off[i + 1] += deg_off[i];
  {
    std::vector<Index> fill(deg_off.begin(), deg_off.end() - 1);
    for (std::size_t k = 0; k < segs.size(); ++k) {
      adj[fill[segs[k].first]++] = static_cast<Index>(k);
      adj[fill[segs[k].second]++] = static_cast<Index>(k);
    }
  }
  auto pos = [&](Index node) { return row3(ends, node_point[node]); };
  auto other = [&](Index sg, Index node) { return segs[sg].first == node ? segs[sg].second : segs[sg].first; };
  // At every node, pair the incident segments that continue each other: the two
  // of a plain node, and at a non-manifold junction greedily the straightest
  // pairs, so a flap branches off and the main curve runs through.
  constexpr Index kNone = ~Index(0);
  std::vector<Index> partner(adj.size(), kNone);  // per adjacency slot: the continuing segment
  {
    std::vector<std::tuple<double, Index, Index>> pairs;
    for (Index v = 0; v < nodes; ++v) {
      const Index b0 = deg_off[v], b1 = deg_off[v + 1];
      if (b1 - b0 == 2) {
        partner[b0] = adj[b0 + 1];
        partner[b0 + 1] = adj[b0];
      } else if (b1 - b0 > 2) {
        pairs.clear();
        for (Index x = b0; x < b1; ++x)
          for (Index y = x + 1; y < b1; ++y) {
            const Vec3 dx = (pos(other(adj[x], v)) - pos(v)).normalized();
            const Vec3 dy = (pos(other(adj[y], v)) - pos(v)).normalized();
            pairs.emplace_back(dx.dot(dy), x, y);
          }
        std::sort(pairs.begin(), pairs.end());
        for (const auto& [d, x, y] : pairs)
          if (partner[x] == kNone && partner[y] == kNone) partner[x] = adj[y], partner[y] = adj[x];
      }
    }
  }
  auto next_segment = [&](Index node, Index sg) {
    for (Index k = deg_off[node]; k < deg_off[node + 1]; ++k)
      if (adj[k] == sg) return partner[k];
    return kNone;
  };
  std::vector<std::uint8_t> used(segs.size(), 0);
  auto walk = [&](Index start, Index sg) {
    std::vector<Index> chain{start};
    Index cur = start;
    bool closed = false;
    for (;;) {
      used[sg] = 1;
      const Index next = other(sg, cur);
      const Index nsg = next_segment(next, sg);
      if (next == start && nsg != kNone && used[nsg]) {
        closed = chain.size() >= 3;
        if (!closed) chain.push_back(next);
        break;
      }
      chain.push_back(next);
      if (nsg == kNone || used[nsg]) break;
      cur = next;
      sg = nsg;
    }
    SlicePiece piece;
    piece.closed = closed;
    piece.points.resize(static_cast<Eigen::Index>(chain.size()), 3);
    for (std::size_t i = 0; i < chain.size(); ++i) piece.points.row(static_cast<Eigen::Index>(i)) = pos(chain[i]).transpose();
    result.pieces.push_back(std::move(piece));
  };
  // Open chains from their unpaired ends first, then what is left is loops.
  for (Index v = 0; v < nodes; ++v)
    for (Index k = deg_off[v]; k < deg_off[v + 1]; ++k)
      if (partner[k] == kNone && !used[adj[k]]) walk(v, adj[k]);
  for (Index v = 0; v < nodes; ++v)
    for (Index k = deg_off[v]; k < deg_off[v + 1]; ++k)
      if (!used[adj[k]]) walk(v, adj[k]);
  return result;
}

}  // namespace refit
