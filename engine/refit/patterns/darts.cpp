// Automatic darts; see darts.hpp.
#include <refit/patterns/darts.hpp>

#include <refit/io/obj_attributes.hpp>
#include <refit/patterns/lengths.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

namespace refit {
namespace {

using Edge = std::array<Index, 2>;
constexpr Index kNone = std::numeric_limits<Index>::max();
constexpr double kInf = std::numeric_limits<double>::infinity();

Edge sorted(Index a, Index b) { return a < b ? Edge{a, b} : Edge{b, a}; }

// Garment edges of one face only: where the garment itself ends (sorted).
std::vector<Edge> free_edges(const Garment& g) {
  std::vector<Edge> all;
  for (Index f = 0; f < g.faces.rows(); ++f) {
    const auto row = g.faces.row(f);
    for (std::size_t i = 0; i < row.size(); ++i)
      if (row[i] != row[(i + 1) % row.size()]) all.push_back(sorted(row[i], row[(i + 1) % row.size()]));
  }
  std::sort(all.begin(), all.end());
  std::vector<Edge> once;
  for (std::size_t i = 0; i < all.size();) {
    std::size_t j = i;
    while (j < all.size() && all[j] == all[i]) ++j;
    if (j - i == 1) once.push_back(all[i]);
    i = j;
  }
  return once;
}

// A panel's face edges (not the fan diagonals) with their 3D lengths, and per
// vertex the area-weighted stretch of its faces.
struct PanelGraph {
  std::vector<std::vector<std::pair<Index, double>>> next;
  std::vector<double> score;
  std::vector<char> boundary;
};

PanelGraph panel_graph(const Garment& g, const PanelSet& set, std::size_t k, const std::vector<double>& face_stretch) {
  const Panel& p = set.panels[k];
  const Points& x = g.positions;
  const std::size_t n = p.vertices.size();
  PanelGraph out;
  out.next.resize(n);
  out.score.assign(n, 0.0);
  out.boundary.assign(n, 0);
  std::vector<double> weight(n, 0.0);
  std::vector<Edge> edges;
  for (std::size_t i = 0; i < p.faces.size(); ++i) {
    const Index f = p.faces[i], c0 = g.faces.offsets[f], m = static_cast<Index>(g.faces.row_size(f));
    const Vec3 o = row3(x, g.faces.indices[c0]);
    double area = 0;
    for (Index j = 1; j + 1 < m; ++j)
      area += 0.5 * (row3(x, g.faces.indices[c0 + j]) - o).cross(row3(x, g.faces.indices[c0 + j + 1]) - o).norm();
    for (Index j = 0; j < m; ++j) {
      const Index a = set.corner_vertex[c0 + j], b = set.corner_vertex[c0 + (j + 1) % m];
      out.score[a] += area * face_stretch[i];
      weight[a] += area;
      if (a != b) edges.push_back(sorted(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  for (const Edge& e : edges) {
    const double len = (row3(x, p.vertices[e[0]]) - row3(x, p.vertices[e[1]])).norm();
    out.next[e[0]].emplace_back(e[1], len);
    out.next[e[1]].emplace_back(e[0], len);
  }
  for (std::size_t v = 0; v < n; ++v)
    if (weight[v] > 0) out.score[v] /= weight[v];
  for (const auto& loop : p.loops)
    for (Index v : loop) out.boundary[v] = 1;
  return out;
}

// Distance along the panel's edges from the `source` vertices.
std::vector<double> distances(const PanelGraph& graph, const std::vector<char>& source) {
  std::vector<double> d(graph.next.size(), kInf);
  using Item = std::pair<double, Index>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> q;
  for (Index v = 0; v < source.size(); ++v)
    if (source[v]) q.emplace(d[v] = 0.0, v);
  while (!q.empty()) {
    const auto [dv, v] = q.top();
    q.pop();
    if (dv > d[v]) continue;
    for (const auto& [w, len] : graph.next[v])
      if (dv + len < d[w]) q.emplace(d[w] = dv + len, w);
  }
  return d;
}

// The best dart of panel k (garment vertices from the waistline to the apex;
// empty when no path gains): see darts.hpp.
std::vector<Index> best_dart(const Garment& g, const PanelSet& set, std::size_t k, const std::vector<double>& face_stretch,
                             const std::vector<Edge>& free, const Vec3& up, double target) {
  const Panel& p = set.panels[k];
  const PanelGraph graph = panel_graph(g, set, k, face_stretch);
  const std::size_t n = p.vertices.size();
  std::vector<double> h(n);
  for (std::size_t v = 0; v < n; ++v) h[v] = row3(g.positions, p.vertices[v]).dot(up);
  const double top = *std::max_element(h.begin(), h.end()), span = top - *std::min_element(h.begin(), h.end());
  const auto is_free = [&](Index a, Index b) {
    return std::binary_search(free.begin(), free.end(), sorted(p.vertices[a], p.vertices[b]));
  };
  // The waistline: vertices whose two outline edges are the garment's own edge, in the top fifth.
  std::vector<char> waist(n, 0), blocked(n, 0);
  for (const auto& loop : p.loops)
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const Index a = loop[i], before = loop[(i + loop.size() - 1) % loop.size()], after = loop[(i + 1) % loop.size()];
      waist[a] = is_free(before, a) && is_free(a, after) && h[a] >= top - 0.2 * span;
    }
  for (std::size_t v = 0; v < n; ++v) blocked[v] = graph.boundary[v] && !waist[v];
  // Darts keep clear of the piece's seams, its hem and each other.
  // Measured on the shared skirt: darts of up to half the piece's height
  // reach a p95 of 0.0285, of up to a third (about 26 cm, ending above the
  // hips, as a pattern maker's) 0.034; the shorter ones are kept.
  // Darts shorter than a tenth of the piece's height are nicks (on the suit's tabs).
  const double clearance = 0.06 * span, longest = 0.35 * span, shortest = 0.1 * span;
  const std::vector<double> clear = distances(graph, blocked);

  std::vector<double> cost(n, kInf), gain(n, -kInf), length(n, 0.0);
  std::vector<Index> parent(n, kNone);
  using Item = std::pair<double, Index>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> q;
  for (Index v = 0; v < n; ++v)
    if (waist[v] && clear[v] >= clearance) {
      cost[v] = gain[v] = 0.0;
      q.emplace(0.0, v);
    }
  while (!q.empty()) {
    const auto [cv, v] = q.top();
    q.pop();
    if (cv > cost[v]) continue;
    for (const auto& [w, len] : graph.next[v]) {
      if (graph.boundary[w] || clear[w] < clearance || length[v] + len > longest) continue;
      const double rise = h[w] - h[v];
      if (rise > 0.25 * len) continue;  // a dart runs down from the waist
      const double c = cv + len + 4.0 * std::sqrt(std::max(0.0, len * len - rise * rise));
      if (c >= cost[w]) continue;
      cost[w] = c;
      parent[w] = v;
      length[w] = length[v] + len;
      gain[w] = gain[v] + (graph.score[w] - target) * len;
      q.emplace(c, w);
    }
  }
  Index apex = kNone;
  for (Index v = 0; v < n; ++v)
    if (parent[v] != kNone && gain[v] > 0 && length[v] >= shortest && (apex == kNone || gain[v] > gain[apex])) apex = v;
  std::vector<Index> path;
  for (Index v = apex; v != kNone; v = parent[v]) path.push_back(p.vertices[v]);
  std::reverse(path.begin(), path.end());
  return path;
}

// Cuts the original along its seam curves and darts.
PanelSet cut_with_darts(const Garment& original, const ObjFaceAttributes& at, const PatternCut& cut) {
  std::vector<Edge> edges = seam_path_edges(cut.seam_paths);
  for (const Dart& d : cut.darts)
    for (std::size_t i = 0; i + 1 < d.garment_path.size(); ++i) edges.push_back({d.garment_path[i], d.garment_path[i + 1]});
  return cut_panels(original, at, edges);
}

bool same_panels(const PanelSet& a, const PanelSet& b) {
  if (a.panels.size() != b.panels.size()) return false;
  for (std::size_t k = 0; k < a.panels.size(); ++k)
    if (a.panels[k].faces != b.panels[k].faces) return false;
  return true;
}

}  // namespace

Pattern cut_darts(const Garment& original, PatternCut& cut, const PatternOptions& options, const DartOptions& darts) {
  Pattern pattern = flatten_pattern(original, cut, original.positions, options);
  if (darts.max_stretch <= 0) return pattern;
  const std::vector<Edge> free = free_edges(original);
  const ObjFaceAttributes at = obj_face_attributes(original);
  std::vector<int> count(cut.panels.panels.size(), 0);
  while (true) {
    PatternCut next = cut;
    for (std::size_t k = 0; k < cut.panels.panels.size(); ++k) {
      const PatternPiece& piece = pattern.pieces[k];
      if (!piece.flattened || piece.measures.stretch_p95 <= darts.max_stretch || count[k] >= darts.max_per_panel) continue;
      std::vector<Index> path = best_dart(original, cut.panels, k, piece.face_stretch, free, options.up, darts.max_stretch);
      if (path.size() < 2) {
        count[k] = darts.max_per_panel;  // nowhere to cut: the piece is done
        continue;
      }
      const double len = indexed_length(original.positions, path, false);
      next.darts.push_back({static_cast<Index>(k), std::move(path), len});
    }
    if (next.darts.size() == cut.darts.size()) break;
    next.panels = cut_with_darts(original, at, next);
    if (!same_panels(next.panels, cut.panels)) break;  // a dart would split a piece (cannot by construction): stop
    Pattern again = flatten_pattern(original, next, original.positions, options);
    for (std::size_t i = cut.darts.size(); i < next.darts.size(); ++i) ++count[next.darts[i].panel];
    cut = std::move(next);
    pattern = std::move(again);
  }
  return pattern;
}

long dart_seam(const PatternCut& cut, const Dart& dart) {
  for (std::size_t i = 0; i < cut.panels.seams.size(); ++i) {
    const Seam& s = cut.panels.seams[i];
    if (s.panel[0] != dart.panel || s.panel[1] != dart.panel) continue;
    if (s.garment_path == dart.garment_path ||
        std::equal(s.garment_path.rbegin(), s.garment_path.rend(), dart.garment_path.begin(), dart.garment_path.end()))
      return static_cast<long>(i);
  }
  return -1;
}

}  // namespace refit
