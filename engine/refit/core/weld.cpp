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

std::vector<Index> weld_points(const Points& p, double tol) {
  const std::size_t n = static_cast<std::size_t>(p.rows());
  std::vector<Index> rep(n);
  for (std::size_t i = 0; i < n; ++i) rep[i] = static_cast<Index>(i);
  if (!(tol > 0.0) || n < 2) return rep;

  // Cells of 32 tol: the tol-box around a point usually stays in its own cell
  // (about 1.2 cells visited on average, each a likely cache miss below).
  const double cell = 32.0 * tol, reach = 1.01 * tol;
  const double inv = 1.0 / cell;
  const auto cell_of = [inv](double v) { return static_cast<std::int64_t>(std::floor(v * inv)); };
  const auto box = [&](std::size_t i, auto&& visit) {
    const auto r = static_cast<Eigen::Index>(i);
    std::int64_t lo[3], hi[3];
    for (int c = 0; c < 3; ++c) lo[c] = cell_of(p(r, c) - reach), hi[c] = cell_of(p(r, c) + reach);
    for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
      for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
        for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
          if (!visit(std::array<std::int64_t, 3>{x, y, z})) return;
  };
  const auto own_cell = [&](std::size_t i) {
    const auto r = static_cast<Eigen::Index>(i);
    return std::array<std::int64_t, 3>{cell_of(p(r, 0)), cell_of(p(r, 1)), cell_of(p(r, 2))};
  };

  // 1. Which points may have another point within tol, in parallel: occupied
  // cells go into filters "one point" and "two or more": a cell sets two hashed
  // bits of one hashed 64-bit word (one cache miss per cell; 16 bits per point,
  // so the sets stay small enough for the cache). A collision only adds a
  // candidate, never loses one, and the final result does not depend on which
  // extra candidates there are (they find no twin in step 2). Most points of a
  // garment have no twin and are done here.
  std::size_t words = 1 << 10;
  while (64 * words < 16 * n) words *= 2;
  const std::size_t mask = words - 1;
  const auto slot = [mask](const std::array<std::int64_t, 3>& k) {
    const std::uint64_t h = CellHash{}(k);
    return std::pair<std::size_t, std::uint64_t>(h & mask, (std::uint64_t(1) << ((h >> 40) & 63)) |
                                                               (std::uint64_t(1) << ((h >> 52) & 63)));
  };
  std::vector<std::atomic<std::uint64_t>> once(words), twice(words);
  parallel_for(0, n, 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const auto [w, bits] = slot(own_cell(i));
      if ((once[w].fetch_or(bits, std::memory_order_relaxed) & bits) == bits) twice[w].fetch_or(bits, std::memory_order_relaxed);
    }
  });
  std::vector<std::uint8_t> candidate(n, 0);
  parallel_for(0, n, 1 << 14, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const auto own = own_cell(i);
      box(i, [&](const std::array<std::int64_t, 3>& k) {
        const auto [w, bits] = slot(k);
        const auto& set = k == own ? twice : once;  // its own cell counts only with another point in it
        candidate[i] = (set[w].load(std::memory_order_relaxed) & bits) == bits ? 1 : 0;
        return !candidate[i];
      });
    }
  });

  // 2. The candidates, in row order: each joins the lowest-numbered
  // representative within tol, or becomes one.
  std::unordered_map<std::array<std::int64_t, 3>, std::vector<Index>, CellHash> grid;
  const double tol2 = tol * tol;
  for (std::size_t i = 0; i < n; ++i) {
    if (!candidate[i]) continue;
    Index found = static_cast<Index>(i);
    box(i, [&](const std::array<std::int64_t, 3>& k) {
      const auto it = grid.find(k);
      if (it != grid.end())
        for (Index r : it->second)
          if (r < found && (p.row(r) - p.row(static_cast<Eigen::Index>(i))).squaredNorm() <= tol2) found = r;
      return true;
    });
    rep[i] = found;
    if (found == i) grid[own_cell(i)].push_back(found);
  }
  return rep;
}

}  // namespace refit
