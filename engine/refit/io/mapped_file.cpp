#include <refit/io/mapped_file.hpp>

#include <refit/core/error.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/file_bytes.hpp>

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <csignal>
#include <cstring>

namespace refit {

namespace {

std::atomic<bool> g_map{false};

// The mappings alive now, for the SIGBUS handler: read there without locks or
// allocation (the path is owned by its MappedFile).
struct MappedSlot {
  std::atomic<bool> taken{false};
  std::atomic<const char*> begin{nullptr};
  std::atomic<std::size_t> size{0};
  std::atomic<const char*> path{nullptr};
};
constexpr std::size_t kMappedSlots = 64;
std::array<MappedSlot, kMappedSlots> g_mapped;

int hold_mapping(const char* begin, std::size_t size, const char* path) {
  for (std::size_t i = 0; i < kMappedSlots; ++i) {
    bool expected = false;
    if (!g_mapped[i].taken.compare_exchange_strong(expected, true)) continue;
    g_mapped[i].size.store(size);
    g_mapped[i].path.store(path);
    g_mapped[i].begin.store(begin);
    return int(i);
  }
  return -1;
}

void release_mapping(int slot) {
  if (slot < 0) return;
  g_mapped[std::size_t(slot)].begin.store(nullptr);
  g_mapped[std::size_t(slot)].taken.store(false);
}

void say_on_stderr(const char* text) {
  std::size_t left = std::strlen(text);
  while (left > 0) {
    const ssize_t n = ::write(STDERR_FILENO, text, left);
    if (n <= 0) return;
    text += n;
    left -= std::size_t(n);
  }
}

extern "C" void on_bus_error(int sig, siginfo_t* info, void*) {
  const char* at = static_cast<const char*>(info->si_addr);
  const bool fault = info->si_code > 0;  // not sent by kill() or raise()
  for (const MappedSlot& s : g_mapped) {
    const char* begin = s.begin.load();
    if (!fault || !begin || at < begin || at >= begin + s.size.load()) continue;
    say_on_stderr("refit: error: ");
    say_on_stderr(s.path.load());
    say_on_stderr(": cannot read: the file got shorter while it was being read; nothing written\n");
    remove_temporaries_now();
    ::_exit(1);
  }
  // Not a mapped input's: the default action (a fault repeats and ends the process).
  std::signal(sig, SIG_DFL);
  if (!fault) std::raise(sig);
}

bool same_time(const struct timespec& a, const struct timespec& b) { return a.tv_sec == b.tv_sec && a.tv_nsec == b.tv_nsec; }

}  // namespace

bool map_input_files() {
  struct sigaction sa {};
  sa.sa_sigaction = on_bus_error;
  sa.sa_flags = SA_SIGINFO;
  sigemptyset(&sa.sa_mask);
  if (::sigaction(SIGBUS, &sa, nullptr) != 0) return false;
  g_map.store(true);
  return true;
}

bool input_files_mapped() { return g_map.load(); }

std::unique_ptr<MappedFile> MappedFile::map(const SourceFile& file) {
  const int fd = ::fcntl(file.fd(), F_DUPFD_CLOEXEC, 0);
  if (fd < 0) return nullptr;
  struct stat st {};
  void* data = MAP_FAILED;
  if (::fstat(fd, &st) == 0 && st.st_size > 0)
    data = ::mmap(nullptr, std::size_t(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
  if (data == MAP_FAILED) {
    ::close(fd);
    return nullptr;
  }
  std::unique_ptr<MappedFile> m(new MappedFile(file.path(), fd, st, static_cast<const char*>(data), std::size_t(st.st_size)));
  if (m->slot_ < 0) return nullptr;  // more files mapped at once than the handler knows: read instead
  return m;
}

MappedFile::MappedFile(std::string path, int fd, const struct stat& at_open, const char* data, std::size_t size)
    : path_(std::move(path)), fd_(fd), at_open_(at_open), data_(data), size_(size),
      slot_(hold_mapping(data, size, path_.c_str())) {}

MappedFile::~MappedFile() {
  release_mapping(slot_);
  ::munmap(const_cast<char*>(data_), size_);
  ::close(fd_);
}

void MappedFile::check_unchanged() const {
  struct stat now {};
  if (::fstat(fd_, &now) != 0 || now.st_size != at_open_.st_size || !same_time(now.st_mtim, at_open_.st_mtim) ||
      !same_time(now.st_ctim, at_open_.st_ctim))
    throw input_error(path_, "the file changed while it was being read; nothing written");
}

}  // namespace refit
