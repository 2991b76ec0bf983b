// A feature curve cut from one layer of a multi-layer garment stays on that
// layer: the shared outfit's dress profiles pass within 0.05 cm of the jeans
// beneath at the hip, and the fit leaves samples up to 0.05 cm off the dress,
// so they were attached to the jeans, which the collision step then moved
// (written feature gap 0.22 cm on F_heavier, 0.21 on F_taller).
// Skips when ../shared/data is absent.
#include "shared_case.hpp"

#include <refit/body/body_surface.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/resize.hpp>
#include <refit/surface/agents.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

namespace refit {
namespace {

TEST(LayersSharedData, OutfitProfilesStayOnTheDress) {
  const auto outfit = test::shared_case("outfit_dress_jeans");
  if (!outfit) GTEST_SKIP() << "../shared/data is absent: real-data layer test skipped";
  const GarmentBinding binding(outfit->garment, outfit->body_a, {}, outfit->features);
  for (const char* target : {"F_heavier", "F_taller"}) {
    const ResizeResult r = binding.resize(outfit->body(target));
    const double gap = r.report.at("surface").at("feature_gap_written").get<double>();
    std::printf("[ info ] outfit -> %s: written feature gap %.3f cm\n", target, gap);
    EXPECT_LE(gap, 0.05) << target;
  }
}

// Vertices of one layer that another layer covered in the input (a ray out from
// body A's closest point meets it within 3 cm) and that have it behind them on
// body B by more than 0.02 cm (a fifth of a millimetre: not seen; the collision
// step's rounds can end a hair short where two constraints meet). Checked with
// rays, not with the collision step's own covers.
struct Through {
  std::size_t covered = 0, through = 0;
  double deepest = 0.0;
};
Through layers_through(const Garment& g, const BodyMesh& body_a, const BodyMesh& body_b, const Points& result) {
  const std::vector<std::uint32_t> layer = garment_layers(g, 1.0, 0.0);
  const auto layer_mesh = [&](const Points& x, std::uint32_t l) {
    BodyMesh m{x, {}, "layer", ""};
    for (std::size_t f = 0; f < g.faces.rows(); ++f) {
      const auto face = g.faces.row(f);
      if (layer[face[0]] != l) continue;
      for (std::size_t k = 1; k + 1 < face.size(); ++k) m.triangles.push_back({face[0], face[k], face[k + 1]});
    }
    return m;
  };
  const auto outward = [](const BodySurface& body, const Vec3& p) {
    const ClosestPoint cp = body.closest(p);
    return Vec3(body.inside(p) ? (cp.point - p).normalized() : (p - cp.point).normalized());
  };
  const BodySurface a(body_a), b(body_b);
  Through t;
  for (std::uint32_t over = 1; over <= *std::max_element(layer.begin(), layer.end()); ++over) {
    const BodySurface over_in(layer_mesh(g.positions, over)), over_out(layer_mesh(result, over));
    for (Index v = 0; v < g.vertex_count(); ++v) {
      if (layer[v] == over || layer[v] == 0) continue;
      const Vec3 p = row3(g.positions, v);
      if (!(over_in.intersect(p, outward(a, p)) < 3.0)) continue;
      ++t.covered;
      const Vec3 q = row3(result, v), d = outward(b, q);
      const double ahead = over_out.intersect(q, d), behind = over_out.intersect(q, -d);
      if (behind < 1.0 && !(ahead < behind)) t.deepest = std::max(t.deepest, behind);
      if (behind > 0.02 && behind < 1.0 && !(ahead < behind)) ++t.through;
    }
  }
  return t;
}

// The shared suit's trousers lie 0.6-0.8 cm under the jacket at the hip; on
// M_heavier the surface step (each layer solved on its own) took the jacket in
// by 1 cm more than the trousers, 0.31 cm through them, and the warp keeps them
// under it.
TEST(LayersSharedData, SuitTrousersStayUnderTheJacket) {
  const auto suit = test::shared_case("male_suit");
  if (!suit) GTEST_SKIP() << "../shared/data is absent: real-data layer test skipped";
  const BodyMesh body_b = suit->body("M_heavier");
  const ResizeResult r = GarmentBinding(suit->garment, suit->body_a, {}, {}).resize(body_b);
  const Through t = layers_through(*suit->garment, suit->body_a, body_b, r.positions);
  std::printf("[ info ] suit -> M_heavier: %zu vertices under another layer, %zu through it by more than 0.02 cm "
              "(deepest %.3f cm; the step's own count of covers short of their gap: %zu)\n",
              t.covered, t.through, t.deepest, r.report.at("collision").at("layers_crossed_after").get<std::size_t>());
  EXPECT_GT(t.covered, 100u);
  EXPECT_EQ(t.through, 0u);
  EXPECT_LT(t.deepest, 0.02);
}

// The outfit's jeans under the dress at the back waist: the collision step's
// last rounds, which push out what is still inside body B, took the layers in
// their first 3 only, and the fourth pushed a jeans vertex 0.06 cm through the
// dress on F_taller (0.03 cm on F_heavier). Now a round after one that pushed
// something out of the body takes them too.
TEST(LayersSharedData, OutfitJeansStayUnderTheDress) {
  const auto outfit = test::shared_case("outfit_dress_jeans");
  if (!outfit) GTEST_SKIP() << "../shared/data is absent: real-data layer test skipped";
  const GarmentBinding binding(outfit->garment, outfit->body_a, {}, outfit->features);
  for (const char* target : {"F_heavier", "F_taller"}) {
    const BodyMesh body_b = outfit->body(target);
    const ResizeResult r = binding.resize(body_b);
    const Through t = layers_through(*outfit->garment, outfit->body_a, body_b, r.positions);
    std::printf("[ info ] outfit -> %s: %zu vertices under another layer, %zu through it by more than 0.02 cm "
                "(deepest %.3f cm)\n", target, t.covered, t.through, t.deepest);
    EXPECT_GT(t.covered, 100u) << target;
    EXPECT_EQ(t.through, 0u) << target;
  }
}

}  // namespace
}  // namespace refit
