#include <refit/core/parallel.hpp>
#include <refit/core/spatial_order.hpp>

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace refit {

CurveOrder curve_order(const Points& p) {
  return curve_order(static_cast<std::size_t>(p.rows()), [&p](std::size_t i) { return row3(p, Index(i)); });
}

CurveOrder curve_order(std::size_t n, const std::function<Vec3(std::size_t)>& point) {
  CurveOrder out;
  out.order.resize(n);
  out.key.resize(n);
  if (n == 0) return out;
  // The finite coordinates' box (min and max: exact in any order of combination).
  struct Bounds {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    Bounds& operator+=(const Bounds& o) {
      lo = lo.cwiseMin(o.lo), hi = hi.cwiseMax(o.hi);
      return *this;
    }
  };
  const Bounds box = deterministic_sum(0, n, 1 << 14, Bounds{}, [&](std::size_t i) {
    const Vec3 v = point(i);
    Bounds b;
    for (int k = 0; k < 3; ++k)
      if (std::isfinite(v[k])) b.lo[k] = b.hi[k] = v[k];
    return b;
  });
  const Vec3 lo = box.lo, hi = box.hi;
  constexpr double kCells = double((1u << 21) - 1);
  Vec3 scale;
  for (int k = 0; k < 3; ++k) scale[k] = hi[k] > lo[k] ? kCells / (hi[k] - lo[k]) : 0.0;
  // Key: 63 Morton bits, then the row (so keys are unique and the order total).
  // The buffers are left unset and filled in parallel: their pages are first
  // touched by the threads, not zeroed by one (a million points: 36 MB).
  struct RowKey {
    std::uint64_t key;
    Index row;
    bool operator<(const RowKey& o) const { return key != o.key ? key < o.key : row < o.row; }
  };
  UninitVector<RowKey> keys(n);
  parallel_for(0, n, 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Vec3 v = point(i);
      std::uint64_t key = ~std::uint64_t{0};
      if (v.allFinite()) {
        key = 0;
        for (int k = 0; k < 3; ++k) {
          const double c = std::clamp((v[k] - lo[k]) * scale[k], 0.0, kCells);
          key |= spread3(static_cast<std::uint64_t>(c)) << k;
        }
      }
      keys[i] = {key, Index(i)};
    }
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  parallel_for(0, n, 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) out.order[i] = keys[i].row, out.key[i] = keys[i].key;
  });
  return out;
}

UninitVector<Index> spatial_order(const Points& p) { return curve_order(p).order; }

}  // namespace refit
