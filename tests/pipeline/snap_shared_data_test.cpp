// Issue 13 ("meeting curves meet: feature gap at most 0.05 cm") on the shared
// dress, whose side profiles end at the armholes. There the garment agents
// crowd the feature agents out of a vertex's 8 blended agents, so a corner of
// the face a profile's top sample sits on had no feature agent at all, and the
// snap through the blends (--snap-radius 0) could not move it: the written dress
// was 0.105 cm off its side profiles on F_thinner. The snap now moves every
// vertex within 2 voxels of a sample (SurfaceBinding::snap_reach).
//
// On a symmetric pair the garment is then made symmetric, each vertex the mean
// of itself and its mirror image carried on the other side's faces. The outfit's
// dress is not vertex-symmetric: that took it 0.053 cm off its mirrored side
// profile, 0.072 once written on F_thinner. The snap runs again after it, its
// moves made alike on both sides (GarmentBinding::surface_step). Skips when
// ../shared/data is absent.
#include "shared_case.hpp"

#include <refit/features/feature_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/resize.hpp>

#include <gtest/gtest.h>

#include <map>
#include <tuple>

#include <cstdio>

namespace refit {
namespace {

TEST(SnapSharedData, TheWrittenDressPassesThroughItsSideProfiles) {
  const auto dress = test::shared_case("dress");
  if (!dress) GTEST_SKIP() << "../shared/data is absent: real-data dress gap test skipped";
  const auto& garment = dress->garment;
  const BodyMesh& a = dress->body_a;
  const std::vector<FeatureSpec>& features = dress->features;
  const GarmentBinding binding(garment, a, {}, features);
  ResizeOptions through_blends;
  through_blends.surface.snap_radius = 0.0;
  through_blends.surface.snap_regularisation = 1e-3;  // the values before the snap had its own reach
  const GarmentBinding before(garment, a, through_blends, features);
  for (const char* target : {"F_thinner", "F_heavier"}) {
    SCOPED_TRACE(target);
    const BodyMesh b = dress->body(target);
    const ResizeResult r = binding.resize(b);
    const double gap = r.report.at("surface").at("feature_gap").get<double>();
    const double written = r.report.at("surface").at("feature_gap_written").get<double>();
    const double old_gap = before.resize(b).report.at("surface").at("feature_gap").get<double>();
    std::printf("[ info ] dress -> %s: feature gap %.3f cm (through the blends %.3f cm), written %.3f cm\n", target,
                gap, old_gap, written);
    EXPECT_LE(written, 0.05);
    EXPECT_LE(gap, old_gap);
  }
}

TEST(SnapSharedData, TheWrittenOutfitPassesThroughItsMirroredSideProfile) {
  const auto outfit = test::shared_case("outfit_dress_jeans");
  if (!outfit) GTEST_SKIP() << "../shared/data is absent: real-data outfit gap test skipped";
  const GarmentBinding binding(outfit->garment, outfit->body_a, {}, outfit->features);
  const ResizeResult r = binding.resize(outfit->body("F_thinner"));
  const nlohmann::json& s = r.report.at("surface");
  const double symmetrised = s.at("feature_gap_symmetrised").get<double>();
  const double written = s.at("feature_gap_written").get<double>();
  std::printf("[ info ] outfit -> F_thinner: feature gap %.3f cm after the snap, %.3f after the symmetrisation, "
              "written %.3f cm\n", s.at("feature_gap").get<double>(), symmetrised, written);
  EXPECT_GT(symmetrised, 0.05);  // what the second snap is there for
  EXPECT_TRUE(s.at("snapped_after_symmetrising").get<bool>());
  EXPECT_LE(written, 0.05);
}

// The skirt is vertex-symmetric: without the collision step (whose pushes are
// not alike on both sides), the snap after the symmetrisation keeps it so. Its
// own moves are not: the two sides' quads are cut into triangles differently,
// and it left the waist 0.05 cm out of symmetry before its moves were made alike.
TEST(SnapSharedData, TheSnapAfterTheSymmetrisationKeepsTheSkirtSymmetric) {
  const auto skirt = test::shared_case("skirt");
  if (!skirt) GTEST_SKIP() << "../shared/data is absent: real-data skirt symmetry test skipped";
  const auto& garment = skirt->garment;
  const BodyMesh& a = skirt->body_a;
  const std::vector<FeatureSpec>& features = skirt->features;
  ResizeOptions o;
  o.collision = false;
  const GarmentBinding binding(garment, a, o, features);
  const Points& x = garment->positions;
  std::map<std::tuple<double, double, double>, Index> at;
  for (Index i = 0; i < x.rows(); ++i) at[{x(i, 0), x(i, 1), x(i, 2)}] = i;
  // (On F_heavier that snap is not kept: it takes one side profile 0.003 cm farther off.)
  for (const char* target : {"F_thinner", "F_taller"}) {
    SCOPED_TRACE(target);
    const ResizeResult r = binding.resize(skirt->body(target));
    ASSERT_TRUE(r.report.at("surface").at("snapped_after_symmetrising").get<bool>());
    double worst = 0.0;
    std::size_t pairs = 0;
    for (Index i = 0; i < x.rows(); ++i) {
      const auto partner = at.find({-x(i, 0), x(i, 1), x(i, 2)});
      if (partner == at.end()) continue;
      ++pairs;
      Vec3 mirrored = row3(r.positions, partner->second);
      mirrored.x() = -mirrored.x();
      worst = std::max(worst, (row3(r.positions, i) - mirrored).norm());
    }
    ASSERT_EQ(pairs, std::size_t(x.rows()));  // the body's plane is x = 0 and every vertex has its mirror
    EXPECT_LE(worst, 1e-6);
    EXPECT_LE(r.report.at("surface").at("feature_gap_written").get<double>(), 0.05);
  }
}

// A body further from body A than the shared ones (the quality suite's
// F_heaviest: body A plus 1.6 times F_heavier's difference from it) bulges at
// the hips under the coarse faces the dress's side profiles cross, where the
// curves' own clearance does not see it: the collision step pushed those faces
// off the body and took the written dress 0.09 cm off its curves. The shape
// steps then run again with those samples kept as far off as the push left
// them (ResizeOptions::lift_pushed_curves). Measured without the slide beside
// the features (SurfaceOptions::feature_slide_rings), which lets the surface
// there follow the curves off the bulge and leaves 0.018 cm without the lift.
TEST(SnapSharedData, TheCurvesLiftWhereTheCollisionStepPushedTheirFaces) {
  const auto dress = test::shared_case("dress");
  if (!dress) GTEST_SKIP() << "../shared/data is absent: real-data lifted curves test skipped";
  const auto& garment = dress->garment;
  const BodyMesh& a = dress->body_a;
  const std::vector<FeatureSpec>& features = dress->features;
  BodyMesh heaviest = dress->body("F_heavier");
  heaviest.vertices = a.vertices + 1.6 * (heaviest.vertices - a.vertices);
  ResizeOptions held;
  held.surface.feature_slide_rings = 0;
  ResizeOptions unlifted = held;
  unlifted.lift_pushed_curves = false;
  const ResizeResult r = GarmentBinding(garment, a, held, features).resize(heaviest);
  const ResizeResult r0 = GarmentBinding(garment, a, unlifted, features).resize(heaviest);
  const double written = r.report.at("surface").at("feature_gap_written").get<double>();
  const double written0 = r0.report.at("surface").at("feature_gap_written").get<double>();
  std::printf("[ info ] dress -> 1.6 x F_heavier: written feature gap %.3f cm, %.3f without the lift\n", written,
              written0);
  EXPECT_GT(written0, 0.05);  // what the lift is there for
  EXPECT_TRUE(r.report.at("surface").at("lifted_off_pushes").get<bool>());
  EXPECT_FALSE(r0.report.at("surface").at("lifted_off_pushes").get<bool>());
  EXPECT_LE(written, 0.05);
  EXPECT_EQ(r.report.at("collision").at("faces_inside_after").get<int>(), 0);
  EXPECT_EQ(r.report.at("collision").at("inside_after").get<int>(), 0);
}

}  // namespace
}  // namespace refit
