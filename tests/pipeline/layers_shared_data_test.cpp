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

// The shared suit's trousers lie 0.6-0.8 cm under the jacket at the hip; on
// M_heavier the surface step (each layer solved on its own) took the jacket in
// by 1 cm more than the trousers, 0.31 cm through them, and the warp keeps them
// under it. Checked with rays, not with the step's own covers: each trouser
// vertex the jacket covers in the input (a ray out from body A's closest point
// meets the jacket within 3 cm) must not have the jacket behind it on body B by
// more than 0.02 cm (a fifth of a millimetre: not seen; the collision step's
// rounds can end a hair short where two constraints meet).
TEST(LayersSharedData, SuitTrousersStayUnderTheJacket) {
  const auto suit = test::shared_case("male_suit");
  if (!suit) GTEST_SKIP() << "../shared/data is absent: real-data layer test skipped";
  const Garment& g = *suit->garment;
  const std::vector<std::uint32_t> piece = garment_layers(g, 1.0, 0.0);
  const BodyMesh body_b = suit->body("M_heavier");
  const ResizeResult r = GarmentBinding(suit->garment, suit->body_a, {}, {}).resize(body_b);
  // The jacket: the piece of the most vertices; the trousers: the other pieces'.
  std::vector<std::size_t> count(*std::max_element(piece.begin(), piece.end()) + 1, 0);
  for (std::uint32_t p : piece) ++count[p];
  const auto jacket = std::uint32_t(std::max_element(count.begin() + 1, count.end()) - count.begin());
  const auto jacket_mesh = [&](const Points& x) {
    BodyMesh m{x, {}, "jacket", ""};
    for (std::size_t f = 0; f < g.faces.rows(); ++f) {
      const auto face = g.faces.row(f);
      if (piece[face[0]] != jacket) continue;
      for (std::size_t k = 1; k + 1 < face.size(); ++k) m.triangles.push_back({face[0], face[k], face[k + 1]});
    }
    return m;
  };
  const auto outward = [](const BodySurface& body, const Vec3& p) {
    const ClosestPoint cp = body.closest(p);
    return Vec3(body.inside(p) ? (cp.point - p).normalized() : (p - cp.point).normalized());
  };
  const BodySurface a(suit->body_a), b(body_b), jacket_in(jacket_mesh(g.positions)), jacket_out(jacket_mesh(r.positions));
  std::size_t covered = 0, through = 0;
  double deepest = 0.0;
  for (Index v = 0; v < g.vertex_count(); ++v) {
    if (piece[v] == jacket || piece[v] == 0) continue;
    const Vec3 p = row3(g.positions, v);
    if (!(jacket_in.intersect(p, outward(a, p)) < 3.0)) continue;
    ++covered;
    const Vec3 q = row3(r.positions, v), d = outward(b, q);
    const double ahead = jacket_out.intersect(q, d), behind = jacket_out.intersect(q, -d);
    if (behind < 1.0 && !(ahead < behind)) deepest = std::max(deepest, behind);
    if (behind > 0.02 && behind < 1.0 && !(ahead < behind)) ++through;
  }
  std::printf("[ info ] suit -> M_heavier: %zu trouser vertices under the jacket, %zu through it by more than 0.02 cm "
              "(deepest %.3f cm; the step's own count of covers short of their gap: %zu)\n",
              covered, through, deepest, r.report.at("collision").at("layers_crossed_after").get<std::size_t>());
  EXPECT_GT(covered, 100u);
  EXPECT_EQ(through, 0u);
  EXPECT_LT(deepest, 0.02);
}

}  // namespace
}  // namespace refit
