#include <refit/core/progress.hpp>

#include <cstdio>
#include <fstream>
#include <string>
#include <unistd.h>

namespace refit {

void Progress::stage(const std::string& what) const {
  if (quiet_) return;
  if (sink_) return sink_(what);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "[refit %7.2fs] %s\n", s, what.c_str());
}

double peak_memory_mb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return 0.0;
}

double physical_memory_mb() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) / (1024.0 * 1024.0) : 0.0;
}

}  // namespace refit
