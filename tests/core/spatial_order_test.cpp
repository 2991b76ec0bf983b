// Space-filling-curve order of a point set.
#include <refit/core/spatial_order.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace refit {
namespace {

TEST(SpatialOrder, IsAPermutationAlongTheCurve) {
  Points p(500, 3);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Eigen::Index i = 0; i < p.rows(); ++i) p.row(i) << u(rng), u(rng), u(rng);
  p.row(17) << std::nan(""), 0, 0;
  const CurveOrder c = curve_order(p);
  std::vector<Index> sorted(c.order.begin(), c.order.end());
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
  EXPECT_TRUE(std::is_sorted(c.key.begin(), c.key.end()));
  EXPECT_EQ(c.order.back(), 17u);  // not finite: last
  // Consecutive points are near each other: far nearer than random pairs on average.
  double walk = 0.0;
  for (std::size_t i = 0; i + 2 < c.order.size(); ++i) walk += (p.row(c.order[i + 1]) - p.row(c.order[i])).norm();
  EXPECT_LT(walk / 498.0, 0.35);
}

}  // namespace
}  // namespace refit
