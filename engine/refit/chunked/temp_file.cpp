#include <refit/chunked/temp_file.hpp>

#include <refit/core/error.hpp>
#include <refit/io/file_bytes.hpp>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <unistd.h>

namespace refit {

TempFile::TempFile(const std::filesystem::path& folder) : folder_(folder.string()) {
#ifdef O_TMPFILE
  fd_ = ::open(folder_.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
#endif
  if (fd_ < 0) {  // a file system without O_TMPFILE: a named file, unlinked at once
    std::string name = (folder / "refit-chunk-XXXXXX").string();
    fd_ = ::mkostemp(name.data(), O_CLOEXEC);
    if (fd_ >= 0) ::unlink(name.c_str());
  }
  if (fd_ < 0)
    throw input_error(folder_, std::string("cannot make a temporary file for the chunked mode: ") + std::strerror(errno));
}

TempFile::~TempFile() {
  if (fd_ >= 0) ::close(fd_);
}

TempFile::TempFile(TempFile&& o) noexcept : folder_(std::move(o.folder_)), fd_(o.fd_), size_(o.size_) { o.fd_ = -1; }

TempFile& TempFile::operator=(TempFile&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    folder_ = std::move(o.folder_);
    fd_ = o.fd_;
    size_ = o.size_;
    o.fd_ = -1;
  }
  return *this;
}

void TempFile::write(const void* data, std::size_t bytes, std::size_t at) {
  const int failed = transfer_all(fd_, static_cast<char*>(const_cast<void*>(data)), bytes, off_t(at), true);
  if (failed != 0)
    throw input_error(folder_, std::string("cannot write a temporary file of the chunked mode: ") +
                                   std::strerror(failed < 0 ? EIO : failed));
  size_ = std::max(size_, at + bytes);
}

void TempFile::read(void* data, std::size_t bytes, std::size_t at) const {
  const int failed = transfer_all(fd_, static_cast<char*>(data), bytes, off_t(at), false);
  if (failed != 0)
    throw input_error(folder_, std::string("cannot read a temporary file of the chunked mode: ") +
                                   (failed < 0 ? "it is shorter than written" : std::strerror(failed)));
}

std::size_t TempFile::append(const void* data, std::size_t bytes) {
  const std::size_t at = size_;
  write(data, bytes, at);
  return at;
}

PointFile::PointFile(const std::filesystem::path& folder, std::size_t rows) : file_(folder), rows_(rows) {}

void PointFile::write(std::size_t first, const Points& rows) {
  const std::size_t n = static_cast<std::size_t>(rows.rows());
  if (first + n > rows_) throw Error("internal: point file rows out of range");
  std::vector<double> xyz(3 * n);
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) xyz[3 * i + std::size_t(k)] = rows(Eigen::Index(i), k);
  file_.write(xyz.data(), xyz.size() * sizeof(double), 3 * first * sizeof(double));
}

void PointFile::read(std::size_t first, std::size_t count, Points& out) const {
  if (first + count > rows_) throw Error("internal: point file rows out of range");
  std::vector<double> xyz(3 * count);
  file_.read(xyz.data(), xyz.size() * sizeof(double), 3 * first * sizeof(double));
  out.resize(Eigen::Index(count), 3);
  for (std::size_t i = 0; i < count; ++i)
    for (int k = 0; k < 3; ++k) out(Eigen::Index(i), k) = xyz[3 * i + std::size_t(k)];
}

CsrFile::CsrFile(const std::filesystem::path& folder) : sizes_(folder), indices_(folder) { stride_entry_.push_back(0); }

void CsrFile::append(const Csr& rows) {
  const std::size_t n = rows.rows();
  std::vector<std::uint32_t> sizes(n);
  for (std::size_t r = 0; r < n; ++r) {
    sizes[r] = static_cast<std::uint32_t>(rows.row_size(r));
    ++rows_;
    entries_ += sizes[r];
    if (rows_ % kStride == 0) stride_entry_.push_back(entries_);
  }
  sizes_.append(sizes.data(), n * sizeof(std::uint32_t));
  indices_.append(rows.indices.data(), rows.indices.size() * sizeof(Index));
}

std::size_t CsrFile::entry_of(std::size_t r) const {
  if (r >= rows_) return entries_;
  const std::size_t s = r / kStride;
  std::size_t e = stride_entry_[s];
  if (r > s * kStride) {
    std::vector<std::uint32_t> sizes(r - s * kStride);
    sizes_.read(sizes.data(), sizes.size() * sizeof(std::uint32_t), s * kStride * sizeof(std::uint32_t));
    for (std::uint32_t k : sizes) e += k;
  }
  return e;
}

void CsrFile::read(std::size_t first, std::size_t count, Csr& out) const {
  if (first + count > rows_) throw Error("internal: CSR file rows out of range");
  std::vector<std::uint32_t> sizes(count);
  sizes_.read(sizes.data(), count * sizeof(std::uint32_t), first * sizeof(std::uint32_t));
  out.offsets.resize(count + 1);
  out.offsets[0] = 0;
  for (std::size_t r = 0; r < count; ++r) out.offsets[r + 1] = out.offsets[r] + sizes[r];
  out.indices.resize(out.offsets[count]);
  indices_.read(out.indices.data(), out.indices.size() * sizeof(Index), entry_of(first) * sizeof(Index));
}

}  // namespace refit
