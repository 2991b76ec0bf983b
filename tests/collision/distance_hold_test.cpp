// The distance hold: vertices that sat near body A end as far from body B, the
// move spreads without folds, pinned and unheld far vertices stay, any thread count the same.
#include <refit/collision/distance_hold.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>

#include "support/shapes.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace refit {
namespace {

// A spherical cap shell 0.5 cm outside a sphere of radius 10 (body A), left
// where it was around a thinner sphere of radius 9 (body B): 1.5 cm off it.
struct Shell {
  BodyMesh a = test::icosphere(4, 10.0), b = test::icosphere(4, 9.0);
  Garment g = test::icosphere_garment(3, 10.5);
};

double signed_distance(const BodySurface& body, const Vec3& p) {
  const ClosestPoint cp = body.closest(p);
  return body.inside(p) ? -cp.distance : cp.distance;
}

TEST(DistanceHold, VerticesNearBodyAKeepTheirDistanceOnBodyB) {
  Shell s;
  const BodySurface a(s.a), b(s.b);
  // Only the upper half sat near body A (the rest: a loose part, 1.5 cm off it).
  Points start = s.g.positions;
  for (Index i = 0; i < start.rows(); ++i)
    if (start(i, 1) < 0.0) start.row(i) *= 11.5 / 10.5;
  const std::vector<double> da = near_body_distances(start, a, 1.0);
  std::size_t held = 0;
  for (Index i = 0; i < start.rows(); ++i) {
    EXPECT_EQ(std::isfinite(da[i]), start(i, 1) >= 0.0) << i;
    if (std::isfinite(da[i])) {
      ++held;
      EXPECT_NEAR(da[i], 0.5, 0.05) << i;
    }
  }
  ASSERT_GT(held, 100u);

  Points p = start;
  DistanceHoldOptions o;
  const DistanceHoldReport r = hold_body_distance(s.g, p, b, da, o);
  EXPECT_EQ(r.held, held);
  EXPECT_EQ(r.corrected, held);
  EXPECT_NEAR(r.largest_change, 1.0, 0.06);
  for (Index i = 0; i < p.rows(); ++i) {
    const double d = signed_distance(b, row3(p, i));
    if (std::isfinite(da[i])) {
      EXPECT_NEAR(d, da[i], o.tolerance + 0.01) << i;  // followed body B
    }
    // The loose part takes a falloff of the held part's move: less the farther it is.
    const double moved = (row3(p, i) - row3(start, i)).norm();
    if (start(i, 1) < 0.0) {
      EXPECT_LT(moved, 1.0) << i;
    }
    if (start(i, 1) < -11.0) {
      EXPECT_LT(moved, 0.1) << i;
    }
  }
  // Smooth and fold-free: every face keeps its side.
  for (std::size_t f = 0; f < s.g.faces.rows(); ++f) {
    const auto face = s.g.faces.row(f);
    const auto normal = [&](const Points& q) {
      return Vec3((row3(q, face[1]) - row3(q, face[0])).cross(row3(q, face[2]) - row3(q, face[0])));
    };
    EXPECT_GT(normal(p).dot(normal(start)), 0.0) << f;
  }
}

TEST(DistanceHold, PinnedVerticesStayAndTheResultIsTheSameForAnyThreadCount) {
  Shell s;
  const BodySurface a(s.a), b(s.b);
  const std::vector<double> da = near_body_distances(s.g.positions, a, 1.0);
  std::vector<std::uint8_t> pinned(s.g.vertex_count(), 0);
  for (Index i = 0; i < s.g.positions.rows(); ++i) pinned[i] = s.g.positions(i, 0) > 5.0;
  DistanceHoldOptions o;
  o.pinned = &pinned;
  Points one = s.g.positions, two = s.g.positions;
  {
    ThreadLimit limit(1);
    hold_body_distance(s.g, one, b, da, o);
  }
  {
    ThreadLimit limit(2);
    hold_body_distance(s.g, two, b, da, o);
  }
  EXPECT_TRUE((one.array() == two.array()).all());
  for (Index i = 0; i < one.rows(); ++i) {
    if (pinned[i]) {
      EXPECT_EQ(row3(one, i), row3(s.g.positions, i)) << i;
    }
    if (s.g.positions(i, 0) < -5.0) {
      EXPECT_NEAR(signed_distance(b, row3(one, i)), 0.5, o.tolerance + 0.01) << i;
    }
  }
}

TEST(DistanceHold, MismatchedSizesAreRefused) {
  Shell s;
  const BodySurface b(s.b);
  Points p = s.g.positions;
  EXPECT_THROW(hold_body_distance(s.g, p, b, std::vector<double>(3, 0.5)), Error);
  const std::vector<std::uint8_t> few(3, 0);
  DistanceHoldOptions o;
  o.pinned = &few;
  EXPECT_THROW(hold_body_distance(s.g, p, b, std::vector<double>(s.g.vertex_count(), 0.5), o), Error);
}

}  // namespace
}  // namespace refit
