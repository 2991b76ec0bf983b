// The faces the collision step's last rounds turn over (pipeline/last_folds.hpp):
// smoothed out where that keeps clear of body B, kept where the pushes put them
// otherwise.
#include "support/shapes.hpp"

#include <refit/core/topology.hpp>
#include <refit/pipeline/last_folds.hpp>

#include <gtest/gtest.h>

namespace refit {
namespace {

constexpr int kSide = 21;
constexpr double kSpacing = 0.5;
constexpr Index kCentre = Index(10 * kSide + 10);  // at (5, 0, 5)
constexpr double kClearance = 0.1;

std::size_t faces_turned_down(const Garment& g, const Points& p) {
  std::size_t n = 0;
  for (std::size_t f = 0; f < g.faces.rows(); ++f) n += face_normal(p, g.faces.row(f)).y() <= 0.0;
  return n;
}

struct Crumple {
  Garment g = test::quad_grid(kSide, kSide, kSpacing, [](double, double) { return 0.0; });  // in y = 0, normals +y
  Csr adjacency = vertex_adjacency(g);
  FoldBinding binding = bind_folds(g);
  Points p = g.positions;
  // The centre vertex pushed 2 spacings along x and 1.3 along z: the faces on that side turn over.
  Crumple() { p.row(kCentre) += Vec3(2.0 * kSpacing, 0.0, 1.3 * kSpacing).transpose(); }
  LastFoldsReport smooth(const BodySurface& body) {
    return smooth_out_last_folds(g, binding, p, adjacency, nullptr, body, kClearance);
  }
};

TEST(LastFolds, AFoldIsSmoothedOutWhereThatKeepsClearOfTheBody) {
  Crumple c;
  ASSERT_GE(faces_turned_down(c.g, c.p), 1u);
  const BodySurface far(test::icosphere(3, 1.0, Vec3(100.0, 100.0, 100.0)));
  const LastFoldsReport r = c.smooth(far);
  EXPECT_GE(r.folds.folded_before, 1u);
  EXPECT_GT(r.folds.smoothed, 0u);
  EXPECT_EQ(r.held, 0u);
  EXPECT_EQ(faces_turned_down(c.g, c.p), 0u);
}

// A body right under where the smoothing takes the centre: the vertices it
// would move within the clearance keep the place the pushes gave them; the
// others take the smoothing's.
TEST(LastFolds, AVertexTheSmoothingWouldTakeTooCloseToTheBodyKeepsItsPlace) {
  Crumple c;
  const Points pushed = c.p;
  const BodySurface body(test::icosphere(3, 0.4, Vec3(5.0, -0.05, 5.0)));
  const LastFoldsReport r = c.smooth(body);
  EXPECT_GT(r.held, 0u);
  EXPECT_TRUE(c.p.row(kCentre) == pushed.row(kCentre));
  std::size_t moved = 0;
  for (Index v = 0; v < c.p.rows(); ++v) {
    if (c.p.row(v) == pushed.row(v)) continue;
    ++moved;
    EXPECT_GE(body.signed_distance(row3(c.p, v)), kClearance * (1.0 - 1e-3)) << v;
  }
  EXPECT_GT(moved, 0u);
  EXPECT_LE(moved + r.held, r.folds.smoothed);  // smoothed: the region, some of it left where it was
}

}  // namespace
}  // namespace refit
