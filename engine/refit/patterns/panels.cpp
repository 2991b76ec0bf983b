// Cutting a garment into panels: faces joined across uncut manifold edges, and
// per garment vertex one panel vertex per fan of corners joined the same way.
#include <refit/patterns/panels.hpp>

#include <refit/patterns/seams.hpp>

#include <algorithm>
#include <map>
#include <numeric>
#include <queue>

namespace refit {

namespace {

constexpr Index kUnassigned = 0xffffffffu;

class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), Index{0}); }
  Index find(Index x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  // The smaller root wins: components are named by their first element.
  void join(Index a, Index b) {
    a = find(a), b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<Index> parent_;
};

struct HalfEdge {
  Index lo, hi;  // garment vertices, lo < hi
  Index corner;  // the face corner it starts at (index into faces.indices)
  Index face;
  bool operator<(const HalfEdge& o) const { return std::tie(lo, hi, corner) < std::tie(o.lo, o.hi, o.corner); }
};

Index next_corner(const Csr& faces, Index face, Index corner) {
  return corner + 1 == faces.offsets[face + 1] ? faces.offsets[face] : corner + 1;
}

bool same_uv(const ObjFaceAttributes& at, Index c1, Index c2) {
  if (at.corner_texcoords.empty()) return true;
  const Index t1 = at.corner_texcoords[c1], t2 = at.corner_texcoords[c2];
  if (t1 == t2) return true;
  if (t1 == ObjFaceAttributes::kNoTexcoord || t2 == ObjFaceAttributes::kNoTexcoord) return false;
  return at.texcoords.row(t1) == at.texcoords.row(t2);
}

// Orients the panel's faces by breadth-first search over its joined edges;
// returns false when two faces cannot agree (a Moebius band).
bool orient(const Panel& p, const std::vector<std::vector<std::pair<Index, bool>>>& joined,
            const std::vector<Index>& local, std::vector<char>& flip) {
  std::vector<char> seen(p.faces.size(), 0);
  bool ok = true;
  for (std::size_t start = 0; start < p.faces.size(); ++start) {
    if (seen[start]) continue;
    seen[start] = 1;
    std::queue<Index> q;
    q.push(static_cast<Index>(start));
    while (!q.empty()) {
      const Index f = q.front();
      q.pop();
      for (const auto& [other, opposite] : joined[p.faces[f]]) {
        const Index o = local[other];
        // Opposite directions along the shared edge: same orientation.
        const char want = static_cast<char>(flip[f] ^ (opposite ? 0 : 1));
        if (!seen[o]) {
          seen[o] = 1;
          flip[o] = want;
          q.push(o);
        } else if (flip[o] != want) {
          ok = false;
        }
      }
    }
  }
  return ok;
}

// Edges, boundary loops (followed in the winding direction) and genus, from the triangles.
void panel_topology(Panel& p) {
  std::map<std::pair<Index, Index>, std::pair<int, Index>> uses;  // edge -> (count, the start of its last half-edge)
  for (const Triangle& t : p.triangles)
    for (int i = 0; i < 3; ++i) {
      const Index a = t[i], b = t[(i + 1) % 3];
      if (a == b) continue;
      auto& u = uses[{std::min(a, b), std::max(a, b)}];
      ++u.first;
      u.second = a;
    }
  p.edges = uses.size();
  std::multimap<Index, Index> next;  // boundary half-edges a -> b
  for (const auto& [e, u] : uses)
    if (u.first == 1) next.emplace(u.second, u.second == e.first ? e.second : e.first);
  p.loops.clear();
  while (!next.empty()) {
    std::vector<Index> loop;
    auto it = next.begin();
    const Index start = it->first;
    while (it != next.end()) {
      loop.push_back(it->first);
      const Index to = it->second;
      next.erase(it);
      if (to == start) break;
      it = next.find(to);
    }
    p.loops.push_back(std::move(loop));
  }
  const long chi = static_cast<long>(p.vertices.size()) - static_cast<long>(p.edges) + static_cast<long>(p.triangles.size());
  p.genus = static_cast<int>((2 - chi - static_cast<long>(p.loops.size())) / 2);
}

}  // namespace

