#include <refit/chunked/chunked_normals.hpp>

#include <cmath>

namespace refit {

std::optional<ChunkedNormals> chunked_normals(const GarmentStore& g, const PointFile& positions, const ChunkPlan& plan) {
  const RecordFile<Index>* corner_normals = g.corner_normals();
  if (!corner_normals) return std::nullopt;
  const std::size_t nn = g.obj().normal_count();
  // Each face's Newell normal (recompute_normals' sum, obj_write.cpp), once.
  PointFile face_normal(plan.folder, g.face_count());
  {
    const PointGather x(positions, plan.gather_bytes);
    for_each_block(g.faces(), plan.chunk_faces, x, [&](const ElementBlock& b) {
      Points n(Eigen::Index(b.rows.rows()), 3);
      for (std::size_t f = 0; f < b.rows.rows(); ++f) {
        const std::size_t o = b.rows.offsets[f], k = b.rows.row_size(f);
        Vec3 s = Vec3::Zero();
        for (std::size_t c = 0; c < k; ++c) s += b.corner(o + c).cross(b.corner(o + (c + 1) % k));
        n.row(Eigen::Index(f)) = s.transpose();
      }
      face_normal.write(b.first, n);
    });
  }
  ChunkedNormals out{PointFile(plan.folder, nn), RecordFile<std::uint8_t>(plan.folder), 0, {}};
  // Summed per normal in face order, a range of normals at a time.
  const std::size_t range = std::max<std::size_t>(plan.chunk_vertices * 4, 1 << 12);
  std::size_t degenerate = 0;
  for (std::size_t first = 0; first < nn; first += range) {
    const std::size_t count = std::min(range, nn - first);
    Points sum = Points::Zero(Eigen::Index(count), 3);
    std::vector<std::uint8_t> used(count, 0), done(count, 0);
    Points n;
    std::vector<Index> corners;
    for_each_chunk(g.faces(), plan.chunk_faces, [&](std::size_t f0, const Csr& rows) {
      face_normal.read(f0, rows.rows(), n);
      corner_normals->read(g.faces().entry_of(f0), rows.indices.size(), corners);
      for (std::size_t f = 0; f < rows.rows(); ++f)
        for (std::size_t e = rows.offsets[f]; e < rows.offsets[f + 1]; ++e) {
          const Index ni = corners[e];
          if (ni == ObjSource::kNoNormal || ni < first || ni >= first + count) continue;
          sum.row(Eigen::Index(ni - first)) += n.row(Eigen::Index(f));
          used[ni - first] = 1;
        }
    });
    for (std::size_t i = 0; i < count; ++i) {
      if (!used[i]) continue;
      const double len = sum.row(Eigen::Index(i)).norm();
      if (len > 0 && std::isfinite(len)) {
        sum.row(Eigen::Index(i)) /= len;
        done[i] = 1;
        ++out.count;
      } else {
        ++degenerate;
      }
    }
    out.normals.write(first, sum);
    out.recomputed.write(first, std::span<const std::uint8_t>(done));
  }
  if (degenerate > 0)
    out.warnings.push_back(std::to_string(degenerate) + " normals belong only to zero-area faces and were kept as they were");
  return out;
}

}  // namespace refit
