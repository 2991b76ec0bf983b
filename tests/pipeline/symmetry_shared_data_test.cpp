// Issue 13 item 2 on real data: the MakeHuman skirt (mirror-symmetric about x = 0,
// like every shared body) with a hem, a front and only a LEFT profile
// (bench/quality/features/skirt.json). The left profile's mirror becomes a
// feature, and the written garment is at most 0.1 cm less symmetric than the warp
// (here: at least twice as symmetric);
// a lopsided body B is not forced into symmetry.
// Skips when ../shared/data is absent.
#include "shared_case.hpp"

#include <refit/body/centre_tree.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/resize.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace refit {
namespace {

// Largest distance between a vertex and the mirror image (x -> -x) of its partner,
// partners found on the original garment (vertices at each other's mirror image).
double mirror_error(const Points& original, const Points& p) {
  const PointTree tree(original);
  double worst = 0.0;
  for (Index i = 0; i < original.rows(); ++i) {
    const Vec3 q = row3(original, i);
    const auto [j, d2] = tree.nearest(Vec3(-q.x(), q.y(), q.z()));
    if (d2 > 1e-6) continue;  // no partner
    const Vec3 a = row3(p, i), b = row3(p, j);
    worst = std::max(worst, (a - Vec3(-b.x(), b.y(), b.z())).norm());
  }
  return worst;
}

TEST(SymmetrySharedData, OneSidedProfileKeepsSkirtSymmetric) {
  const auto skirt = test::shared_case("skirt");
  if (!skirt) GTEST_SKIP() << "../shared/data is absent: real-data symmetry test skipped";
  const auto& garment = skirt->garment;
  const BodyMesh& a = skirt->body_a;
  const std::vector<FeatureSpec>& features = skirt->features;
  const GarmentBinding binding(garment, a, {}, features);
  for (const char* target : {"F_heavier", "F_thinner"}) {
    const ResizeResult r = binding.resize(skirt->body(target));
    const nlohmann::json& sym = r.report.at("symmetry");
    EXPECT_TRUE(sym.at("symmetric").get<bool>()) << target;
    EXPECT_EQ(sym.at("mirrored_features"), nlohmann::json::array({"left~mirror"})) << target;
    const double warp = mirror_error(garment->positions, r.warped), result = mirror_error(garment->positions, r.positions);
    // The surface step goes through the symmetrised curves (the gap asserted).
    // On the written garment the gap is 0.18-0.26 cm (issue 13's 0.05 not met):
    // the collision step moves the waistband faces' corners under the front
    // profile's top samples (docs/method.md).
    std::printf("[ info ] skirt -> %s: mirror error %.3f cm (warp %.3f cm), feature gap %.4f cm (written %.4f cm)\n",
                target, result, warp, r.report.at("surface").at("feature_gap").get<double>(),
                r.report.at("surface").at("feature_gap_written").get<double>());
    EXPECT_LE(result, warp + 0.1) << target;
    // The collision step moves both sides alike (GarmentMirror::alike_pushes):
    // pushing each side by what it alone needed left 0.19 cm on F_heavier (warp 0.35).
    EXPECT_LE(result, 0.5 * warp) << target;
    EXPECT_LE(r.report.at("surface").at("feature_gap").get<double>(), 0.05) << target;
    EXPECT_TRUE(sym.at("symmetrised").get<bool>()) << target;
  }
  // A body B that is not symmetric (its left side 5 % wider) is not forced into symmetry.
  BodyMesh lopsided = skirt->body("F_heavier");
  for (Eigen::Index i = 0; i < lopsided.vertices.rows(); ++i)
    if (lopsided.vertices(i, 0) > 0.0) lopsided.vertices(i, 0) *= 1.05;
  const ResizeResult r = binding.resize(lopsided);
  EXPECT_GT(r.report.at("symmetry").at("body_b_error").get<double>(), 0.5);
  EXPECT_FALSE(r.report.at("symmetry").at("symmetrised").get<bool>());
}

// The shared suit: its jacket's overlapping front is one-sided (7 % of the
// vertices; their 95th percentile mirror error is 1.1 cm), the rest symmetric.
// It is detected symmetric, and the written suit is at most 0.1 cm less
// symmetric than the warp (before: 0.68 cm against the warp's 0.49 on M_heavier).
TEST(SymmetrySharedData, SuitWithOverlappingFrontStaysSymmetric) {
  const auto suit = test::shared_case("male_suit");
  if (!suit) GTEST_SKIP() << "../shared/data is absent: real-data symmetry test skipped";
  const auto& garment = suit->garment;
  const GarmentBinding binding(garment, suit->body_a);
  const ResizeResult r = binding.resize(suit->body("M_heavier"));
  const nlohmann::json& sym = r.report.at("symmetry");
  EXPECT_TRUE(sym.at("symmetric").get<bool>());
  EXPECT_TRUE(sym.at("symmetrised").get<bool>());
  const double warp = mirror_error(garment->positions, r.warped), result = mirror_error(garment->positions, r.positions);
  std::printf("[ info ] suit -> M_heavier: garment mirror error (90th percentile) %.2f cm; written mirror error %.3f cm "
              "(warp %.3f cm)\n", sym.at("garment_error").get<double>(), result, warp);
  EXPECT_LE(result, warp + 0.1);
}

}  // namespace
}  // namespace refit
