#include <refit/core/error.hpp>
#include <refit/io/atomic_file.hpp>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace refit {

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  const fs::path tmp = target.parent_path() /
                       (target.filename().string() + ".tmp" + std::to_string(::getpid()));
  try {
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw input_error(path, "cannot open for writing");
      write(out);
      out.flush();
      if (!out) throw input_error(path, "write failed (disk full?)");
    }
    std::error_code ec;
    fs::rename(tmp, target, ec);
    if (ec) throw input_error(path, "cannot rename temporary file: " + ec.message());
  } catch (...) {
    std::error_code ignore;
    fs::remove(tmp, ignore);
    throw;
  }
}

}  // namespace refit
