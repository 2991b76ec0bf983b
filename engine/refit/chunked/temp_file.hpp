#pragma once
// Temporary binary files for the chunked mode (issue 14): what a stage holds
// per vertex or per face goes to disk and comes back in chunks. The files are
// anonymous (unlinked as soon as they are made), so nothing is left behind
// however the process ends.
#include <refit/core/types.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace refit {

/// An anonymous file in `folder` (a temporary file with no name). Reads and
/// writes at offsets (pread/pwrite) may come from several threads at once.
/// Throws refit::Error naming the folder on any failure (no space, ...).
class TempFile {
 public:
  explicit TempFile(const std::filesystem::path& folder);
  ~TempFile();
  TempFile(TempFile&& other) noexcept;
  TempFile& operator=(TempFile&& other) noexcept;
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  void write(const void* data, std::size_t bytes, std::size_t at);
  void read(void* data, std::size_t bytes, std::size_t at) const;
  /// Appends at the end of what was appended so far; returns where it went.
  std::size_t append(const void* data, std::size_t bytes);
  std::size_t size() const { return size_; }

 private:
  std::string folder_;
  int fd_ = -1;
  std::size_t size_ = 0;
};

/// Rows of 3 doubles (positions, displacements) on disk, x y z per row.
class PointFile {
 public:
  PointFile(const std::filesystem::path& folder, std::size_t rows);
  std::size_t rows() const { return rows_; }
  void write(std::size_t first, const Points& rows);
  /// Rows [first, first + count) into `out` (resized).
  void read(std::size_t first, std::size_t count, Points& out) const;

 private:
  TempFile file_;
  std::size_t rows_ = 0;
};

/// Fixed-size plain records (indices, flags, small structs) on disk.
template <class T>
class RecordFile {
 public:
  explicit RecordFile(const std::filesystem::path& folder) : file_(folder) {}
  std::size_t size() const { return count_; }
  void write(std::size_t first, std::span<const T> items) {
    file_.write(items.data(), items.size_bytes(), first * sizeof(T));
    count_ = std::max(count_, first + items.size());
  }
  void read(std::size_t first, std::size_t count, std::vector<T>& out) const {
    out.resize(count);
    file_.read(out.data(), count * sizeof(T), first * sizeof(T));
  }

 private:
  TempFile file_;
  std::size_t count_ = 0;
};

/// A CSR written a block of rows at a time, in row order, and read back by
/// ranges of rows (faces, lines, points of a garment). The row offsets stay
/// in memory every `kStride` rows only.
class CsrFile {
 public:
  explicit CsrFile(const std::filesystem::path& folder);
  /// Appends `rows` (its offsets start at 0).
  void append(const Csr& rows);
  std::size_t rows() const { return rows_; }
  std::size_t entries() const { return entries_; }
  /// Rows [first, first + count) as a CSR with offsets from 0.
  void read(std::size_t first, std::size_t count, Csr& out) const;
  /// Entry offset of row r (r <= rows()).
  std::size_t entry_of(std::size_t r) const;

 private:
  static constexpr std::size_t kStride = 4096;
  TempFile sizes_, indices_;  // per row its size (uint32); the entries
  std::vector<std::size_t> stride_entry_;  // entry offset of rows 0, kStride, 2 kStride, ...
  std::size_t rows_ = 0, entries_ = 0;
};

}  // namespace refit
