#include <refit/io/file_bytes.hpp>

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace refit {

int transfer_all(int fd, char* data, std::size_t size, off_t at, bool write) {
  while (size > 0) {
    const ssize_t n = write ? ::pwrite(fd, data, size, at) : ::pread(fd, data, size, at);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return errno;
    if (n == 0) return -1;
    data += n;
    size -= static_cast<std::size_t>(n);
    at += n;
  }
  return 0;
}

TextBytes read_file_bytes(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw input_error(path, std::string("cannot open: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw input_error(path, "cannot read: not a regular file");
  }
  TextBytes bytes(static_cast<std::size_t>(st.st_size));
  constexpr std::size_t kRange = std::size_t(1) << 23;
  std::atomic<int> error{0};  // the first failure, as transfer_all returns it
  parallel_for(0, (bytes.size() + kRange - 1) / kRange, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t r = b; r < e && error.load() == 0; ++r) {
      const std::size_t at = r * kRange;
      const int failed = transfer_all(fd, bytes.data() + at, std::min(kRange, bytes.size() - at), static_cast<off_t>(at), false);
      int expected = 0;
      if (failed != 0) error.compare_exchange_strong(expected, failed);
    }
  });
  ::close(fd);
  if (error.load() > 0) throw input_error(path, std::string("cannot read: ") + std::strerror(error.load()));
  if (error.load() < 0) throw input_error(path, "cannot read the whole file (it got shorter while being read)");
  return bytes;
}

}  // namespace refit
