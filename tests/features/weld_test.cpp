// weld_points: the parallel pre-filter must not change what the documented rule
// gives (in row order, join the lowest-numbered representative within tol).
#include <refit/core/parallel.hpp>
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
