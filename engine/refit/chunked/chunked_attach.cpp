#include <refit/chunked/chunked_attach.hpp>

#include <refit/core/error.hpp>

#include <algorithm>
#include <limits>

namespace refit {
namespace {

// A block of elements as a garment of its own (its vertices renumbered in order).
Garment block_garment(const Csr& rows, const PointGather& x, Csr Garment::*kind, std::vector<Index>& ids) {
  ids.assign(rows.indices.begin(), rows.indices.end());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  Garment sub;
  x.gather(ids, sub.positions);
  Csr& out = sub.*kind;
  out.offsets = rows.offsets;
  out.indices.resize(rows.indices.size());
  for (std::size_t e = 0; e < rows.indices.size(); ++e)
    out.indices[e] = Index(std::lower_bound(ids.begin(), ids.end(), rows.indices[e]) - ids.begin());
  return sub;
}

}  // namespace

SurfaceAttachment chunked_attach(const GarmentStore& g, const PointGather& x, const ChunkPlan& plan, const Points& samples) {
  const std::size_t n = static_cast<std::size_t>(samples.rows());
  SurfaceAttachment at;
  at.vertex.resize(n);
  at.weight.resize(n);
  at.offset.resize(samples.rows(), 3);
  if (n == 0) return at;
  std::vector<double> best(n, std::numeric_limits<double>::infinity());
  std::vector<Index> ids;
  // Blocks in element order (faces, lines, points, as GarmentLocator numbers
  // them): a later block wins only when strictly closer.
  const auto take = [&](const Garment& sub) {
    const SurfaceAttachment part = GarmentLocator(sub).attach(samples);
    for (std::size_t s = 0; s < n; ++s) {
      const double d2 = part.offset.row(Eigen::Index(s)).squaredNorm();
      if (!(d2 < best[s])) continue;
      best[s] = d2;
      for (int k = 0; k < 3; ++k) at.vertex[s][k] = ids[part.vertex[s][k]];
      at.weight[s] = part.weight[s];
      at.offset.row(Eigen::Index(s)) = part.offset.row(Eigen::Index(s));
    }
  };
  const std::pair<const CsrFile*, Csr Garment::*> kinds[] = {
      {&g.faces(), &Garment::faces}, {&g.lines(), &Garment::lines}, {&g.points(), &Garment::points}};
  for (const auto& entry : kinds) {  // not a structured binding: clang 14 cannot capture one (fuzz preset)
    Csr Garment::*const kind = entry.second;
    for_each_chunk(*entry.first, plan.chunk_faces, [&](std::size_t, const Csr& rows) { take(block_garment(rows, x, kind, ids)); });
  }
  if (g.face_count() + g.line_count() + g.point_count() == 0) {
    // A garment without elements attaches to its vertices (GarmentLocator does so).
    for (std::size_t first = 0; first < g.vertex_count(); first += plan.chunk_vertices) {
      Csr rows;
      std::vector<Index> all(std::min(plan.chunk_vertices, g.vertex_count() - first));
      for (std::size_t i = 0; i < all.size(); ++i) all[i] = Index(first + i);
      rows.push_row(all);
      take(block_garment(rows, x, &Garment::points, ids));
    }
  }
  return at;
}

}  // namespace refit
