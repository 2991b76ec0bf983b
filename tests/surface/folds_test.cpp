// The fold smoothing (surface/folds.hpp): faces turned over against their
// neighbours are smoothed out; a smooth deformation and pinned vertices are left alone.
#include <refit/core/parallel.hpp>
#include <refit/core/topology.hpp>
#include <refit/surface/folds.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace refit {
namespace {

constexpr int kSide = 21;        // vertices per side
constexpr double kSpacing = 0.5;

// A flat side x side grid of triangles in the plane y = 0.
Garment grid(int side = kSide) {
  Garment g;
  g.positions.resize(side * side, 3);
  for (int i = 0; i < side; ++i)
    for (int k = 0; k < side; ++k) g.positions.row(i * side + k) << kSpacing * i, 0.0, kSpacing * k;
  for (int i = 0; i + 1 < side; ++i)
    for (int k = 0; k + 1 < side; ++k) {
      const Index a = Index(i * side + k);
      g.faces.push_row(std::array<Index, 3>{a, a + 1, a + side + 1});
      g.faces.push_row(std::array<Index, 3>{a, a + side + 1, a + side});
    }
  return g;
}

// A smooth deformation: a 30 degree turn about x and a 10 % stretch along x.
Eigen::Matrix3d smooth_map() {
  return Eigen::AngleAxisd(M_PI / 6.0, Vec3::UnitX()).toRotationMatrix() * Eigen::Vector3d(1.1, 1.0, 1.0).asDiagonal();
}

// Faces whose normal points against the smooth map's image of their original
// normal: folds, counted without the code under test.
std::size_t folds_against(const Garment& g, const Points& positions, const Eigen::Matrix3d& map) {
  std::size_t n = 0;
  for (std::size_t f = 0; f < g.faces.rows(); ++f) {
    const auto face = g.faces.row(f);
    auto normal = [&](const Points& p) {
      return Vec3((row3(p, face[1]) - row3(p, face[0])).cross(row3(p, face[2]) - row3(p, face[0])));
    };
    const Vec3 expected = map.inverse().transpose() * normal(g.positions);  // normals map by the inverse transpose
    if (normal(positions).dot(expected) <= 0.0) ++n;
  }
  return n;
}

Points deformed(const Garment& g, const Eigen::Matrix3d& map) {
  Points p = g.positions;
  for (Index v = 0; v < p.rows(); ++v) p.row(v) = (map * row3(g.positions, v)).transpose();
  return p;
}

constexpr Index kCentre = Index(10 * kSide + 10);

// The smooth deformation with the centre vertex pushed about 2.4 spacings along the
// grid (its image): the faces on that side turn over.
Points crumpled(const Garment& g, const Eigen::Matrix3d& map) {
  Points p = deformed(g, map);
  p.row(kCentre) += (map * Vec3(2.0 * kSpacing, 0.0, 1.3 * kSpacing)).transpose();
  return p;
}

// The grid, what the smoothing needs of it, and the smooth map.
struct Grid {
  explicit Grid(int side = kSide) : g(grid(side)) {}
  Garment g;
  Csr adjacency = vertex_adjacency(g);
  FoldBinding binding = bind_folds(g);
  Eigen::Matrix3d map = smooth_map();

