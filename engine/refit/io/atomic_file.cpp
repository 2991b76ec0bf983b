#include <refit/core/error.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/file_bytes.hpp>

#include <refit/core/parallel.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sys/stat.h>
#include <unistd.h>

namespace refit {

namespace {

namespace fs = std::filesystem;

// Temporaries alive now, for the signal handler: fixed slots of plain chars, so
// that the handler reads them without locks or allocation.
constexpr std::size_t kSlots = 64, kPathMax = 4096;
std::array<std::array<char, kPathMax>, kSlots> g_temporary{};
std::array<std::atomic<bool>, kSlots> g_used{};
std::mutex g_slot_mutex;

int hold_temporary(const fs::path& tmp) {
  const std::string s = tmp.string();
  if (s.size() >= kPathMax) return -1;
  const std::lock_guard<std::mutex> lock(g_slot_mutex);
  for (std::size_t i = 0; i < kSlots; ++i)
    if (!g_used[i].load()) {
      std::memcpy(g_temporary[i].data(), s.c_str(), s.size() + 1);
      g_used[i].store(true);
      return int(i);
    }
  return -1;  // more than kSlots at once: that one is not removed on a signal
}

void release_temporary(int slot) {
  if (slot >= 0) g_used[std::size_t(slot)].store(false);
}

extern "C" void remove_temporaries_and_die(int sig) {
  for (std::size_t i = 0; i < kSlots; ++i)
    if (g_used[i].load()) ::unlink(g_temporary[i].data());
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

thread_local OutputBatch* g_batch = nullptr;

// The temporary, held for the signal handler while it lives.
class Temporary {
 public:
  explicit Temporary(const fs::path& target)
      : path_(target.parent_path() / ("." + target.filename().string() + ".tmp" + std::to_string(::getpid()))),
        slot_(hold_temporary(path_)) {}
  ~Temporary() {
    if (!kept_) {
      std::error_code ignore;
      fs::remove(path_, ignore);
    }
    release_temporary(slot_);
  }
  const fs::path& path() const { return path_; }
  void keep() { kept_ = true; }

 private:
  fs::path path_;
  int slot_;
  bool kept_ = false;
};

void rename_or_throw(const fs::path& tmp, const fs::path& target, const std::string& path) {
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) throw input_error(path, "cannot rename temporary file: " + ec.message());
}

}  // namespace

fs::path checked_output_path(const std::string& path) {
  if (path.empty()) throw Error("an output path is empty");
  fs::path target(path);
  // Follow symbolic links to the file they name: that file is replaced, the link stays.
  for (int hops = 0; fs::is_symlink(fs::symlink_status(target)); ++hops) {
    if (hops == 40) throw input_error(path, "too many levels of symbolic links");
    const fs::path next = fs::read_symlink(target);
    target = next.is_absolute() ? next : target.parent_path() / next;
  }
  struct stat st {};
  if (::stat(target.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) throw input_error(path, "is a directory, not an output file");
    if (S_ISFIFO(st.st_mode)) throw input_error(path, "is a FIFO: refit writes only regular files");
    if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) throw input_error(path, "is a device: refit writes only regular files");
    if (S_ISSOCK(st.st_mode)) throw input_error(path, "is a socket: refit writes only regular files");
    if (!S_ISREG(st.st_mode)) throw input_error(path, "is not a regular file");
  }
  const fs::path folder = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw input_error(path, "its folder " + folder.string() + " does not exist");
  if (::access(folder.c_str(), W_OK) != 0)
    throw input_error(path, "cannot write in its folder " + folder.string() + ": " + std::strerror(errno));
  return target;
}

void check_outputs(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
  const auto same = [](const fs::path& x, const fs::path& y) {
    std::error_code ec;
    if (fs::equivalent(x, y, ec)) return true;  // both exist: same inode
    return fs::weakly_canonical(x, ec) == fs::weakly_canonical(y, ec) && !ec;
  };
  std::vector<fs::path> seen;
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const fs::path target = checked_output_path(outputs[i]);
    for (const std::string& in : inputs)
      if (same(target, in)) throw input_error(outputs[i], "is an input of this run (" + in + "): not overwritten");
    for (std::size_t j = 0; j < seen.size(); ++j)
      if (same(target, seen[j]))
        throw input_error(outputs[i], "is also the output " + outputs[j] + ": each output needs its own file");
    seen.push_back(target);
  }
}

// Renames the written temporary over the target, or leaves it to the batch.
void finish_output(const fs::path& tmp, const fs::path& target, const std::string& path) {
  if (g_batch) {
    g_batch->staged_.emplace_back(tmp, target);
    g_batch->names_.push_back(path);
    g_batch->slots_.push_back(hold_temporary(tmp));
    return;
  }
  rename_or_throw(tmp, target, path);
}

OutputBatch::OutputBatch() : outer_(g_batch) { g_batch = this; }

OutputBatch::~OutputBatch() {
  if (g_batch == this) g_batch = outer_;
  for (const auto& [tmp, target] : staged_) {
    std::error_code ignore;
    fs::remove(tmp, ignore);
  }
  for (int slot : slots_) release_temporary(slot);
}

void OutputBatch::commit() {
  if (g_batch == this) g_batch = outer_;
  // Into the enclosing batch if there is one. A rename that fails (the folder
  // vanished) throws, and the destructor removes the rest.
  for (std::size_t i = 0; i < staged_.size(); ++i) finish_output(staged_[i].first, staged_[i].second, names_[i]);
  staged_.clear();
}

void remove_temporaries_on_signal() {
  struct sigaction sa {};
  sa.sa_handler = remove_temporaries_and_die;
  sigemptyset(&sa.sa_mask);
  ::sigaction(SIGINT, &sa, nullptr);
  ::sigaction(SIGTERM, &sa, nullptr);
}

void write_parts_atomically(const std::string& path, std::size_t count, const PartFormatter& format) {
  const fs::path target = checked_output_path(path);
  Temporary temporary(target);
  const fs::path& tmp = temporary.path();
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
    finish_output(tmp, target, path);
    temporary.keep();
  } catch (...) {
    if (fd >= 0) ::close(fd);
    throw;
  }
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const fs::path target = checked_output_path(path);
  Temporary temporary(target);
  {
    std::ofstream out(temporary.path(), std::ios::binary | std::ios::trunc);
    if (!out) throw input_error(path, std::string("cannot open for writing: ") + std::strerror(errno));
    write(out);
    out.flush();
    if (!out) throw input_error(path, "write failed (disk full?)");
  }
  finish_output(temporary.path(), target, path);
  temporary.keep();
}

}  // namespace refit
