// The holds of the clearance rounds (clearance.hpp) on a body that is the
// half-space y < 0 (distance y): hold_clear_of_body lifts free agents closer
// than the clearance to it; hold_near_body brings free agents farther than their
// ceiling back to it (the band of SurfaceOptions::near_body_band).
#include <refit/surface/clearance.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace refit {
namespace {

const std::function<double(const Vec3&)> kFloor = [](const Vec3& p) { return p.y(); };
constexpr double kStep = 1e-4;

TEST(Clearance, HoldNearBodyBringsOnlyFreeAgentsAboveTheirCeilingToIt) {
  Points x(5, 3), warped(5, 3);
  x << 0, 2.0, 0,    // free, above its ceiling 1.0: moved to 1.0
      1, 0.5, 0,     // free, below its ceiling: stays
      2, 3.0, 0,     // not free: stays
      3, 5.0, 0,     // free, no ceiling (not near the body): stays
      4, 1.31, 1;    // free, just above 1.3: moved
  warped << 0, 0.7, 0, 1, 0.2, 0, 2, 0.1, 0, 3, 4.0, 0, 4, 1.0, 1;
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<double> ceiling{1.0, 1.0, 0.5, inf, 1.3};
  const std::vector<std::uint8_t> free{1, 1, 0, 1, 1};
  std::vector<std::uint8_t> fixed{0, 0, 1, 0, 0};
  const Points before = x;
  EXPECT_EQ(hold_near_body(kFloor, ceiling, kStep, free, warped, x, fixed), 2u);
  EXPECT_NEAR(x(0, 1), 1.0, 1e-6);
  EXPECT_NEAR(x(4, 1), 1.3, 1e-6);
  // Along the distance's gradient only: x and z kept.
  EXPECT_DOUBLE_EQ(x(0, 0), 0.0);
  EXPECT_DOUBLE_EQ(x(4, 2), 1.0);
  for (const Index a : {1, 2, 3}) EXPECT_EQ(x.row(a), before.row(a)) << a;
  EXPECT_EQ(fixed, (std::vector<std::uint8_t>{4, 0, 1, 0, 4}));
  // A second call finds nothing more to hold.
  EXPECT_EQ(hold_near_body(kFloor, ceiling, kStep, free, warped, x, fixed), 0u);
}

TEST(Clearance, HoldClearOfBodyLiftsFreeAgentsCloserThanTheClearance) {
  Points x(3, 3), warped(3, 3);
  x << 0, -0.5, 0, 1, 0.1, 0, 2, 0.6, 0;
  warped << 0, 0.3, 0, 1, 0.3, 0, 2, 0.3, 0;
  const std::vector<std::uint8_t> free{1, 1, 1};
  std::vector<std::uint8_t> fixed(3, 0);
  EXPECT_EQ(hold_clear_of_body(kFloor, 0.4, kStep, free, warped, x, fixed), 2u);
  EXPECT_NEAR(x(0, 1), 0.4, 1e-6);
  EXPECT_NEAR(x(1, 1), 0.4, 1e-6);
  EXPECT_DOUBLE_EQ(x(2, 1), 0.6);
  EXPECT_EQ(fixed, (std::vector<std::uint8_t>{3, 3, 0}));
}

// Where the distance grows slower than linearly (a point in a crease of the
// body), Newton's steps approach the clearance from below and their last one
// ended a rounding error short of it; clear_point then went back towards
// `fallback` (an agent's warped place, which can itself be too close: the
// shared skirt on F_thinner had an agent moved 0.8 cm, into the clearance).
TEST(Clearance, ClearPointLandsOnTheClearanceNotOnTheFallback) {
  const std::function<double(const Vec3&)> crease = [](const Vec3& p) { return 2.0 * (std::sqrt(p.y() + 1.0) - 1.0); };
  const double clearance = 0.4, step = 1e-4;
  const Vec3 fallback(0.0, 0.05, 0.0);  // too close as well
  for (int i = 0; i < 200; ++i) {
    const Vec3 start(0.01 * i, -0.5 + 0.0047 * i, 0.3);
    const Vec3 q = clear_point(crease, clearance, step, start, fallback);
    EXPECT_GE(crease(q), clearance) << i;
    EXPECT_LT(crease(q), clearance + 1e-3 * step) << i;
    EXPECT_EQ(q.x(), start.x()) << i;  // along the gradient only
    EXPECT_EQ(q.z(), start.z()) << i;
  }
}

}  // namespace
}  // namespace refit
