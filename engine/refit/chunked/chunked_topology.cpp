#include <refit/chunked/chunked_topology.hpp>

#include <refit/core/topology.hpp>
#include <refit/core/weld.hpp>

#include <algorithm>

namespace refit {

double bounding_box_diagonal(const GarmentStore& g) {
  if (g.vertex_count() == 0) return 0.0;
  return Eigen::RowVector3d((g.high() - g.low()).transpose()).norm();
}

std::unordered_map<Index, Index> chunked_weld(const GarmentStore& g, const ChunkPlan& plan, double tolerance) {
  std::unordered_map<Index, Index> weld;
  if (!(tolerance > 0.0) || g.vertex_count() < 2) return weld;
  PointWelder welder(g.vertex_count(), tolerance);
  for_each_chunk(g.positions(), plan.chunk_vertices, [&](std::size_t, const Points& rows) { welder.mark(rows); });
  for_each_chunk(g.positions(), plan.chunk_vertices, [&](std::size_t first, const Points& rows) {
    const std::vector<Index> rep = welder.cluster(first, rows, welder.candidates(rows));
    for (std::size_t i = 0; i < rep.size(); ++i)
      if (rep[i] != first + i) weld.emplace(Index(first + i), rep[i]);
  });
  return weld;
}

std::vector<Points> chunked_boundary_loops(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan,
                                           double tolerance) {
  const std::unordered_map<Index, Index> weld = chunked_weld(g, plan, tolerance);
  const auto welded = [&](Index v) {
    const auto it = weld.find(v);
    return it == weld.end() ? v : it->second;
  };
  // Each face on the welded vertices as weld_garment makes it: consecutive
  // repeats dropped (across the wrap too), faces left with fewer than 3 corners dropped.
  const auto for_each_welded_face = [&](auto&& f) {
    std::vector<Index> row;
    for_each_chunk(g.faces(), plan.chunk_faces, [&](std::size_t, const Csr& rows) {
      for (std::size_t r = 0; r < rows.rows(); ++r) {
        row.clear();
        for (Index v : rows.row(r)) {
          const Index w = welded(v);
          if (row.empty() || row.back() != w) row.push_back(w);
        }
        while (row.size() > 1 && row.back() == row.front()) row.pop_back();
        if (row.size() >= 3) f(row);
      }
    });
  };
  const auto key = [](Index a, Index b) { return std::uint64_t(std::min(a, b)) << 32 | std::max(a, b); };
  EdgeBuckets edges(plan.folder, g.faces().entries(), std::max<std::size_t>(plan.chunk_vertices * 8, 1 << 12));
  for_each_welded_face([&](const std::vector<Index>& row) {
    for (std::size_t k = 0; k < row.size(); ++k) {
      const Index a = row[k], b = row[(k + 1) % row.size()];
      if (a != b) edges.add(key(a, b));
    }
  });
  std::vector<std::uint64_t> boundary;
  edges.singles([&](std::uint64_t k) { boundary.push_back(k); });
  if (boundary.empty()) return {};
  std::sort(boundary.begin(), boundary.end());
  // The direction the one face using each boundary edge gives it.
  std::vector<std::uint8_t> forward(boundary.size(), 1);
  for_each_welded_face([&](const std::vector<Index>& row) {
    for (std::size_t k = 0; k < row.size(); ++k) {
      const Index a = row[k], b = row[(k + 1) % row.size()];
      if (a == b) continue;
      const auto it = std::lower_bound(boundary.begin(), boundary.end(), key(a, b));
      if (it != boundary.end() && *it == key(a, b)) forward[std::size_t(it - boundary.begin())] = a < b;
    }
  });
  const std::vector<std::vector<Index>> loops = boundary_loops_of(boundary, forward);
  std::vector<Points> polys(loops.size());
  for (std::size_t i = 0; i < loops.size(); ++i) x.gather(loops[i], polys[i]);
  return polys;
}

}  // namespace refit
