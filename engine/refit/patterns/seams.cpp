// Chaining cut edges into seams: per pair of panels, walks from the ends of each
// chain (vertices where one or three or more cut edges meet), then around the
// closed chains that are left.
#include <refit/patterns/seams.hpp>

#include <algorithm>
#include <map>

namespace refit {
namespace {

// One side of a cut edge: its panel and the panel vertices at x and y.
struct Side {
  Index panel;
  std::array<Index, 2> v;
};

struct CutEdge {
  std::array<Index, 2> x;  // garment vertices
  std::array<Side, 2> side;
};

}  // namespace

std::vector<Seam> chain_seams(const PanelSet& set, std::span<const SeamCorners> cut) {
  // Group the cut edges by their (unordered) pair of panels.
  std::map<std::pair<Index, Index>, std::vector<CutEdge>> groups;
  for (const SeamCorners& c : cut) {
    CutEdge e;
    for (int s = 0; s < 2; ++s) {
      const Index panel = set.face_panel[c.face[s]];
      e.side[s] = {panel, {set.corner_vertex[c.corner[s][0]], set.corner_vertex[c.corner[s][1]]}};
    }
    if (e.side[0].panel == e.side[1].panel && e.side[0].v == e.side[1].v) continue;  // did not open
    if (e.side[0].panel > e.side[1].panel) std::swap(e.side[0], e.side[1]);
    const Panel& p = set.panels[e.side[0].panel];
    e.x = {p.vertices[e.side[0].v[0]], p.vertices[e.side[0].v[1]]};
    groups[{e.side[0].panel, e.side[1].panel}].push_back(e);
  }

  std::vector<Seam> seams;
  for (auto& group : groups) {
    auto& edges = group.second;  // not a structured binding: clang 14 cannot capture one (fuzz preset)
    std::map<Index, std::vector<Index>> at;  // garment vertex -> its cut edges
    for (Index i = 0; i < edges.size(); ++i)
      for (Index x : edges[i].x) at[x].push_back(i);
    std::vector<char> used(edges.size(), 0);
    const auto degree = [&](Index x) { return at[x].size(); };
    // Walks from garment vertex `start` along edge `first`; side 0 of the chain is edge first's side 0.
    const auto walk = [&](Index first, Index start) {
      Seam s;
      Index e = first, from = start;
      int a = 0;  // which side of edge e continues the chain's side 0
      while (true) {
        used[e] = 1;
        const CutEdge& ce = edges[e];
        const int k = ce.x[0] == from ? 0 : 1;  // index of `from` in the edge
        if (s.garment_path.empty()) {
          s.panel = {ce.side[a].panel, ce.side[1 - a].panel};
          s.garment_path.push_back(from);
          s.path[0].push_back(ce.side[a].v[k]);
          s.path[1].push_back(ce.side[1 - a].v[k]);
        }
        const Index to = ce.x[1 - k];
        s.garment_path.push_back(to);
        s.path[0].push_back(ce.side[a].v[1 - k]);
        s.path[1].push_back(ce.side[1 - a].v[1 - k]);
        if (degree(to) != 2) break;
        const Index next = at[to][0] == e ? at[to][1] : at[to][0];
        if (used[next]) break;
        // The next edge's side that shares the chain's side-0 vertex at `to`.
        const CutEdge& ne = edges[next];
        const int kn = ne.x[0] == to ? 0 : 1;
        const Index mine = s.path[0].back();
        int an = -1;
        for (int c = 0; c < 2; ++c)
          if (ne.side[c].panel == s.panel[0] && ne.side[c].v[kn] == mine) an = c;
        if (an < 0) break;
        e = next, from = to, a = an;
      }
      seams.push_back(std::move(s));
    };
    for (Index i = 0; i < edges.size(); ++i)
      for (Index end : edges[i].x)
        if (!used[i] && degree(end) != 2) walk(i, end);
    for (Index i = 0; i < edges.size(); ++i)
      if (!used[i]) walk(i, edges[i].x[0]);
  }
  return seams;
}

}  // namespace refit
