// weld_points: the parallel pre-filter must not change what the documented rule
// gives (in row order, join the lowest-numbered representative within tol).
#include <refit/core/parallel.hpp>
#include <refit/core/topology.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/features/slice.hpp>

#include <gtest/gtest.h>

#include <random>

using namespace refit;

namespace {

// The rule of slice.hpp, by brute force.
std::vector<Index> weld_reference(const Points& p, double tol) {
  const std::size_t n = static_cast<std::size_t>(p.rows());
  std::vector<Index> rep(n);
  std::vector<Index> reps;
  for (std::size_t i = 0; i < n; ++i) {
    rep[i] = static_cast<Index>(i);
    for (Index r : reps)
      if ((p.row(r) - p.row(static_cast<Eigen::Index>(i))).squaredNorm() <= tol * tol) {
        rep[i] = r;
        break;
      }
    if (rep[i] == i) reps.push_back(static_cast<Index>(i));
  }
  return rep;
}

// Random points in a 10-unit cube, a third of them with one or two twins closer
// than, near, or just beyond tol (in random directions), shuffled.
Points points_with_twins(std::size_t base, double tol, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 10.0), d(-1.0, 1.0);
  std::vector<Vec3> pts;
  for (std::size_t i = 0; i < base; ++i) {
    const Vec3 p(u(rng), u(rng), u(rng));
    pts.push_back(p);
    if (i % 3 != 0) continue;
    for (int k = 0; k < 1 + static_cast<int>(i % 2); ++k) {
      const double scale[] = {0.0, 0.3, 0.9, 0.999, 1.001, 1.5};
      const Vec3 dir = Vec3(d(rng), d(rng), d(rng)).normalized();
      pts.push_back(p + scale[(i / 3 + static_cast<std::size_t>(k)) % 6] * tol * dir);
    }
  }
  std::shuffle(pts.begin(), pts.end(), rng);
  Points out(static_cast<Eigen::Index>(pts.size()), 3);
  for (std::size_t i = 0; i < pts.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  return out;
}

TEST(Weld, MatchesTheRuleByBruteForce) {
  for (double tol : {1e-3, 0.05}) {
    const Points p = points_with_twins(1500, tol, 7);
    const std::vector<Index> expected = weld_reference(p, tol);
    std::size_t merged = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) merged += expected[i] != i;
    ASSERT_GT(merged, 300u) << "the case must weld many points";
    EXPECT_EQ(weld_points(p, tol), expected) << "tol " << tol;
  }
}

TEST(Weld, SameResultForOneAndTwoThreads) {
  const Points p = points_with_twins(60000, 1e-4, 11);
  std::vector<Index> one, two;
  {
    const ThreadLimit limit(1);
    one = weld_points(p, 1e-4);
  }
  {
    const ThreadLimit limit(2);
    two = weld_points(p, 1e-4);
  }
  EXPECT_EQ(one, two);
}

TEST(Weld, NonPositiveToleranceWeldsNothing) {
  Points p(3, 3);
  p << 0, 0, 0, 0, 0, 0, 1, 1, 1;
  const std::vector<Index> identity{0, 1, 2};
  EXPECT_EQ(weld_points(p, 0.0), identity);
  EXPECT_EQ(weld_points(p, -1.0), identity);
}

}  // namespace

// A 200 x 100 quad grid cut down the middle (the seam's vertices duplicated),
// with one quad whose corners all fall within the tolerance (it collapses) and
// one whose two corners weld (it becomes a triangle): welded, the faces are the
// documented rule applied row by row, one and two threads agree, and the seam
// no longer shows as boundary.
TEST(Weld, WeldGarmentRebuildsFacesAsTheRuleSaysForAnyThreadCount) {
  const Index W = 200, H = 100, half = W / 2;
  Garment g;
  std::vector<Vec3> pts;
  std::vector<Index> left((W + 1) * (H + 1)), right((W + 1) * (H + 1));
  for (Index y = 0; y <= H; ++y)
    for (Index x = 0; x <= W; ++x) {
      const Index k = y * (W + 1) + x;
      const double dx = (x == 51 && y == 40) ? -0.99999 : 0.0;  // welds onto (50, 40)
      left[k] = static_cast<Index>(pts.size());
      pts.emplace_back(double(x) + dx, double(y), 0.0);
      right[k] = left[k];
      if (x == half) {
        right[k] = static_cast<Index>(pts.size());
        pts.emplace_back(double(x), double(y), 0.0);
      }
    }
  g.positions.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (std::size_t i = 0; i < pts.size(); ++i) g.positions.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  for (Index y = 0; y < H; ++y)
    for (Index x = 0; x < W; ++x) {
      const auto& v = x < half ? left : right;
      const Index k = y * (W + 1) + x;
      g.faces.push_row(std::vector<Index>{v[k], v[k + 1], v[k + W + 2], v[k + W + 1]});
    }
  const double tol = 1e-4;
  const std::vector<Index> rep = weld_points(g.positions, tol);
  Garment expected;
  for (std::size_t f = 0; f < g.faces.rows(); ++f) {
    std::vector<Index> row;
    for (Index v : g.faces.row(f))
      if (row.empty() || row.back() != rep[v]) row.push_back(rep[v]);
    while (row.size() > 1 && row.back() == row.front()) row.pop_back();
    if (row.size() >= 3) expected.faces.push_row(row);
  }
  ASSERT_EQ(expected.faces.rows(), g.faces.rows()) << "no face collapses in this case";
  Garment one, two;
  {
    const ThreadLimit limit(1);
    one = weld_garment(g, tol);
  }
  {
    const ThreadLimit limit(2);
    two = weld_garment(g, tol);
  }
  EXPECT_EQ(one.faces.offsets, expected.faces.offsets);
  EXPECT_EQ(one.faces.indices, expected.faces.indices);
  EXPECT_EQ(two.faces.offsets, expected.faces.offsets);
  EXPECT_EQ(two.faces.indices, expected.faces.indices);
  std::size_t triangles = 0;
  for (std::size_t f = 0; f < one.faces.rows(); ++f) triangles += one.faces.row_size(f) == 3;
  EXPECT_EQ(triangles, 2u);  // the two quads at the welded corner
  EXPECT_EQ(boundary_loops(g).size(), 2u);    // the two halves
  EXPECT_EQ(boundary_loops(one).size(), 1u);  // one rim
}

// A quad whose corners all weld into one point is dropped.
TEST(Weld, WeldGarmentDropsCollapsedFaces) {
  Garment g;
  g.positions.resize(6, 3);
  g.positions << 0, 0, 0, 1e-9, 0, 0, 1e-9, 1e-9, 0, 0, 1e-9, 0, 1, 0, 0, 1, 1, 0;
  g.faces.push_row(std::vector<Index>{0, 1, 2, 3});
  g.faces.push_row(std::vector<Index>{1, 4, 5, 2});
  const Garment w = weld_garment(g, 1e-6);
  ASSERT_EQ(w.faces.rows(), 1u);
  EXPECT_EQ(std::vector<Index>(w.faces.row(0).begin(), w.faces.row(0).end()), (std::vector<Index>{0, 4, 5}));
}
