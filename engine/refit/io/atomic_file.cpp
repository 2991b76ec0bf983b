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
#include <sys/stat.h>
#include <unistd.h>

namespace refit {

namespace fs = std::filesystem;

namespace {

// Temporaries alive now, for the signal handler: slots of C strings owned by
// their TemporaryFile, so that the handler reads them without locks or allocation.
constexpr std::size_t kSlots = 4096;
std::array<std::atomic<const char*>, kSlots> g_temporary{};

int hold_temporary(const char* path) {
  for (std::size_t i = 0; i < kSlots; ++i) {
    const char* expected = nullptr;
    if (g_temporary[i].compare_exchange_strong(expected, path)) return int(i);
  }
  return -1;  // more than kSlots at once: that one is not removed on a signal
}

extern "C" void remove_temporaries_and_die(int sig) {
  remove_temporaries_now();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

thread_local OutputBatch* g_batch = nullptr;
std::atomic<unsigned> g_temporary_count{0};

// ".out.obj.<pid>.<n>.tmp" beside out.obj: hidden, and unique per process and call.
fs::path temporary_name(const fs::path& target) {
  std::string name = ".";  // not "." + string: GCC 12's false -Wrestrict (bug 105329)
  name += target.filename().string();
  name += '.';
  name += std::to_string(::getpid());
  name += '.';
  name += std::to_string(g_temporary_count.fetch_add(1));
  name += ".tmp";
  return target.parent_path() / name;
}

}  // namespace

namespace detail {

// A temporary file beside its target, held for the signal handler while it
// exists; removed by the destructor unless renamed over the target.
class TemporaryFile {
 public:
  TemporaryFile(fs::path target, std::string name)
      : target_(std::move(target)), name_(std::move(name)), path_(temporary_name(target_)),
        slot_(hold_temporary(path_.c_str())) {}
  ~TemporaryFile() {
    if (!renamed_) {
      std::error_code ignore;
      fs::remove(path_, ignore);
    }
    if (slot_ >= 0) g_temporary[std::size_t(slot_)].store(nullptr);
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  const fs::path& path() const { return path_; }
  const std::string& name() const { return name_; }

  void rename_over_target() {
    std::error_code ec;
    fs::rename(path_, target_, ec);
    if (ec) throw input_error(name_, "cannot rename temporary file: " + ec.message());
    renamed_ = true;
  }

 private:
  fs::path target_;
  std::string name_;  // as the user gave it
  fs::path path_;
  int slot_;
  bool renamed_ = false;
};

}  // namespace detail

using detail::TemporaryFile;

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
      if (!in.empty() && same(target, in))
        throw input_error(outputs[i], "is an input of this run (" + in + "): not overwritten");
    for (std::size_t j = 0; j < seen.size(); ++j)
      if (same(target, seen[j]))
        throw input_error(outputs[i], "is also the output " + outputs[j] + ": each output needs its own file");
    seen.push_back(target);
  }
}

// Renames the written temporary over its target, or leaves it to the batch.
void finish_output(std::unique_ptr<TemporaryFile> temporary) {
  if (g_batch)
    g_batch->staged_.push_back(std::move(temporary));
  else
    temporary->rename_over_target();
}

OutputBatch::OutputBatch() : outer_(g_batch) { g_batch = this; }

OutputBatch::~OutputBatch() {
  if (g_batch == this) g_batch = outer_;
  staged_.clear();  // removes the temporaries not renamed
}

void OutputBatch::commit() {
  if (g_batch == this) g_batch = outer_;
  // Into the enclosing batch if there is one. A rename that fails (the folder
  // vanished) throws, and the destructor removes the rest.
  for (auto& temporary : staged_) finish_output(std::move(temporary));
  staged_.clear();
}

OutputFolder::OutputFolder(const std::string& path) {
  std::error_code ec;
  const fs::path folder(path);
  if (fs::exists(folder, ec)) {
    if (!fs::is_directory(folder, ec)) throw input_error(path, "is not a folder");
    return;
  }
  for (fs::path p = folder; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    created_.push_back(p);
    if (p == p.parent_path()) break;
  }
  fs::create_directories(folder, ec);
  if (ec) {
    remove_created();  // what was made of the chain goes again
    throw input_error(path, "cannot create the folder: " + ec.message());
  }
}

void OutputFolder::remove_created() {
  for (const fs::path& p : created_) {
    std::error_code ignore;
    fs::remove(p, ignore);  // only an empty folder goes
  }
  created_.clear();
}

void remove_temporaries_now() {
  for (auto& slot : g_temporary)
    if (const char* path = slot.load()) ::unlink(path);
}

void remove_temporaries_on_signal() {
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;  // nohup, `&` in a script
    struct sigaction sa {};
    sa.sa_handler = remove_temporaries_and_die;
    sigemptyset(&sa.sa_mask);
    ::sigaction(sig, &sa, nullptr);
  }
}

void write_parts_atomically(const std::string& path, std::size_t count, const PartFormatter& format,
                            std::size_t batch) {
  auto temporary = std::make_unique<TemporaryFile>(checked_output_path(path), path);
  const fs::path& tmp = temporary->path();
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw input_error(path, std::string("cannot open for writing: ") + std::strerror(errno));
  try {
    // 64 parts of a few hundred kB by default: enough work per batch for the
    // threads, and buffers small enough that reusing them costs no fresh pages.
    const std::size_t parts = std::max<std::size_t>(batch, 1);
    std::vector<std::string> buffer(std::min(count, parts));
    std::vector<off_t> offset(buffer.size() + 1, 0);
    std::atomic<int> error{0};
    for (std::size_t first = 0; first < count; first += parts) {
      const std::size_t m = std::min(parts, count - first);
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
  } catch (...) {
    if (fd >= 0) ::close(fd);
    throw;
  }
  finish_output(std::move(temporary));
}

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  auto temporary = std::make_unique<TemporaryFile>(checked_output_path(path), path);
  {
    std::ofstream out(temporary->path(), std::ios::binary | std::ios::trunc);
    if (!out) throw input_error(path, std::string("cannot open for writing: ") + std::strerror(errno));
    write(out);
    out.flush();
    if (!out) throw input_error(path, "write failed (disk full?)");
  }
  finish_output(std::move(temporary));
}

}  // namespace refit
