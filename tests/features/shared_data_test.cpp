// Feature optimisation on the real MakeHuman data (../shared/data; skipped when absent):
// a side profile of the dress, warped from A_female to each female target body.
#include <refit/body/body_surface.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/features/shape_matching.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/warp/warp.hpp>

#include <gtest/gtest.h>

#include <cstdio>

#include "support/test_support.hpp"

using namespace refit;

TEST(SharedData, DressSideProfileGetsItsShapeBack) {
  const std::string dir = test::shared_data_dir();
  if (dir.empty()) GTEST_SKIP() << "../shared/data not found: real-data feature test skipped";
  const Garment dress = read_garment_obj(dir + "/garments/dress_on_A_female.obj");
  BodyMesh a = read_body(dir + "/bodies/A_female.obj");
  // The plane z = the body's centre (mean z of its vertices): a side view of the dress.
  const double zc = a.vertices.col(2).mean();
  // The skirt's left side, from the waist down to the hem (the piece's own ends).
  char json[1024];
  std::snprintf(json, sizeof json, R"({"units": "cm", "features": [
    {"name": "left-profile", "plane": {"point": [0, 0, %.6f], "normal": [0, 0, 1]},
     "curve": {"kind": "slice", "near": [18, -10, %.6f], "from": [18, 15, %.6f], "to": [18, -40, %.6f], "control_points": 12},
     "samples": 80}]})",
                zc, zc, zc, zc);
  std::vector<FeatureCurve> curves = build_feature_curves(dress, parse_feature_json(json, "profile.json"));
  ASSERT_EQ(curves.size(), 1u);
  EXPECT_FALSE(curves[0].closed);
  EXPECT_GT(curves[0].samples(0, 1) - curves[0].samples(79, 1), 25.0);  // waist to hem
  const ReferenceBody ref(std::move(a));
  const FeatureBinding binding = bind_features(ref, curves);
  ShapeMatchingOptions raw;
  raw.sampling_invariant = false;
  const FeatureBinding binding_raw = bind_features(ref, curves, raw);
  for (const char* target : {"F_heavier", "F_thinner", "F_taller"}) {
    SCOPED_TRACE(target);
    const BodyMesh b = read_body(dir + "/bodies/" + target + ".obj");
    check_same_connectivity(ref.mesh(), b);
    const BodySurface surface(b);
    const auto distance = [&](const Vec3& p) { return surface.closest(p).distance; };
    const FeatureResult r = optimise_features(binding, compute_frames(b), distance);
    const FeatureResult rr = optimise_features(binding_raw, compute_frames(b), distance);
    const CurveResult& c = r.curves[0];
    std::printf("[ info ] %s: shape error warped %.5f -> optimised %.5f (paper's raw weights: %.5f); "
                "turning-angle change %.3f -> %.3f deg (raw: %.3f); held sample %u (%s %.2f cm); max move from warped %.2f cm\n",
                target, c.shape_error_warped, c.shape_error_result, rr.curves[0].shape_error_result,
                c.turning_angle_change_warped_deg, c.turning_angle_change_result_deg,
                rr.curves[0].turning_angle_change_result_deg, c.fixed.at(0).index, c.fixed.at(0).reason.c_str(),
                c.fixed.at(0).distance, (c.optimised - c.warped).rowwise().norm().maxCoeff());
    EXPECT_GT(c.shape_error_warped, 0.0);
    EXPECT_LE(10.0 * c.shape_error_result, c.shape_error_warped);
  }
}
