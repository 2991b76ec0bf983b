#pragma once
// The one place algorithms meet threading. Every loop body must write only to
// its own indices, and reductions go through deterministic_sum, so results never
// depend on the thread count.
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstddef>
#include <memory>
#include <vector>

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

/// What emit(first, last, out) appends to `out` for the fixed blocks
/// [first, last) of `block` indices that cover [0, n), run in parallel and
/// joined in block order: the same list whatever the thread count. emit may
/// write only to `out` and to what its own indices own.
template <class T, class Emit>
std::vector<T> gather_in_blocks(std::size_t n, std::size_t block, Emit&& emit) {
  if (block == 0) block = 1;
  const std::size_t blocks = (n + block - 1) / block;
  std::vector<std::vector<T>> lists(blocks);
  parallel_for(0, blocks, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) emit(k * block, std::min(n, (k + 1) * block), lists[k]);
  });
  std::vector<std::size_t> start(blocks + 1, 0);
  for (std::size_t k = 0; k < blocks; ++k) start[k + 1] = start[k] + lists[k].size();
  std::vector<T> out(start.back());
  parallel_for(0, blocks, 8, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) {
      std::move(lists[k].begin(), lists[k].end(), out.begin() + std::ptrdiff_t(start[k]));
      std::vector<T>().swap(lists[k]);
    }
  });
  return out;
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
