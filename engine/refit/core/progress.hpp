#pragma once
// Progress lines on stderr for long runs; silent when quiet; or each stage's
// name handed to a sink (the Python module's callback, Blender's status bar).
#include <chrono>
#include <functional>
#include <string>

namespace refit {

class Progress {
 public:
  using Sink = std::function<void(const std::string& stage)>;
  explicit Progress(bool quiet = false) : quiet_(quiet) {}
  explicit Progress(Sink sink) : quiet_(false), sink_(std::move(sink)) {}
  void stage(const std::string& what) const;
  bool quiet() const { return quiet_; }

 private:
  bool quiet_;
  Sink sink_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

/// Wall-clock milliseconds since construction.
class Stopwatch {
 public:
  double ms() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  }
  void reset() { start_ = std::chrono::steady_clock::now(); }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

/// Peak resident set size of this process in MB (VmHWM), 0 if unknown.
double peak_memory_mb();

/// This machine's memory in MB (physical pages), 0 if unknown.
double physical_memory_mb();

}  // namespace refit
