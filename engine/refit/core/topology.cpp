#include <refit/core/topology.hpp>

#include <refit/core/error.hpp>

#include <refit/core/parallel.hpp>
#include <refit/core/union_find.hpp>

#include <algorithm>

#include <atomic>
#include <numeric>
#include <string>

namespace refit {
namespace {

// An undirected edge as one sortable key: smaller vertex in the high half.
std::uint64_t edge_key(Index a, Index b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(a) << 32) | b;
}
Index key_lo(std::uint64_t k) { return static_cast<Index>(k >> 32); }
Index key_hi(std::uint64_t k) { return static_cast<Index>(k & 0xffffffffu); }

void check_indices(const Garment& g) {
  const std::size_t n = g.vertex_count();
  const auto check = [&](const Csr& csr, const char* what) {
    for (Index i : csr.indices)
      if (i >= n)
        throw Error("garment: a " + std::string(what) + " references vertex " + std::to_string(std::size_t(i) + 1) +
                    " but there are only " + std::to_string(n) + " vertices");
  };
  check(g.faces, "face");
  check(g.lines, "line");
  check(g.points, "point");
}

/// Values put into n buckets in parallel: emit(begin, end, put) calls
/// put(bucket, value) for items [begin, end) of [0, items). Each bucket is
/// sorted, so the result does not depend on the threads (the fill order does).
template <class Values, class Emit>
void sorted_buckets(std::size_t n, std::size_t items, const Emit& emit, std::vector<Index>& start, Values& values) {
  constexpr std::size_t kGrain = 1 << 14;
  start.assign(n + 1, 0);
  parallel_for(0, items, kGrain, [&](std::size_t b, std::size_t e) {
    emit(b, e, [&](Index bucket, Index) {
      std::atomic_ref<Index>(start[bucket + 1]).fetch_add(1, std::memory_order_relaxed);
    });
  });
  for (std::size_t v = 0; v < n; ++v) start[v + 1] += start[v];
  values.resize(start[n]);
  std::vector<Index> fill(start.begin(), start.end() - 1);
  parallel_for(0, items, kGrain, [&](std::size_t b, std::size_t e) {
    emit(b, e, [&](Index bucket, Index value) {
      values[std::atomic_ref<Index>(fill[bucket]).fetch_add(1, std::memory_order_relaxed)] = value;
    });
  });
  parallel_for(0, n, kGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) std::sort(values.begin() + start[v], values.begin() + start[v + 1]);
  });
}

/// Every face side (consecutive corners, wrapping) as an undirected edge,
/// bucketed by its smaller vertex: bucket v holds the larger vertices, sorted,
/// in hi[start[v], start[v+1]); an edge used by k face sides appears k times.
/// Repeated-vertex (zero-length) sides are skipped. Built in parallel: the fill
/// order within a bucket varies with the threads, the sorted buckets do not.
struct FaceEdges {
  std::vector<Index> start, hi;
};

/// With `id`, each corner's vertex v stands for id[v] (welded vertices).
FaceEdges face_edges(const Garment& g, const std::vector<Index>* id = nullptr) {
  FaceEdges e;
  sorted_buckets(
      g.vertex_count(), g.faces.rows(),
      [&](std::size_t begin, std::size_t end, auto&& put) {
        for (std::size_t r = begin; r < end; ++r) {
          const auto row = g.faces.row(r);
          for (std::size_t k = 0; k < row.size(); ++k) {
            Index a = row[k], b = row[k + 1 == row.size() ? 0 : k + 1];
            if (id) a = (*id)[a], b = (*id)[b];
            if (a != b) put(std::min(a, b), std::max(a, b));
          }
        }
      },
      e.start, e.hi);
  return e;
}

/// Calls f(lo, hi, k) for each distinct edge, k = how many face sides use it,
/// in key order.
template <class F>
void for_each_edge(const FaceEdges& e, F&& f) {
  const std::size_t n = e.start.size() - 1;
  for (std::size_t v = 0; v < n; ++v)
    for (Index i = e.start[v]; i < e.start[v + 1];) {
      Index j = i + 1;
      while (j < e.start[v + 1] && e.hi[j] == e.hi[i]) ++j;
      f(static_cast<Index>(v), e.hi[i], j - i);
      i = j;
    }
}

std::vector<std::vector<Index>> loops_from_edges(const Garment& g, const FaceEdges& edges);

}  // namespace

