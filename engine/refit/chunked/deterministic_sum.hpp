#pragma once
// deterministic_sum (core/parallel.hpp) over terms that come in chunks: the
// same leaves of TBB's deterministic reduction (blocked_range halved while
// larger than the grain), each summed from zero in index order, then joined
// in the same tree, so the chunked mode's sums have the in-memory bits.
#include <cstddef>
#include <vector>

namespace refit {

class DeterministicSum {
 public:
  DeterministicSum(std::size_t first, std::size_t last, std::size_t grain) : first_(first), last_(last) {
    if (grain == 0) grain = 1;
    if (last > first) split(first, last, grain);
    sums_.assign(ends_.size(), 0.0);
  }
  /// Term i; i must go up by one from `first` on.
  void add(std::size_t i, double term) {
    while (ends_[leaf_] <= i) ++leaf_;
    sums_[leaf_] += term;
  }
  double result() const {
    if (last_ <= first_) return 0.0;
    std::size_t leaf = 0;
    return join(first_, last_, leaf);
  }

 private:
  void split(std::size_t b, std::size_t e, std::size_t grain) {
    if (e - b > grain) {
      const std::size_t m = b + (e - b) / 2;
      split(b, m, grain);
      split(m, e, grain);
    } else {
      ends_.push_back(e);
      grain_ = grain;
    }
  }
  double join(std::size_t b, std::size_t e, std::size_t& leaf) const {
    if (e - b > grain_) {
      const std::size_t m = b + (e - b) / 2;
      double left = join(b, m, leaf);
      left += join(m, e, leaf);
      return left;
    }
    return sums_[leaf++];
  }

  std::size_t first_, last_, grain_ = 1, leaf_ = 0;
  std::vector<std::size_t> ends_;  // end of each leaf, in order
  std::vector<double> sums_;
};

}  // namespace refit
