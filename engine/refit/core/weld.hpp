#pragma once
// Welding coincident points: the same surface given as a polygon soup or with
// split seams (coincident but separate vertices) becomes connected again. Used
// by the feature curves (slices, boundary loops) and the surface step (layers).
#include <refit/core/types.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace refit {

/// Hash of integer grid-cell coordinates. The coordinates are mixed (xor of odd
/// multiples, then a 64-bit finaliser): the plain xor of multiples puts whole
/// rows of a regular grid of cells into a few buckets, which made welding a
/// 1M-vertex garment take seconds.
struct CellHash {
  std::size_t operator()(const std::array<std::int64_t, 3>& k) const {
    std::uint64_t h = static_cast<std::uint64_t>(k[0]) * 0x9E3779B97F4A7C15ULL ^
                      static_cast<std::uint64_t>(k[1]) * 0xC2B2AE3D27D4EB4FULL ^
                      static_cast<std::uint64_t>(k[2]) * 0x165667B19E3779F9ULL;
    h ^= h >> 32;
    h *= 0xD6E8FEB86659FD93ULL;
    h ^= h >> 32;
    return static_cast<std::size_t>(h);
  }
};

/// Diagonal of the axis-aligned bounding box of the rows (0 when empty).
double bounding_box_diagonal(const Points& p);

/// Welds points closer than `tolerance` (grid hashing): returns, per row, the index
/// of its representative: in row order, each point joins the lowest-numbered
/// representative within `tolerance`, or becomes one (so a cluster's
/// representative is its first row, and the result is deterministic). Points with
/// no other point within `tolerance` (most of a garment) are found in parallel
/// first; only the others go through the sequential clustering. Points must be finite.
std::vector<Index> weld_points(const Points& p, double tolerance);

/// weld_points in passes over chunks of rows, for point sets not in memory
/// (the chunked mode, issue 14): the same representatives. Pass 1: mark(rows)
/// for every chunk (any order); pass 2: candidates(rows) for every chunk (any
/// order), the rows that may have a twin; pass 3: cluster(rows, their
/// candidates) for every chunk in row order, which gives each chunk's
/// representatives.
class PointWelder {
 public:
  PointWelder(std::size_t points, double tolerance);
  ~PointWelder();
  void mark(const Points& rows);
  std::vector<std::uint8_t> candidates(const Points& rows) const;
  /// Rows [first, first + rows.rows()), in order after the rows before them.
  std::vector<Index> cluster(std::size_t first, const Points& rows, const std::vector<std::uint8_t>& candidate);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace refit