TopologyStats topology_stats(const Garment& g) {
  check_indices(g);
  TopologyStats s;
  s.vertices = g.vertex_count();
  s.faces = g.faces.rows();
  s.lines = g.lines.rows();
  s.points = g.points.rows();

  const FaceEdges edges = face_edges(g);
  for_each_edge(edges, [&](Index, Index, Index k) {
    ++s.edges;
    if (k == 1) ++s.boundary_edges;
    if (k >= 3) ++s.non_manifold_edges;
  });

  std::vector<Index> parent(s.vertices);
  std::iota(parent.begin(), parent.end(), Index{0});
  std::vector<std::uint8_t> used(s.vertices, 0);
  for (const Csr* csr : {&g.faces, &g.lines})
    for (std::size_t r = 0; r < csr->rows(); ++r) {
      const auto row = csr->row(r);
      for (Index v : row) {
        used[v] = 1;
        unite_roots(parent, row[0], v);
      }
    }
  // `p v1 v2 ...` lists separate points (OBJ spec): each vertex stands alone.
  for (Index v : g.points.indices) used[v] = 1;
  for (std::size_t v = 0; v < s.vertices; ++v) {
    if (!used[v]) ++s.unreferenced_vertices;
    else if (parent[v] == v) ++s.components;  // a root
  }
  s.boundary_loops = loops_from_edges(g, edges).size();
  return s;
}

std::vector<Index> boundary_vertices(const Garment& g, const std::vector<Index>& id) {
  check_indices(g);
  if (id.size() != g.vertex_count()) throw Error("internal: boundary_vertices needs one id per vertex");
  for (Index i : id)
    if (i >= id.size()) throw Error("internal: boundary_vertices: a vertex id out of range");
  std::vector<Index> out;
  for_each_edge(face_edges(g, &id), [&](Index lo, Index hi, Index k) {
    if (k == 1) out.insert(out.end(), {lo, hi});
  });
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<std::vector<Index>> boundary_loops(const Garment& g) {
  check_indices(g);
  return loops_from_edges(g, face_edges(g));
}

namespace {

std::vector<std::vector<Index>> loops_from_edges(const Garment& g, const FaceEdges& edges) {
  // Boundary edges (used once), in key order.
  std::vector<std::uint64_t> boundary;
  for_each_edge(edges, [&](Index lo, Index hi, Index k) {
    if (k == 1) boundary.push_back(edge_key(lo, hi));
  });
  if (boundary.empty()) return {};

  // The direction a face gives each boundary edge, so loops follow the faces'
  // orientation where they are consistent.
  std::vector<std::uint8_t> forward(boundary.size(), 1);  // lo -> hi
  std::vector<std::uint8_t> on_boundary(g.vertex_count(), 0);
  for (std::uint64_t k : boundary) on_boundary[key_lo(k)] = on_boundary[key_hi(k)] = 1;
  // A boundary edge has exactly one face side, so exactly one iteration writes it.
  parallel_for(0, g.faces.rows(), 1 << 14, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const auto row = g.faces.row(f);
      for (std::size_t k = 0; k < row.size(); ++k) {
        const Index a = row[k], b = row[(k + 1) % row.size()];
        if (a == b || !on_boundary[a] || !on_boundary[b]) continue;
        const auto it = std::lower_bound(boundary.begin(), boundary.end(), edge_key(a, b));
        if (it != boundary.end() && *it == edge_key(a, b)) forward[std::size_t(it - boundary.begin())] = a < b;
      }
    }
  });
  return boundary_loops_of(boundary, forward);
}

}  // namespace

