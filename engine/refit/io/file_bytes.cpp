#include <refit/io/file_bytes.hpp>

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/mapped_file.hpp>

#include <atomic>
#include <utility>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace refit {

TextBytes::TextBytes() = default;
TextBytes::TextBytes(std::size_t size) : owned_(new char[size]), bytes_(owned_.get()), size_(size) {}
TextBytes::TextBytes(std::string_view text) : TextBytes(text.size()) { std::copy(text.begin(), text.end(), owned_.get()); }
TextBytes::TextBytes(std::unique_ptr<MappedFile> mapped)
    : mapped_(std::move(mapped)), bytes_(mapped_->view().data()), size_(mapped_->view().size()) {}
TextBytes::TextBytes(TextBytes&& o) noexcept
    : owned_(std::move(o.owned_)), mapped_(std::move(o.mapped_)), bytes_(std::exchange(o.bytes_, nullptr)),
      size_(std::exchange(o.size_, 0)) {}
TextBytes& TextBytes::operator=(TextBytes&& o) noexcept {
  owned_ = std::move(o.owned_);
  mapped_ = std::move(o.mapped_);
  bytes_ = std::exchange(o.bytes_, nullptr);
  size_ = std::exchange(o.size_, 0);
  return *this;
}
TextBytes::~TextBytes() = default;

void TextBytes::check_unchanged() const {
  if (mapped_) mapped_->check_unchanged();
}

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

namespace {

// Bytes [at, at + size) of `fd` into `data`, several threads reading 8 MB ranges
// at once (the kernel's copy and the first touch of the pages were most of a
// large garment's read time on one thread).
void read_ranges(int fd, char* data, std::size_t size, std::size_t at, const std::string& path) {
  constexpr std::size_t kRange = std::size_t(1) << 23;
  std::atomic<int> error{0};  // the first failure, as transfer_all returns it
  parallel_for(0, (size + kRange - 1) / kRange, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t r = b; r < e && error.load() == 0; ++r) {
      const std::size_t off = r * kRange;
      const int failed = transfer_all(fd, data + off, std::min(kRange, size - off), static_cast<off_t>(at + off), false);
      int expected = 0;
      if (failed != 0) error.compare_exchange_strong(expected, failed);
    }
  });
  if (error.load() > 0) throw input_error(path, std::string("cannot read: ") + std::strerror(error.load()));
  if (error.load() < 0) throw input_error(path, "cannot read the whole file (it got shorter while being read)");
}

}  // namespace

SourceFile::SourceFile(const std::string& path) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw input_error(path, std::string("cannot open: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd_);
    throw input_error(path, "cannot read: not a regular file");
  }
  size_ = static_cast<std::size_t>(st.st_size);
}

SourceFile::~SourceFile() { ::close(fd_); }

void SourceFile::read(std::size_t at, std::size_t size, std::string& out) const {
  // A larger read than the last frees the old text first: growing in place
  // keeps both (and doubles the capacity), so a pass reading 64 MB groups of a
  // 1M-vertex file held 140 MB.
  if (size > out.capacity()) {
    out.clear();
    out.shrink_to_fit();
  }
  out.resize(size);
  read_ranges(fd_, out.data(), size, at, path_);
}

std::size_t SourceFile::find_newline(std::size_t at) const {
  char buf[4096];
  while (at < size_) {
    const std::size_t n = std::min(sizeof buf, size_ - at);
    const int failed = transfer_all(fd_, buf, n, off_t(at), false);
    if (failed != 0) throw input_error(path_, "cannot read the whole file");
    if (const void* nl = std::memchr(buf, '\n', n)) return at + std::size_t(static_cast<const char*>(nl) - buf);
    at += n;
  }
  return size_;
}

TextBytes read_file_bytes(const std::string& path, bool may_map) {
  const SourceFile file(path);
  if (may_map && input_files_mapped())
    if (auto mapped = MappedFile::map(file)) return TextBytes(std::move(mapped));
  TextBytes bytes(file.size());
  read_ranges(file.fd(), bytes.data(), bytes.size(), 0, path);
  return bytes;
}

}  // namespace refit
