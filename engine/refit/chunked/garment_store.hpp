#pragma once
// A garment too large for memory, in temporary files (issue 14): the OBJ is
// read a group of lines at a time (ObjStream) into its positions and its
// elements, which the chunked stages then stream back in chunks of rows.
#include <refit/chunked/temp_file.hpp>
#include <refit/io/obj_stream.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace refit {

class GarmentStore {
 public:
  /// Reads the garment OBJ of `obj` (its first pass done) into temporary files
  /// in `folder`, obj.group_bytes() of the file at a time. Throws refit::Error
  /// as read_garment_obj does for bad input.
  GarmentStore(ObjStream obj, const std::filesystem::path& folder);

  const ObjStream& obj() const { return obj_; }
  const std::filesystem::path& folder() const { return folder_; }
  std::size_t vertex_count() const { return obj_.vertex_count(); }
  std::size_t face_count() const { return faces_.rows(); }
  std::size_t line_count() const { return lines_.rows(); }
  std::size_t point_count() const { return points_.rows(); }
  const PointFile& positions() const { return positions_; }
  const CsrFile& faces() const { return faces_; }
  const CsrFile& lines() const { return lines_; }
  const CsrFile& points() const { return points_; }
  /// Normal index of every face corner (aligned with faces' entries); null when no corner has one.
  const RecordFile<Index>* corner_normals() const { return any_corner_normal_ ? &corner_normals_ : nullptr; }
  const std::vector<std::string>& warnings() const { return warnings_; }
  /// The bounding box of the positions.
  const Vec3& low() const { return low_; }
  const Vec3& high() const { return high_; }
  /// The report's garment counts (garment_summary).
  nlohmann::json summary() const;

 private:
  ObjStream obj_;
  std::filesystem::path folder_;
  PointFile positions_;
  CsrFile faces_, lines_, points_;
  RecordFile<Index> corner_normals_;
  bool any_corner_normal_ = false;
  std::vector<std::string> warnings_;
  Vec3 low_, high_;
};

/// f(first, rows) over consecutive chunks of `file`: rows [first, first + rows.rows()), `chunk` at a time.
template <class F>
void for_each_chunk(const PointFile& file, std::size_t chunk, F&& f) {
  Points rows;
  for (std::size_t first = 0; first < file.rows(); first += chunk) {
    file.read(first, std::min(chunk, file.rows() - first), rows);
    f(first, rows);
  }
}

/// f(first, rows) over consecutive chunks of rows of `file` (offsets from 0).
template <class F>
void for_each_chunk(const CsrFile& file, std::size_t chunk, F&& f) {
  Csr rows;
  for (std::size_t first = 0; first < file.rows(); first += chunk) {
    file.read(first, std::min(chunk, file.rows() - first), rows);
    f(first, static_cast<const Csr&>(rows));
  }
}

/// Random access to the rows of a PointFile within a memory bound: the whole
/// file in memory when it fits in `max_bytes` (24 bytes per row), else read
/// from disk a window of rows at a time for each request (slower).
class PointGather {
 public:
  PointGather(const PointFile& file, std::size_t max_bytes);
  bool resident() const { return resident_; }
  std::size_t rows() const { return file_.rows(); }
  /// out.row(k) = row ids[k] of the file (out resized).
  void gather(std::span<const Index> ids, Points& out) const;
  /// Every row (resident() only).
  const Points& all() const { return all_; }
  /// The memory a resident gather of `rows` rows takes.
  static std::size_t resident_bytes(std::size_t rows) { return rows * 3 * sizeof(double); }

 private:
  const PointFile& file_;
  bool resident_ = false;
  std::size_t window_rows_ = 0;
  Points all_;
};

/// A chunk of a garment's faces (or lines, or points) with its corners' positions.
struct ElementBlock {
  std::size_t first = 0;      // number of the block's first row in its file
  Csr rows;                   // corners as global vertex indices
  const Points* x = nullptr;  // positions: corner entry e is at row at[e]
  std::vector<Index> at;
  Vec3 corner(std::size_t entry) const { return row3(*x, at[entry]); }
};

/// f(block) over consecutive blocks of `chunk` rows of `file`, the corners'
/// positions from `gather`.
template <class F>
void for_each_block(const CsrFile& file, std::size_t chunk, const PointGather& gather, F&& f) {
  ElementBlock block;
  Points local;
  std::vector<Index> ids;
  for_each_chunk(file, chunk, [&](std::size_t first, const Csr& rows) {
    block.first = first;
    block.rows = rows;
    if (gather.resident()) {
      block.x = &gather.all();
      block.at.assign(rows.indices.begin(), rows.indices.end());
    } else {
      ids.assign(rows.indices.begin(), rows.indices.end());
      std::sort(ids.begin(), ids.end());
      ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
      gather.gather(ids, local);
      block.x = &local;
      block.at.resize(rows.indices.size());
      for (std::size_t e = 0; e < rows.indices.size(); ++e)
        block.at[e] = Index(std::lower_bound(ids.begin(), ids.end(), rows.indices[e]) - ids.begin());
    }
    f(static_cast<const ElementBlock&>(block));
  });
}

}  // namespace refit
