// Layers in the surface step (beyond the paper): pieces of a garment lying over
// each other closer than a voxel get agents, rings and blends of their own, and
// a layer with nothing fixed moves with the layer beneath.
#include "support/shapes.hpp"

#include <refit/surface/agents.hpp>
#include <refit/surface/surface.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace refit {
namespace {

// An n x n quad grid of spacing s on y = y0 + wave * sin(1.7 x), from (x0, z0).
Garment sheet(int n, double s, double y0, double x0 = 0.0, double z0 = 0.0, double wave = 0.0) {
  return test::quad_grid(n, n, s, [=](double x, double) { return y0 + wave * std::sin(1.7 * x); }, x0, z0);
}

std::uint32_t max_layer(const std::vector<std::uint32_t>& l) { return *std::max_element(l.begin(), l.end()); }

TEST(GarmentLayers, PiecesOverEachOtherAreLayersSeamsAndSoupsAreNot) {
  // Two sheets 0.4 apart: two layers, each one label throughout.
  const Garment two = test::merge_garments(sheet(11, 1.0, 0.0), sheet(11, 1.0, 0.4));
  const std::vector<std::uint32_t> l2 = garment_layers(two, 8.0, 0.1);
  ASSERT_EQ(l2.size(), two.vertex_count());
  EXPECT_EQ(max_layer(l2), 2u);
  for (std::size_t v = 0; v < 121; ++v) EXPECT_EQ(l2[v], 1u);
  for (std::size_t v = 121; v < 242; ++v) EXPECT_EQ(l2[v], 2u);

  // Two panels side by side sharing coincident but separate seam vertices (x = 10): one layer.
  const Garment seam = test::merge_garments(sheet(11, 1.0, 0.0), sheet(11, 1.0, 0.0, 10.0));
  EXPECT_EQ(max_layer(garment_layers(seam, 8.0, 0.1)), 1u);
  // Cut apart by a gap of 0.05: one layer when boundaries within 0.1 join, two when nothing joins.
  const Garment gap = test::merge_garments(sheet(11, 1.0, 0.0), sheet(11, 1.0, 0.0, 10.05));
  EXPECT_EQ(max_layer(garment_layers(gap, 8.0, 0.1)), 1u);
  EXPECT_EQ(max_layer(garment_layers(gap, 8.0, 0.0)), 2u);
  // A gap of 0.3 is no seam.
  EXPECT_EQ(max_layer(garment_layers(test::merge_garments(sheet(11, 1.0, 0.0), sheet(11, 1.0, 0.0, 10.3)), 8.0, 0.1)), 2u);

  // Points, hanging lines and small pieces are loose (0): they belong to no layer.
  Garment extras = sheet(3, 0.5, 5.0);  // area 1: below the 8 of a layer
  extras.positions.conservativeResize(extras.positions.rows() + 3, 3);
  extras.positions.bottomRows(3) << 20, 0, 0, 21, 0, 0, 22, 0, 0;
  extras.lines.push_row(std::array<Index, 2>{9, 10});
  extras.points.push_row(std::array<Index, 1>{11});
  const Garment with_extras = test::merge_garments(sheet(11, 1.0, 0.0), extras);
  const std::vector<std::uint32_t> le = garment_layers(with_extras, 8.0, 0.1);
  EXPECT_EQ(max_layer(le), 1u);
  for (std::size_t v = 121; v < with_extras.vertex_count(); ++v) EXPECT_EQ(le[v], 0u) << v;
}

TEST(GarmentLayers, EachLayerGetsItsOwnAgentsAndRings) {
  // Sheets 0.3 voxel apart: the paper's one agent per voxel leaves about half
  // the voxels of each sheet to the other; with layers every voxel of each has one.
  const Garment g = test::merge_garments(sheet(21, 0.5, 0.0), sheet(21, 0.5, 0.3));
  const VoxelGrid grid = make_voxel_grid(g, Points(0, 3), 1.0);
  const std::vector<std::uint32_t> layer = garment_layers(g, 8.0, 0.1);
  const GarmentAgents shared = select_agents(g, grid);
  const GarmentAgents own = select_agents(g, grid, {}, layer);
  ASSERT_EQ(own.layer.size(), own.size());
  std::size_t per_layer[3] = {0, 0, 0};
  for (std::uint32_t l : own.layer) ++per_layer[l];
  EXPECT_EQ(per_layer[0], 0u);
  EXPECT_EQ(per_layer[1], per_layer[2]);
  EXPECT_EQ(own.size(), 2 * shared.size());
  // No one-ring edge joins the two layers; without layers, many do.
  const Points p = own.positions(g.positions);
  const Csr rings = build_one_rings(p, 3.0, own.layer);
  const Csr mixed = build_one_rings(p, 3.0);
  std::size_t across = 0, across_mixed = 0;
  for (std::size_t a = 0; a < own.size(); ++a) {
    EXPECT_GE(rings.row_size(a), 2u);
    for (Index q : rings.row(a)) across += own.layer[q] != own.layer[a];
    for (Index q : mixed.row(a)) across_mixed += own.layer[q] != own.layer[a];
  }
  EXPECT_EQ(across, 0u);
  EXPECT_GT(across_mixed, own.size() / 4);
}

// Body B's bump (the warp copies it into the garment).
double bump_at(double x, double z) { return 0.6 * std::exp(-0.25 * (std::pow(x - 4, 2) + std::pow(z - 4, 2))); }

// Lower sheet at y = 0, upper at y = 0.4, both wavy (so that without layers
// the voxels' agents fall on either); the warp puts body B's bump into both.
struct TwoSheets {
  Garment g = test::merge_garments(sheet(17, 0.5, 0.0, 0.0, 0.0, 0.3), sheet(17, 0.5, 0.4, 0.0, 0.0, 0.3));
  Points warped = g.positions;
  TwoSheets() {
    for (Eigen::Index v = 0; v < warped.rows(); ++v) warped(v, 1) += bump_at(warped(v, 0), warped(v, 2));
  }
  // Largest height change of the upper sheet from its original position.
  double upper_bump(const Points& x) const {
    double worst = 0.0;
    for (Eigen::Index v = 289; v < x.rows(); ++v) worst = std::max(worst, std::abs(x(v, 1) - g.positions(v, 1)));
    return worst;
  }
  // Feature samples along the upper sheet's edge z = 0 (its vertices), and their warped positions.
  Points edge(const Points& x) const {
    Points f(17, 3);
    for (int i = 0; i < 17; ++i) f.row(i) = x.row(289 + i * 17);
    return f;
  }
};

TEST(GarmentLayers, ALayerIsNotDraggedByTheLayerUnderIt) {
  // The body holds the lower sheet as warped (eq. 14); the upper sheet, free
  // and held at one edge to its original shape, gets that shape back.
  // Without layers half its voxels' agents stand on the bumped lower sheet and
  // its vertices blend them: the bump shows through.
  const TwoSheets t;
  // Body B 0.2 under the warped lower sheet: it holds that sheet, not the upper one (0.6 away).
  auto body = [](const Vec3& p) { return p.y() - 0.3 * std::sin(1.7 * p.x()) - bump_at(p.x(), p.z()) + 0.2; };
  SurfaceOptions o;
  o.voxel = 1.0;
  o.epsilon = 0.25;
  o.feature_zone_rings = 0;
  o.keep_clear_of_body = false;
  SurfaceOptions paper = o;
  paper.layers = false;
  const Points f = t.edge(t.g.positions), fw = t.edge(t.warped);
  const SurfaceResult with = SurfaceBinding::bind(t.g, f, o).apply(t.warped, f, body, &fw);
  const SurfaceResult without = SurfaceBinding::bind(t.g, f, paper).apply(t.warped, f, body, &fw);
  ASSERT_TRUE(with.positions.allFinite());
  EXPECT_EQ(with.stats.layers, 2u);
  EXPECT_EQ(with.stats.anchored, 0u);
  // The lower sheet stays as warped in both.
  EXPECT_LT((with.positions.topRows(289) - t.warped.topRows(289)).cwiseAbs().maxCoeff(), 1e-9);
  const double bump = t.upper_bump(t.warped), bump_with = t.upper_bump(with.positions),
               bump_without = t.upper_bump(without.positions);
  std::printf("[ info ] upper sheet's bump: warp %.4f, with layers %.4f, without %.4f\n", bump, bump_with, bump_without);
  EXPECT_LT(bump_with, 0.1 * bump);
  EXPECT_LT(bump_with, 0.5 * bump_without);
}

TEST(GarmentLayers, ALayerWithNothingFixedMovesWithTheLayerBeneath) {
  // The lower sheet, held at one edge to its original shape, loses the warp's
  // bump; the upper sheet has no feature and no body near it: anchored, it
  // takes the correction of the lower sheet's agents within reach, and loses
  // the bump too (the paper would leave it as warped, or, without layers,
  // drag it along through shared agents).
  const TwoSheets t;
  auto no_body = [](const Vec3&) { return std::numeric_limits<double>::infinity(); };
  Points f(17, 3), fw(17, 3);
  for (int i = 0; i < 17; ++i) {
    f.row(i) = t.g.positions.row(i * 17);
    fw.row(i) = t.warped.row(i * 17);
  }
  SurfaceOptions o;
  o.voxel = 1.0;
  o.feature_zone_rings = 0;
  const SurfaceResult r = SurfaceBinding::bind(t.g, f, o).apply(t.warped, f, no_body, &fw);
  ASSERT_TRUE(r.positions.allFinite());
  EXPECT_GT(r.stats.anchored, 0u);
  EXPECT_EQ(r.stats.anchored_followed, r.stats.anchored);
  const double bump = t.upper_bump(t.warped), left = t.upper_bump(r.positions);
  std::printf("[ info ] anchored upper sheet's bump: warp %.4f, result %.4f\n", bump, left);
  EXPECT_LT(left, 0.25 * bump);

  // Out of reach (the upper sheet 5 voxels up) it stays where the warp put it.
  TwoSheets far;
  for (Eigen::Index v = 289; v < far.g.positions.rows(); ++v) far.g.positions(v, 1) += 5.0, far.warped(v, 1) += 5.0;
  const SurfaceResult rf = SurfaceBinding::bind(far.g, f, o).apply(far.warped, f, no_body, &fw);
  EXPECT_EQ(rf.stats.anchored_followed, 0u);
  EXPECT_LT((rf.positions.bottomRows(289) - far.warped.bottomRows(289)).cwiseAbs().maxCoeff(), 1e-9);
}

}  // namespace
}  // namespace refit
