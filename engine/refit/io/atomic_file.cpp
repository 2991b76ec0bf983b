#include <refit/core/error.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/file_bytes.hpp>

#include <refit/core/parallel.hpp>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace refit {

namespace {

std::filesystem::path temporary_for(const std::filesystem::path& target) {
  return target.parent_path() / (target.filename().string() + ".tmp" + std::to_string(::getpid()));
}

void rename_or_throw(const std::filesystem::path& tmp, const std::filesystem::path& target, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, target, ec);
  if (ec) throw input_error(path, "cannot rename temporary file: " + ec.message());
}

}  // namespace

void write_parts_atomically(const std::string& path, std::size_t count, const PartFormatter& format) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path tmp = temporary_for(target);
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw input_error(path, std::string("cannot open for writing: ") + std::strerror(errno));
  try {
    // 64 parts of a few hundred kB: enough work per batch for the threads, and
    // buffers small enough that reusing them costs no fresh pages.
    constexpr std::size_t kBatch = 64;
    std::vector<std::string> buffer(std::min(count, kBatch));
    std::vector<off_t> offset(buffer.size() + 1, 0);
    std::atomic<int> error{0};
    for (std::size_t first = 0; first < count; first += kBatch) {
      const std::size_t m = std::min(kBatch, count - first);
      parallel_for(0, m, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
          buffer[i].clear();
          format(first + i, buffer[i]);
        }
      });
      for (std::size_t i = 0; i < m; ++i) offset[i + 1] = offset[i] + static_cast<off_t>(buffer[i].size());
      parallel_for(0, m, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e && error.load() == 0; ++i) {
          const int failed = transfer_all(fd, buffer[i].data(), buffer[i].size(), offset[i], true);
          int expected = 0;
          if (failed != 0) error.compare_exchange_strong(expected, failed < 0 ? EIO : failed);
        }
      });
      if (error.load() != 0) throw input_error(path, std::string("write failed: ") + std::strerror(error.load()));
      offset[0] = offset[m];
    }
    const int closed = ::close(fd);
    fd = -1;
    if (closed != 0) throw input_error(path, std::string("write failed: ") + std::strerror(errno));
    rename_or_throw(tmp, target, path);
  } catch (...) {
    if (fd >= 0) ::close(fd);
    std::error_code ignore;
    fs::remove(tmp, ignore);
    throw;
  }
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path tmp = temporary_for(target);
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw input_error(path, "cannot open for writing");
      write(out);
      out.flush();
      if (!out) throw input_error(path, "write failed (disk full?)");
    }
    rename_or_throw(tmp, target, path);
  } catch (...) {
    std::error_code ignore;
    fs::remove(tmp, ignore);
    throw;
  }
}

}  // namespace refit
