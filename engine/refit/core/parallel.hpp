#pragma once
// The one place algorithms meet threading. Every loop body must write only to
// its own indices, and reductions go through deterministic_sum, so results never
// depend on the thread count.
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <cstddef>
#include <memory>

namespace refit {

/// f(begin, end) over [first, last) in chunks of about `grain` indices.
template <class F>
void parallel_for(std::size_t first, std::size_t last, std::size_t grain, F&& f) {
  if (last <= first) return;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(first, last, grain ? grain : 1),
                    [&](const tbb::blocked_range<std::size_t>& r) { f(r.begin(), r.end()); },
                    tbb::simple_partitioner());
}

/// Sum of term(i) over [first, last), bit-identical whatever the thread count
/// (fixed chunking, fixed combination order).
template <class T, class F>
T deterministic_sum(std::size_t first, std::size_t last, std::size_t grain, T zero, F&& term) {
  if (last <= first) return zero;
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(first, last, grain ? grain : 1), zero,
      [&](const tbb::blocked_range<std::size_t>& r, T acc) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) acc += term(i);
        return acc;
      },
      [](T a, const T& b) { return a += b; });
}

/// Caps the worker threads while alive (0 = no cap).
class ThreadLimit {
 public:
  explicit ThreadLimit(std::size_t threads) {
    if (threads > 0)
      control_ = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
  }

 private:
  std::unique_ptr<tbb::global_control> control_;
};

}  // namespace refit