PanelSet cut_panels(const Garment& g, const ObjFaceAttributes& at, std::span<const std::array<Index, 2>> seam_edges) {
  const Csr& faces = g.faces;
  const std::size_t nf = faces.rows(), nc = faces.indices.size();
  PanelSet set;
  std::vector<std::array<Index, 2>> seams(seam_edges.begin(), seam_edges.end());
  for (auto& s : seams)
    if (s[0] > s[1]) std::swap(s[0], s[1]);
  std::sort(seams.begin(), seams.end());

  std::vector<HalfEdge> half;
  half.reserve(nc);
  for (Index f = 0; f < nf; ++f)
    for (Index c = faces.offsets[f]; c < faces.offsets[f + 1]; ++c) {
      const Index a = faces.indices[c], b = faces.indices[next_corner(faces, f, c)];
      if (a != b) half.push_back({std::min(a, b), std::max(a, b), c, f});
    }
  std::sort(half.begin(), half.end());

  UnionFind face_sets(nf), corner_sets(nc);
  // Per face, the faces it is joined to and whether the shared edge runs in opposite directions.
  std::vector<std::vector<std::pair<Index, bool>>> joined(nf);
  std::vector<SeamCorners> cut_pairs;  // cut manifold edges
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].lo == half[i].lo && half[j].hi == half[i].hi) ++j;
    const std::size_t n = j - i;
    if (n >= 3) ++set.non_manifold_edges;
    if (n == 2) {
      const HalfEdge &h1 = half[i], &h2 = half[i + 1];
      const Index n1 = next_corner(faces, h1.face, h1.corner), n2 = next_corner(faces, h2.face, h2.corner);
      const bool opposite = faces.indices[h1.corner] == faces.indices[n2];
      // The corners of the edge's two vertices on each face, matched by vertex.
      const Index a1 = h1.corner, b1 = n1;
      const Index a2 = opposite ? n2 : h2.corner, b2 = opposite ? h2.corner : n2;
      const bool group_cut = !at.face_groups.empty() && at.face_groups[h1.face] != at.face_groups[h2.face];
      const bool uv_cut = !same_uv(at, a1, a2) || !same_uv(at, b1, b2);
      const bool curve_cut = std::binary_search(seams.begin(), seams.end(), std::array<Index, 2>{h1.lo, h1.hi});
      set.group_edges += group_cut;
      set.uv_seam_edges += !group_cut && uv_cut;
      set.curve_edges += !group_cut && !uv_cut && curve_cut;
      if (h1.face != h2.face && !group_cut && !uv_cut && !curve_cut) {
        face_sets.join(h1.face, h2.face);
        corner_sets.join(a1, a2);
        corner_sets.join(b1, b2);
        joined[h1.face].emplace_back(h2.face, opposite);
        joined[h2.face].emplace_back(h1.face, opposite);
      } else if (h1.face != h2.face) {
        SeamCorners sc;
        sc.face = {h1.face, h2.face};
        sc.corner = {std::array<Index, 2>{a1, b1}, std::array<Index, 2>{a2, b2}};
        cut_pairs.push_back(sc);
      }
    }
    i = j;
  }

  // Panels in order of their first face; panel vertices in order of first corner.
  set.face_panel.assign(nf, 0);
  std::vector<Index> panel_of_root(nf, kUnassigned), local(nf, 0);
  for (Index f = 0; f < nf; ++f) {
    const Index r = face_sets.find(f);
    if (panel_of_root[r] == kUnassigned) {
      panel_of_root[r] = static_cast<Index>(set.panels.size());
      set.panels.emplace_back();
    }
    Panel& p = set.panels[panel_of_root[r]];
    set.face_panel[f] = panel_of_root[r];
    local[f] = static_cast<Index>(p.faces.size());
    p.faces.push_back(f);
  }
  set.corner_vertex.assign(nc, 0);
  std::vector<Index> vertex_of_root(nc, kUnassigned);
  for (Index f = 0; f < nf; ++f) {
    Panel& p = set.panels[set.face_panel[f]];
    for (Index c = faces.offsets[f]; c < faces.offsets[f + 1]; ++c) {
      const Index r = corner_sets.find(c);
      if (vertex_of_root[r] == kUnassigned) {
        vertex_of_root[r] = static_cast<Index>(p.vertices.size());
        p.vertices.push_back(faces.indices[c]);
      }
      set.corner_vertex[c] = vertex_of_root[r];
    }
  }

  // Names: the group's, numbered when a group has several panels.
  std::map<std::string, std::vector<Index>> by_name;
  for (Index k = 0; k < set.panels.size(); ++k) {
    const Index f = set.panels[k].faces.front();
    const std::string group = at.face_groups.empty() ? "" : at.group_names[at.face_groups[f]];
    by_name[group.empty() ? "piece" : group].push_back(k);
  }
  for (const auto& [name, ks] : by_name)
    for (std::size_t i = 0; i < ks.size(); ++i)
      set.panels[ks[i]].name = ks.size() == 1 && name != "piece" ? name : name + "-" + std::to_string(i + 1);

  for (Panel& p : set.panels) {
    std::vector<char> flip(p.faces.size(), 0);
    const bool orientable = orient(p, joined, local, flip);
    for (std::size_t i = 0; i < p.faces.size(); ++i) {
      // The fan from the face's first corner (as attach/ uses it), reversed when the face is flipped.
      const Index f = p.faces[i], c0 = faces.offsets[f];
      for (Index k = 1; k + 1 < faces.row_size(f); ++k) {
        const Index a = set.corner_vertex[c0], b = set.corner_vertex[c0 + k], c = set.corner_vertex[c0 + k + 1];
        p.triangles.push_back(flip[i] ? Triangle{a, c, b} : Triangle{a, b, c});
        p.triangle_face.push_back(f);
      }
    }
    panel_topology(p);
    if (!orientable) p.problem = "it is not orientable (a Moebius band): cut it with a seam curve";
    else if (p.loops.empty()) p.problem = "it is closed (no boundary): cut it with an OBJ group, a UV seam or a seam curve";
    else if (p.genus > 0)
      p.problem = "it has " + std::to_string(p.genus) + " handle(s) (genus " + std::to_string(p.genus) +
                  "): cut it with a seam curve";
    else if (p.vertices.size() < 3) p.problem = "it has fewer than 3 vertices";
  }
  set.seams = chain_seams(set, cut_pairs);
  return set;
}

}  // namespace refit
