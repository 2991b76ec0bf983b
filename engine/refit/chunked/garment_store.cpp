#include <refit/chunked/garment_store.hpp>

#include <refit/core/error.hpp>

#include <algorithm>
#include <limits>
#include <numeric>

namespace refit {

GarmentStore::GarmentStore(ObjStream obj, const std::filesystem::path& folder)
    : obj_(std::move(obj)),
      folder_(folder),
      positions_(folder, obj_.vertex_count()),
      faces_(folder),
      lines_(folder),
      points_(folder),
      corner_normals_(folder) {
  if (obj_.vertex_count() >= std::numeric_limits<Index>::max())
    throw input_error(obj_.file(), "more than " + std::to_string(std::numeric_limits<Index>::max() - 1) + " vertices");
  low_ = Vec3::Constant(std::numeric_limits<double>::infinity());
  high_ = -low_;
  std::size_t corners = 0;
  warnings_ = obj_.read([&](ObjGroup& g) {
    positions_.write(g.first_vertex, g.positions);
    if (g.positions.rows() > 0) {
      low_ = low_.cwiseMin(g.positions.colwise().minCoeff().transpose());
      high_ = high_.cwiseMax(g.positions.colwise().maxCoeff().transpose());
    }
    faces_.append(g.faces);
    lines_.append(g.lines);
    points_.append(g.points);
    if (obj_.normal_count() > 0) {
      if (g.corner_normals.empty()) g.corner_normals.assign(g.faces.indices.size(), ObjSource::kNoNormal);
      any_corner_normal_ = any_corner_normal_ ||
                           std::any_of(g.corner_normals.begin(), g.corner_normals.end(),
                                       [](Index n) { return n != ObjSource::kNoNormal; });
      corner_normals_.write(corners, std::span<const Index>(g.corner_normals));
    }
    corners += g.faces.indices.size();
  });
}

nlohmann::json GarmentStore::summary() const {
  return {{"vertices", vertex_count()}, {"faces", face_count()}, {"lines", line_count()}, {"points", point_count()}};
}

PointGather::PointGather(const PointFile& file, std::size_t max_bytes) : file_(file) {
  resident_ = resident_bytes(file.rows()) <= max_bytes;
  if (resident_) {
    file.read(0, file.rows(), all_);
  } else {
    window_rows_ = std::max<std::size_t>(max_bytes / (3 * sizeof(double)), 4096);
  }
}

void PointGather::gather(std::span<const Index> ids, Points& out) const {
  out.resize(Eigen::Index(ids.size()), 3);
  if (resident_) {
    for (std::size_t k = 0; k < ids.size(); ++k) out.row(Eigen::Index(k)) = all_.row(ids[k]);
    return;
  }
  // Requests in row order; rows close to each other read in one go (at most a
  // window of rows at a time), so sparse requests read little and dense ones
  // read each window once.
  std::vector<std::uint32_t> order(ids.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return ids[a] < ids[b]; });
  constexpr std::size_t kGap = 512;  // rows: reading across a gap this small costs less than another read
  Points window;
  for (std::size_t k = 0; k < order.size();) {
    const std::size_t first = ids[order[k]];
    std::size_t last = first, j = k;
    while (j < order.size() && ids[order[j]] - first < window_rows_ && ids[order[j]] <= last + kGap) last = ids[order[j++]];
    file_.read(first, last - first + 1, window);
    for (; k < j; ++k) out.row(Eigen::Index(order[k])) = window.row(Eigen::Index(ids[order[k]] - first));
  }
}

}  // namespace refit