  FoldReport smooth(Points& p, const std::vector<std::uint8_t>* pinned = nullptr) const {
    return smooth_out_folds(g, binding, p, adjacency, pinned);
  }
};

TEST(Folds, ASmoothDeformationIsLeftAlone) {
  const Grid grid;
  Points p = deformed(grid.g, grid.map);
  const Points before = p;
  const FoldReport r = grid.smooth(p);
  EXPECT_EQ(r.folded_before, 0u);
  EXPECT_EQ(r.smoothed, 0u);
  EXPECT_TRUE(p == before);
}

TEST(Folds, ACrumpleIsSmoothedOutAndTheRestKept) {
  const Grid grid;
  Points p = crumpled(grid.g, grid.map);
  ASSERT_GE(folds_against(grid.g, p, grid.map), 2u);
  const FoldReport r = grid.smooth(p);
  EXPECT_GE(r.folded_before, 1u);
  EXPECT_EQ(r.folded_after, 0u);
  EXPECT_EQ(folds_against(grid.g, p, grid.map), 0u);
  // Only the neighbourhood of the crumple moved; the grid's edge kept the smooth map exactly.
  EXPECT_GT(r.smoothed, 0u);
  // The crumple's corners and 2 rings, and the feather's 3 rings beyond them
  // (about 120 of the 441 vertices; 110 was the bound before the feather).
  EXPECT_LT(r.smoothed, std::size_t(kSide * kSide / 3));
  const Points smooth = deformed(grid.g, grid.map);
  for (int i = 0; i < kSide; ++i)
    for (Index v : {Index(i), Index(i * kSide), Index(i * kSide + kSide - 1), Index((kSide - 1) * kSide + i)})
      EXPECT_TRUE(p.row(v) == smooth.row(v)) << v;
}

// A 7 x 7 patch shifted 4 spacings along the grid: the faces on its leading
// side fold, and one ring around them cannot take the patch's shift. Each round
// after the first smooths as many rings more around what is left as rounds have
// run. Before, a fold left over added nothing to the region (its corners were in
// it already): the same region was smoothed again, and the second round, leaving
// no fewer folds, ended the smoothing with 5 (6 counted here). The rings
// alone, without the feather: easing a move this large (a tear of 4 spacings)
// over the rings beyond the region leaves the first round's 4 folds to rounds
// that take none of them (bench/README.md, "The fold smoothing's edge eased").
TEST(Folds, AFoldLeftOverGetsAWiderRegion) {
  const Grid grid;
  Points p = deformed(grid.g, grid.map);
  for (int i = 7; i <= 13; ++i)
    for (int k = 7; k <= 13; ++k) p.row(i * kSide + k) += (grid.map * Vec3(4.0 * kSpacing, 0.0, 0.0)).transpose();
  ASSERT_GE(folds_against(grid.g, p, grid.map), 2u);
  FoldOptions narrow;
  narrow.rings = 1;
  narrow.feather = 0;
  narrow.reshape_rounds = 0;  // the rounds alone
  const FoldReport r = smooth_out_folds(grid.g, grid.binding, p, grid.adjacency, nullptr, narrow);
  EXPECT_GE(r.rounds, 3);
  EXPECT_EQ(r.folded_after, 0u);
  EXPECT_EQ(folds_against(grid.g, p, grid.map), 0u);
}

// A round after the first smooths only the pieces of the region that hold a
// fold left: a crumple the first round smoothed out keeps that round's result
// while a shifted patch elsewhere on the grid takes more rounds (each round
// smoothing the whole region again took 1.2 s of the 1M dress's 1.4 s on
// F_thinner, for a few hundred folds left of 50,000). The crumple alone is
// smoothed as it is beside the patch.
TEST(Folds, ALaterRoundLeavesPiecesWithNoFoldLeft) {
  constexpr int side = 41;
  const Grid big(side);
  const Garment& g = big.g;
  const Eigen::Matrix3d& map = big.map;
  const Points smooth = deformed(g, map);
  const Index crumple = Index(30 * side + 30);
  Points crumple_only = smooth;
  crumple_only.row(crumple) += (map * Vec3(2.0 * kSpacing, 0.0, 1.3 * kSpacing)).transpose();
  Points both = crumple_only;
  for (int i = 7; i <= 13; ++i)
    for (int k = 7; k <= 13; ++k) both.row(i * side + k) += (map * Vec3(4.0 * kSpacing, 0.0, 0.0)).transpose();
  FoldOptions narrow;
  narrow.rings = 1;
  narrow.feather = 0;
  narrow.reshape_rounds = 0;
  const FoldReport r_crumple = smooth_out_folds(g, big.binding, crumple_only, big.adjacency, nullptr, narrow);
  const FoldReport r_both = smooth_out_folds(g, big.binding, both, big.adjacency, nullptr, narrow);
  EXPECT_EQ(r_crumple.folded_after, 0u);
  EXPECT_EQ(r_both.folded_after, 0u);
  ASSERT_GT(r_both.rounds, r_crumple.rounds);  // the patch took more rounds than the crumple
  std::size_t crumple_moved = 0;
  for (int i = 20; i < side; ++i)  // the crumple's side of the grid, far from the patch's region
    for (int k = 20; k < side; ++k) {
      const Index v = Index(i * side + k);
      EXPECT_TRUE(both.row(v) == crumple_only.row(v)) << v;
      crumple_moved += crumple_only.row(v) != smooth.row(v);
    }
  EXPECT_GT(crumple_moved, 0u);
}

// The largest move of a vertex that moved next to one that did not: how
// sharply the smoothing's move stops at the edge of what it moved.
double move_at_edge(const Grid& grid, const Points& before, const Points& after) {
  double most = 0.0;
  for (Index v = 0; v < before.rows(); ++v) {
    const double move = (row3(after, v) - row3(before, v)).norm();
    if (move == 0.0) continue;
    for (Index w : grid.adjacency.row(v))
      if (after.row(w) == before.row(w)) most = std::max(most, move);
  }
  return most;
}

// With the region's edge held, its move stopped within an edge there (on the
// dense 1M dress the edges of thin regions around the warp's crumples showed
// as pleats); the feather's rings take their neighbours' mean move, so it eases
// off: at the edge of what moved, the move is a fraction of what it was.
TEST(Folds, TheSmoothedMoveEasesOffBeyondTheRegion) {
  const Grid grid;
  const Points before = crumpled(grid.g, grid.map);
  FoldOptions held;
  held.feather = 0;
  held.reshape_rounds = 0;
  FoldOptions feathered = held;
  feathered.feather = 3;
  Points p_held = before, p_feathered = before;
  const FoldReport r_held = smooth_out_folds(grid.g, grid.binding, p_held, grid.adjacency, nullptr, held);
  const FoldReport r_feathered = smooth_out_folds(grid.g, grid.binding, p_feathered, grid.adjacency, nullptr, feathered);
  EXPECT_EQ(r_held.folded_after, 0u);
  EXPECT_EQ(r_feathered.folded_after, 0u);
  EXPECT_EQ(folds_against(grid.g, p_feathered, grid.map), 0u);
  EXPECT_GT(r_feathered.smoothed, r_held.smoothed);  // the feather's rings moved too
  const double step_held = move_at_edge(grid, before, p_held), step_feathered = move_at_edge(grid, before, p_feathered);
  EXPECT_GT(step_held, 0.0);
  EXPECT_LT(step_feathered, 0.5 * step_held) << step_held << " " << step_feathered;
}

TEST(Folds, PinnedVerticesKeepTheirPlace) {
  const Grid grid;
  Points p = crumpled(grid.g, grid.map);
  std::vector<std::uint8_t> pinned(grid.g.vertex_count(), 0);
  pinned[kCentre] = 1;
  const Vec3 centre = row3(p, kCentre);
  const std::size_t folded = folds_against(grid.g, p, grid.map);
  const FoldReport r = grid.smooth(p, &pinned);
  EXPECT_TRUE(row3(p, kCentre) == centre);
  EXPECT_LE(folds_against(grid.g, p, grid.map), folded);
  EXPECT_LE(r.folded_after, r.folded_before);
}

// Without the smoothing's rounds, the reshaping alone: each face leaning more
// than 60 degrees off its corners takes its original shape turned as its
// neighbourhood turned, which unfolds the crumple and moves only the faces
// around it; with neither, nothing moves.
TEST(Folds, FacesLeftTurnedTakeTheirOriginalShapeTurnedAsAround) {
  const Grid grid;
  Points p = crumpled(grid.g, grid.map);
  const Points before = p;
  ASSERT_GE(folds_against(grid.g, p, grid.map), 2u);
  FoldOptions none;
  none.max_rounds = 0;
  none.reshape_rounds = 0;
  EXPECT_EQ(smooth_out_folds(grid.g, grid.binding, p, grid.adjacency, nullptr, none).smoothed, 0u);
  EXPECT_TRUE(p == before);
  FoldOptions reshape_only;
  reshape_only.max_rounds = 0;
  const FoldReport r = smooth_out_folds(grid.g, grid.binding, p, grid.adjacency, nullptr, reshape_only);
  EXPECT_EQ(folds_against(grid.g, p, grid.map), 0u);
  EXPECT_EQ(r.folded_after, 0u);
  EXPECT_GT(r.smoothed, 0u);
  const auto ring = grid.adjacency.row(kCentre);
  for (Index v = 0; v < p.rows(); ++v) {  // only the centre and its neighbours moved
    if (p.row(v) != before.row(v)) {
      EXPECT_TRUE(v == kCentre || std::find(ring.begin(), ring.end(), v) != ring.end()) << v;
    }
  }
}

// The region's walks run in parallel in blocks of thousands of vertices: a
// grid of 160 x 160 with 121 crumples, whose region spans several blocks,
// smooths to the same bits with one thread and with two.
TEST(Folds, TheSameWithOneThreadOrTwo) {
  constexpr int kBig = 160;
  const Grid big(kBig);
  const Garment& g = big.g;
  const Csr& adjacency = big.adjacency;
  const FoldBinding& binding = big.binding;
  const Eigen::Matrix3d& map = big.map;
  Points crumples = deformed(g, map);
  for (int i = 10; i < kBig; i += 14)
    for (int k = 10; k < kBig; k += 14)
      crumples.row(i * kBig + k) += (map * Vec3(2.0 * kSpacing, 0.0, 1.3 * kSpacing)).transpose();
  ASSERT_GE(folds_against(g, crumples, map), 121u);
  Points one = crumples, two = crumples;
  FoldReport r1, r2;
  {
    const ThreadLimit limit(1);
    r1 = smooth_out_folds(g, binding, one, adjacency, nullptr);
  }
  {
    const ThreadLimit limit(2);
    r2 = smooth_out_folds(g, binding, two, adjacency, nullptr);
  }
  EXPECT_GT(r1.smoothed, std::size_t(2 * 4096));  // more than one block of the parallel walks
  EXPECT_EQ(folds_against(g, one, map), 0u);
  EXPECT_TRUE(one == two);
  EXPECT_EQ(r1.folded_before, r2.folded_before);
  EXPECT_EQ(r1.folded_after, r2.folded_after);
  EXPECT_EQ(r1.smoothed, r2.smoothed);
  EXPECT_EQ(r1.rounds, r2.rounds);
}

TEST(Folds, NothingChangesWhenSmoothingCannotHelp) {
  // Every vertex pinned: no round gets better, so none is kept.
  const Grid grid;
  Points p = crumpled(grid.g, grid.map);
  const Points before = p;
  const std::vector<std::uint8_t> pinned(grid.g.vertex_count(), 1);
  const FoldReport r = grid.smooth(p, &pinned);
  EXPECT_GE(r.folded_before, 1u);
  EXPECT_EQ(r.folded_after, r.folded_before);
  EXPECT_EQ(r.smoothed, 0u);
  EXPECT_TRUE(p == before);
}

}  // namespace
}  // namespace refit
