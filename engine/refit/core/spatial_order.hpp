#pragma once
// A walk through a point set in space-filling-curve order. Nearest-neighbour
// style queries run in this order touch memory that the previous query
// touched, and a query can start from the previous one's answer; the queries'
// results do not depend on the order, only their speed does.
#include <refit/core/types.hpp>

#include <functional>
#include <vector>

namespace refit {

/// The rows of `points` in Morton (Z-curve) order of a 2^21 grid over their
/// bounding box, ties by row, and their 63-bit keys in that order (non-finite
/// rows last, with key 2^64 - 1). Deterministic and parallel.
struct CurveOrder {
  UninitVector<Index> order;
  UninitVector<std::uint64_t> key;  // key[k]: the key of row order[k] (ascending)
};
CurveOrder curve_order(const Points& points);
/// The same for n points given by point(i) (no matrix of them is made).
CurveOrder curve_order(std::size_t n, const std::function<Vec3(std::size_t)>& point);

/// The low 21 bits of x spread to every third bit (one axis of a Morton key).
inline std::uint64_t spread3(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

/// curve_order(points).order.
UninitVector<Index> spatial_order(const Points& points);

}  // namespace refit
