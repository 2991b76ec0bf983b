#pragma once
// A garment file read through the page cache's own pages (mmap) instead of a
// copy: an opt-in of the process, as the command line makes it.
#include <sys/stat.h>

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

namespace refit {

class SourceFile;

/// Garment files read for a resize are mapped from then on instead of copied
/// into fresh memory (read_file_bytes with `may_map`). On the dense 1M dress
/// this took the load from 0.79 to 0.55 s (medians): the kernel's copy and the
/// faults of the 144 MB buffer it filled went (bench/README.md, "The garment
/// file mapped"). A mapped file that shrinks while it is read makes the reads
/// past its new end fault (SIGBUS): this installs a handler that, for a fault
/// inside a mapped input only, removes the output temporaries, says in one line
/// which file got shorter and exits with code 1 (any other SIGBUS keeps its
/// default action). For a whole process (a host's own SIGBUS handler is
/// replaced); call once, from main. Returns false where nothing was installed.
bool map_input_files();

/// Whether map_input_files() was called.
bool input_files_mapped();

/// A regular file's bytes, read-only, mapped for the object's life and known to
/// the SIGBUS handler while mapped. Changes made to the file in place show
/// through: `check_unchanged` says whether any was made since the mapping.
class MappedFile {
 public:
  /// The open file's pages (it keeps a descriptor of its own); null when the
  /// file is empty or the system cannot map it (the caller reads it instead).
  static std::unique_ptr<MappedFile> map(const SourceFile& file);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  std::string_view view() const { return {data_, size_}; }
  /// Throws refit::Error naming the file when it was written to, grew or shrank
  /// since it was mapped (its size or modification time differ).
  void check_unchanged() const;

 private:
  MappedFile(std::string path, int fd, const struct stat& at_open, const char* data, std::size_t size);
  std::string path_;
  int fd_;
  struct stat at_open_;
  const char* data_;
  std::size_t size_;
  int slot_;  // in the handler's list, or -1
};

}  // namespace refit
