#include <refit/core/parallel.hpp>
#include <refit/core/weld.hpp>

#include <atomic>
#include <cmath>
#include <unordered_map>

namespace refit {

double bounding_box_diagonal(const Points& p) {
  if (p.rows() == 0) return 0.0;
  return (p.colwise().maxCoeff() - p.colwise().minCoeff()).norm();
}

// Cells of 32 tol: the tol-box around a point usually stays in its own cell
// (about 1.2 cells visited on average, each a likely cache miss below).
struct PointWelder::Impl {
  using Cell = std::array<std::int64_t, 3>;
  double tol = 0.0, reach = 0.0, inv = 0.0, tol2 = 0.0;
  std::size_t mask = 0;
  // 1. Which points may have another point within tol, in parallel: occupied
  // cells go into filters "one point" and "two or more": a cell sets two hashed
  // bits of one hashed 64-bit word (one cache miss per cell; 16 bits per point,
  // so the sets stay small enough for the cache). A collision only adds a
  // candidate, never loses one, and the final result does not depend on which
  // extra candidates there are (they find no twin in step 3). Most points of a
  // garment have no twin and are done here.
  std::vector<std::atomic<std::uint64_t>> once, twice;
  // 3. The candidates' representatives by cell, with their positions.
  std::unordered_map<Cell, std::vector<std::pair<Index, Vec3>>, CellHash> grid;

  Impl(std::size_t n, double tolerance) : tol(tolerance) {
    const double cell = 32.0 * tol;
    reach = 1.01 * tol;
    inv = 1.0 / cell;
    tol2 = tol * tol;
    std::size_t words = 1 << 10;
    while (64 * words < 16 * n) words *= 2;
    mask = words - 1;
    once = std::vector<std::atomic<std::uint64_t>>(words);
    twice = std::vector<std::atomic<std::uint64_t>>(words);
  }
  std::int64_t cell_of(double v) const { return static_cast<std::int64_t>(std::floor(v * inv)); }
  Cell own_cell(const Points& p, std::size_t i) const {
    const auto r = static_cast<Eigen::Index>(i);
    return {cell_of(p(r, 0)), cell_of(p(r, 1)), cell_of(p(r, 2))};
  }
  template <class Visit>
  void box(const Points& p, std::size_t i, Visit&& visit) const {
    const auto r = static_cast<Eigen::Index>(i);
    std::int64_t lo[3], hi[3];
    for (int c = 0; c < 3; ++c) lo[c] = cell_of(p(r, c) - reach), hi[c] = cell_of(p(r, c) + reach);
    for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
        for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
          if (!visit(Cell{x, y, z})) return;
  }
  std::pair<std::size_t, std::uint64_t> slot(const Cell& k) const {
    const std::uint64_t h = CellHash{}(k);
    return {h & mask, (std::uint64_t(1) << ((h >> 40) & 63)) | (std::uint64_t(1) << ((h >> 52) & 63))};
  }
};

PointWelder::PointWelder(std::size_t points, double tolerance) : impl_(std::make_unique<Impl>(points, tolerance)) {}
PointWelder::~PointWelder() = default;

void PointWelder::mark(const Points& p) {
  Impl& m = *impl_;
  parallel_for(0, std::size_t(p.rows()), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const auto [w, bits] = m.slot(m.own_cell(p, i));
      if ((m.once[w].fetch_or(bits, std::memory_order_relaxed) & bits) == bits)
        m.twice[w].fetch_or(bits, std::memory_order_relaxed);
    }
  });
}

std::vector<std::uint8_t> PointWelder::candidates(const Points& p) const {
  const Impl& m = *impl_;
  std::vector<std::uint8_t> candidate(std::size_t(p.rows()), 0);
  parallel_for(0, std::size_t(p.rows()), 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const auto own = m.own_cell(p, i);
      m.box(p, i, [&](const Impl::Cell& k) {
        const auto [w, bits] = m.slot(k);
        const auto& set = k == own ? m.twice : m.once;  // its own cell counts only with another point in it
        candidate[i] = (set[w].load(std::memory_order_relaxed) & bits) == bits ? 1 : 0;
        return !candidate[i];
      });
    }
  });
  return candidate;
}

// 3. The candidates, in row order: each joins the lowest-numbered
// representative within tol, or becomes one.
std::vector<Index> PointWelder::cluster(std::size_t first, const Points& p, const std::vector<std::uint8_t>& candidate) {
  Impl& m = *impl_;
  const std::size_t n = static_cast<std::size_t>(p.rows());
  std::vector<Index> rep(n);
  for (std::size_t i = 0; i < n; ++i) rep[i] = static_cast<Index>(first + i);
  for (std::size_t i = 0; i < n; ++i) {
    if (!candidate[i]) continue;
    const Vec3 q = row3(p, Index(i));
    Index found = static_cast<Index>(first + i);
    m.box(p, i, [&](const Impl::Cell& k) {
      const auto it = m.grid.find(k);
      if (it != m.grid.end())
        for (const auto& [r, pr] : it->second)
          if (r < found && (pr - q).squaredNorm() <= m.tol2) found = r;
      return true;
    });
    rep[i] = found;
    if (found == first + i) m.grid[m.own_cell(p, i)].emplace_back(found, q);
  }
  return rep;
}

std::vector<Index> weld_points(const Points& p, double tol) {
  const std::size_t n = static_cast<std::size_t>(p.rows());
  if (!(tol > 0.0) || n < 2) {
    std::vector<Index> rep(n);
    for (std::size_t i = 0; i < n; ++i) rep[i] = static_cast<Index>(i);
    return rep;
  }
  PointWelder welder(n, tol);
  welder.mark(p);
  return welder.cluster(0, p, welder.candidates(p));
}

}  // namespace refit
