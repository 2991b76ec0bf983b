// Seam curves to garment edge paths: Dijkstra in a corridor around the curve.
#include <refit/patterns/seam_paths.hpp>

#include <refit/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

namespace refit {
namespace {

// Face-edge adjacency (CSR, both directions, sorted, no duplicates).
Csr face_edge_adjacency(const Garment& g) {
  std::vector<std::array<Index, 2>> pairs;
  const Csr& f = g.faces;
  for (std::size_t r = 0; r < f.rows(); ++r) {
    const auto row = f.row(r);
    for (std::size_t k = 0; k < row.size(); ++k) {
      const Index a = row[k], b = row[(k + 1) % row.size()];
      if (a == b) continue;
      pairs.push_back({a, b});
      pairs.push_back({b, a});
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  Csr adj;
  adj.offsets.assign(g.vertex_count() + 1, 0);
  for (const auto& p : pairs) ++adj.offsets[p[0] + 1];
  for (std::size_t v = 0; v < g.vertex_count(); ++v) adj.offsets[v + 1] += adj.offsets[v];
  adj.indices.resize(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) adj.indices[i] = pairs[i][1];
  return adj;
}

double median_edge_length(const Garment& g, const Csr& adj) {
  std::vector<double> len;
  for (std::size_t v = 0; v < g.vertex_count(); ++v)
    for (Index w : adj.row(v))
      if (w > v) len.push_back((g.positions.row(v) - g.positions.row(w)).norm());
  if (len.empty()) return 0.0;
  std::nth_element(len.begin(), len.begin() + static_cast<std::ptrdiff_t>(len.size() / 2), len.end());
  return len[len.size() / 2];
}

double distance_to_polyline(const Vec3& p, const Points& c, std::size_t first, std::size_t last) {
  double best = std::numeric_limits<double>::infinity();
  const std::size_t m = static_cast<std::size_t>(c.rows());
  for (std::size_t i = first; i < last; ++i) {
    const Vec3 a = row3(c, static_cast<Index>(i % m)), b = row3(c, static_cast<Index>((i + 1) % m));
    const Vec3 ab = b - a;
    const double t = ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    best = std::min(best, (p - a - t * ab).norm());
  }
  if (first == last) best = (p - row3(c, static_cast<Index>(first % m))).norm();
  return best;
}

class PathFinder {
 public:
  PathFinder(const Garment& g, std::span<const char> ends)
      : g_(g), ends_(ends), adj_(face_edge_adjacency(g)), h_(median_edge_length(g, adj_)) {}

  double h() const { return h_; }

  // The vertex for a curve end: the nearest one, or the nearest seam end within 2 h.
  Index snap(const Vec3& p, bool to_ends) const {
    Index best = 0, best_end = kNone;
    double d = std::numeric_limits<double>::infinity(), d_end = 2 * h_;
    for (Index v = 0; v < g_.vertex_count(); ++v) {
      if (adj_.row_size(v) == 0) continue;
      const double dv = (g_.positions.row(v).transpose() - p).norm();
      if (dv < d) d = dv, best = v;
      if (to_ends && v < ends_.size() && ends_[v] && dv <= d_end) d_end = dv, best_end = v;
    }
    return best_end != kNone ? best_end : best;
  }

  // Shortest path from s to t near samples [first, last] of curve c.
  std::vector<Index> path(Index s, Index t, const Points& c, std::size_t first, std::size_t last) const {
    const std::size_t n = g_.vertex_count();
    std::vector<double> dist(n, std::numeric_limits<double>::infinity()), near(n, -1.0);
    std::vector<Index> from(n, kNone);
    const auto closeness = [&](Index v) {
      if (near[v] < 0) near[v] = distance_to_polyline(row3(g_.positions, v), c, first, last);
      return near[v];
    };
    using Item = std::pair<double, Index>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    dist[s] = 0;
    queue.push({0.0, s});
    while (!queue.empty()) {
      const auto [d, v] = queue.top();
      queue.pop();
      if (d > dist[v]) continue;
      if (v == t) break;
      for (Index w : adj_.row(v)) {
        if (closeness(w) > 4 * h_ && w != t) continue;
        const Vec3 a = row3(g_.positions, v), b = row3(g_.positions, w);
        const double dm = distance_to_polyline(0.5 * (a + b), c, first, last) / h_;
        const double nd = d + (a - b).norm() * (1 + 4 * dm * dm);
        if (nd < dist[w]) {
          dist[w] = nd, from[w] = v;
          queue.push({nd, w});
        }
      }
    }
    if (s != t && from[t] == kNone) return {};
    std::vector<Index> out{t};
    while (out.back() != s) out.push_back(from[out.back()]);
    std::reverse(out.begin(), out.end());
    return out;
  }

  const Garment& garment() const { return g_; }

 private:
  static constexpr Index kNone = 0xffffffffu;
  const Garment& g_;
  std::span<const char> ends_;
  Csr adj_;
  double h_;
};

}  // namespace

std::vector<SeamPath> seam_paths(const Garment& g, std::span<const FeatureCurve> seams, std::span<const char> ends,
                                 const std::string& file) {
  std::vector<SeamPath> out;
  if (seams.empty()) return out;
  const PathFinder finder(g, ends);
  for (const FeatureCurve& c : seams) {
    SeamPath sp;
    sp.name = c.name;
    sp.closed = c.closed;
    const std::size_t m = c.size();
    // Anchors along the curve; a closed curve goes around through three.
    std::vector<std::size_t> anchors = c.closed ? std::vector<std::size_t>{0, m / 3, 2 * m / 3, m}
                                                : std::vector<std::size_t>{0, m - 1};
    std::vector<Index> at;
    for (std::size_t k = 0; k < anchors.size(); ++k) {
      const bool end = !c.closed && (k == 0 || k + 1 == anchors.size());
      at.push_back(finder.snap(row3(c.samples, static_cast<Index>(anchors[k] % m)), end));
    }
    for (std::size_t k = 0; k + 1 < anchors.size(); ++k) {
      const std::vector<Index> piece = finder.path(at[k], at[k + 1], c.samples, anchors[k], anchors[k + 1]);
      if (piece.empty())
        throw input_error(file, "feature '" + c.name + "': no path of garment edges follows the seam curve "
                                "(it crosses a gap between pieces?)");
      sp.vertices.insert(sp.vertices.end(), piece.begin() + (sp.vertices.empty() ? 0 : 1), piece.end());
    }
    if (c.closed && sp.vertices.size() > 1 && sp.vertices.back() == sp.vertices.front()) sp.vertices.pop_back();
    if (sp.vertices.size() < 2)
      throw input_error(file, "feature '" + c.name + "': the seam curve is shorter than one garment edge");
    for (Index v : sp.vertices)
      sp.deviation = std::max(sp.deviation, distance_to_polyline(row3(g.positions, v), c.samples, 0,
                                                                 c.closed ? m : m - 1));
    out.push_back(std::move(sp));
  }
  return out;
}

std::vector<std::array<Index, 2>> seam_path_edges(std::span<const SeamPath> paths) {
  std::vector<std::array<Index, 2>> edges;
  for (const SeamPath& p : paths) {
    for (std::size_t i = 0; i + 1 < p.vertices.size(); ++i) edges.push_back({p.vertices[i], p.vertices[i + 1]});
    if (p.closed && p.vertices.size() > 2) edges.push_back({p.vertices.back(), p.vertices.front()});
  }
  return edges;
}

}  // namespace refit
