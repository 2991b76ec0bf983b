#pragma once
// Output files appear whole or not at all: write to a temporary file beside the
// target, then rename over it. On any exception the temporary is removed.
//
// What an output may replace (docs/cli-errors.md): a regular file, or through a
// symbolic link the regular file it points to (the link stays); never a
// directory, a device, a FIFO or a socket. The folder must exist.
#include <filesystem>
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

namespace refit {

/// Where writing `path` puts the file (a symbolic link's final target); throws
/// refit::Error naming `path` when it may not be written (see above).
std::filesystem::path checked_output_path(const std::string& path);

/// Before the work of a run: every output may be written (checked_output_path),
/// no two outputs are the same file, and none is one of the inputs (after
/// following symbolic links; hard links count too). Throws refit::Error naming
/// the output and the file it would clobber.
void check_outputs(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs);

namespace detail {
class TemporaryFile;
}

/// Outputs that appear together: while an OutputBatch lives on this thread, the
/// writers below leave their temporary files in it instead of renaming them;
/// commit() renames them all (or hands them to the enclosing batch), and a batch
/// destroyed without commit() removes them, so a failure part way leaves nothing new.
class OutputBatch {
 public:
  OutputBatch();
  ~OutputBatch();
  OutputBatch(const OutputBatch&) = delete;
  OutputBatch& operator=(const OutputBatch&) = delete;
  void commit();

 private:
  friend void finish_output(std::unique_ptr<detail::TemporaryFile>);
  std::vector<std::unique_ptr<detail::TemporaryFile>> staged_;
  OutputBatch* outer_;
};

/// An output folder made for a run (with the missing folders above it): unless
/// keep() is called, the destructor removes those of them that are still empty,
/// so a run that fails leaves no new folder either. Throws refit::Error naming
/// `path` when it exists and is not a folder, or cannot be made.
class OutputFolder {
 public:
  explicit OutputFolder(const std::string& path);
  ~OutputFolder() { remove_created(); }
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  void keep() { created_.clear(); }

 private:
  void remove_created();
  std::vector<std::filesystem::path> created_;  // innermost first
};

/// Temporaries are removed when SIGINT, SIGTERM or SIGHUP ends the process (then
/// the signal's default action runs); a signal the process was started ignoring
/// stays ignored. Call once, from main.
void remove_temporaries_on_signal();

/// Removes the temporaries alive now; safe inside a signal handler (no locks,
/// no allocation). For a handler that ends the process some other way.
void remove_temporaries_now();

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// Appends part k of a text to `out` (an emptied buffer).
using PartFormatter = std::function<void(std::size_t k, std::string& out)>;

/// The same for a text made of `count` parts, written one after another. Parts
/// are formatted in parallel a batch at a time into buffers reused from batch to
/// batch, and each goes straight to its offset (pwrite) instead of through one
/// buffered stream: the whole text never sits in memory (a 4M-vertex garment is
/// 364 MB of it). Throws refit::Error naming `path` when the file cannot be
/// written; an exception from `format` propagates; either way nothing is left.
/// `batch`: parts formatted at once (their buffers are what the write holds).
void write_parts_atomically(const std::string& path, std::size_t count, const PartFormatter& format,
                            std::size_t batch = 64);

}  // namespace refit