std::vector<std::vector<Index>> boundary_loops_of(const std::vector<std::uint64_t>& boundary,
                                                  const std::vector<std::uint8_t>& forward) {
  // The boundary's vertices renumbered in order (the walk only compares them),
  // so it needs memory for the boundary alone.
  std::vector<Index> vertex;
  for (std::uint64_t k : boundary) vertex.insert(vertex.end(), {key_lo(k), key_hi(k)});
  std::sort(vertex.begin(), vertex.end());
  vertex.erase(std::unique(vertex.begin(), vertex.end()), vertex.end());
  const auto local = [&](Index v) { return Index(std::lower_bound(vertex.begin(), vertex.end(), v) - vertex.begin()); };
  const std::size_t n = vertex.size();
  std::vector<Index> lo(boundary.size()), hi(boundary.size());
  for (std::size_t e = 0; e < boundary.size(); ++e) lo[e] = local(key_lo(boundary[e])), hi[e] = local(key_hi(boundary[e]));

  // Boundary edges at each vertex (CSR, edge ids ascending), to chain them.
  Csr at;
  at.offsets.assign(n + 1, 0);
  for (std::size_t e = 0; e < boundary.size(); ++e) {
    ++at.offsets[lo[e] + 1];
    ++at.offsets[hi[e] + 1];
  }
  for (std::size_t v = 0; v < n; ++v) at.offsets[v + 1] += at.offsets[v];
  at.indices.resize(at.offsets[n]);
  {
    std::vector<Index> fill(at.offsets.begin(), at.offsets.end() - 1);
    for (std::size_t e = 0; e < boundary.size(); ++e) {
      at.indices[fill[lo[e]]++] = static_cast<Index>(e);
      at.indices[fill[hi[e]]++] = static_cast<Index>(e);
    }
  }

  // Walk from each unused edge; at a vertex with several unused boundary edges
  // take the one with the smallest id. Coming back to a vertex already on the
  // chain closes a loop there (so loops are simple cycles); a chain that ends
  // without closing is dropped. Every edge is used once: the walk terminates.
  std::vector<std::uint8_t> done(boundary.size(), 0);
  std::vector<std::int64_t> pos_in_chain(n, -1);
  std::vector<std::vector<Index>> loops;
  std::vector<Index> chain;
  for (std::size_t start = 0; start < boundary.size(); ++start) {
    if (done[start]) continue;
    done[start] = 1;
    const Index a = lo[start], b = hi[start];
    chain.assign({forward[start] ? a : b});
    Index cur = forward[start] ? b : a;
    pos_in_chain[chain[0]] = 0;
    for (;;) {
      const std::int64_t seen = pos_in_chain[cur];
      if (seen >= 0) {
        loops.emplace_back(chain.begin() + seen, chain.end());
        for (auto it = chain.begin() + seen + 1; it != chain.end(); ++it) pos_in_chain[*it] = -1;
        chain.resize(static_cast<std::size_t>(seen) + 1);
      } else {
        pos_in_chain[cur] = static_cast<std::int64_t>(chain.size());
        chain.push_back(cur);
      }
      Index next_edge = Index(-1);
      for (Index e : at.row(cur))
        if (!done[e]) {
          next_edge = e;
          break;
        }
      if (next_edge == Index(-1)) break;
      done[next_edge] = 1;
      cur = lo[next_edge] == cur ? hi[next_edge] : lo[next_edge];
    }
    for (Index v : chain) pos_in_chain[v] = -1;
  }
  // Each loop starts at its smallest vertex (direction kept), so the result
  // does not depend on which edge the walk happened to start from.
  for (auto& loop : loops) {
    std::rotate(loop.begin(), std::min_element(loop.begin(), loop.end()), loop.end());
    for (Index& v : loop) v = vertex[v];
  }
  return loops;
}

Csr vertex_adjacency(const Garment& g) {
  const std::size_t n = g.vertex_count();
  // Every edge of the faces and `l` lines, both ways, bucketed by vertex.
  std::vector<Index> start;
  UninitVector<Index> all;
  sorted_buckets(
      n, g.faces.rows() + g.lines.rows(),
      [&](std::size_t b, std::size_t e, auto&& put) {
        for (std::size_t r = b; r < e; ++r) {
          const bool face = r < g.faces.rows();
          const auto row = face ? g.faces.row(r) : g.lines.row(r - g.faces.rows());
          const std::size_t edges = face ? row.size() : (row.size() > 0 ? row.size() - 1 : 0);
          for (std::size_t k = 0; k < edges; ++k) {
            const Index a = row[k], c = row[(k + 1) % row.size()];
            if (a != c) put(a, c), put(c, a);
          }
        }
      },
      start, all);
  // Drop the duplicates (shared edges appear once per face) row by row.
  std::vector<Index> row_size(n, 0);
  parallel_for(0, n, 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      row_size[i] = static_cast<Index>(std::unique(all.data() + start[i], all.data() + start[i + 1]) - (all.data() + start[i]));
  });
  Csr adj;
  adj.offsets.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) adj.offsets[i + 1] = adj.offsets[i] + row_size[i];
  adj.indices.resize(adj.offsets[n]);
  parallel_for(0, n, 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      std::copy_n(all.begin() + start[i], row_size[i], adj.indices.begin() + adj.offsets[i]);
  });
  return adj;
}

Csr vertex_faces(const Garment& g) {
  const std::size_t n = g.vertex_count();
  std::vector<Index> start;
  UninitVector<Index> all;
  sorted_buckets(
      n, g.faces.rows(),
      [&](std::size_t b, std::size_t e, auto&& put) {
        for (std::size_t f = b; f < e; ++f) {
          const auto row = g.faces.row(f);
          for (std::size_t k = 0; k < row.size(); ++k)
            if (std::find(row.begin(), row.begin() + k, row[k]) == row.begin() + k) put(row[k], Index(f));
        }
      },
      start, all);
  Csr out;
  out.offsets.assign(start.begin(), start.end());
  out.indices = std::move(all);
  return out;
}

std::vector<Index> faces_around(const Csr& faces_of_vertex, std::span<const Index> vertices) {
  std::vector<Index> faces;
  for (Index v : vertices) faces.insert(faces.end(), faces_of_vertex.row(v).begin(), faces_of_vertex.row(v).end());
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  return faces;
}

}  // namespace refit
