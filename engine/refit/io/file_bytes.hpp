#pragma once
// Whole files in and out in parallel ranges: the byte buffer a garment file is
// read into, a file read by ranges, and the pread/pwrite loop shared by the
// readers and the atomic writer.
#include <sys/types.h>

#include <algorithm>
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

namespace refit {

class MappedFile;

/// A file's bytes. Unlike std::string it is made without zero-filling, so a large
/// file goes straight into fresh pages, several threads reading at once; or the
/// file's own pages, mapped (read_file_bytes with `may_map`).
class TextBytes {
 public:
  TextBytes();
  explicit TextBytes(std::size_t size);  // contents unset
  explicit TextBytes(std::string_view text);
  explicit TextBytes(std::unique_ptr<MappedFile> mapped);
  TextBytes(TextBytes&&) noexcept;
  TextBytes& operator=(TextBytes&&) noexcept;
  ~TextBytes();
  char* data() { return owned_.get(); }  // the bytes read into (null when mapped)
  std::size_t size() const { return size_; }
  std::string_view view() const { return {bytes_, size_}; }
  /// Mapped bytes: throws refit::Error naming the file when it was changed in
  /// place since it was mapped (they may not be what was read). Copies: nothing.
  void check_unchanged() const;

 private:
  std::unique_ptr<char[]> owned_;
  std::unique_ptr<MappedFile> mapped_;
  const char* bytes_ = nullptr;
  std::size_t size_ = 0;
};

/// Moves all `size` bytes between `data` and the file `fd` at offset `at`
/// (pwrite when `write`, else pread), retrying short transfers and EINTR.
/// Returns 0, the errno of a failure, or -1 when the file ended first.
int transfer_all(int fd, char* data, std::size_t size, off_t at, bool write);

/// A regular file open for reading by ranges, closed on scope exit. Errors
/// (refit::Error) name the file.
class SourceFile {
 public:
  explicit SourceFile(const std::string& path);
  ~SourceFile();
  SourceFile(const SourceFile&) = delete;
  SourceFile& operator=(const SourceFile&) = delete;
  std::size_t size() const { return size_; }
  int fd() const { return fd_; }
  const std::string& path() const { return path_; }
  /// Bytes [at, at + size) into `out` (resized), several threads reading 8 MB ranges at once.
  void read(std::size_t at, std::size_t size, std::string& out) const;
  /// Offset of the first '\n' at or after `at`, or size().
  std::size_t find_newline(std::size_t at) const;

 private:
  std::string path_;
  int fd_ = -1;
  std::size_t size_ = 0;
};

/// The whole regular file at `path`, read by several threads in 8 MB ranges (the
/// kernel's copy and the first touch of the pages were most of a large garment's
/// read time on one thread); with `may_map`, in a process that asked for it
/// (map_input_files, mapped_file.hpp), its pages mapped instead. Throws
/// refit::Error naming `path` when it cannot be opened, is not a regular file,
/// or cannot be read whole.
TextBytes read_file_bytes(const std::string& path, bool may_map = false);

}  // namespace refit
