// Issue 13 ("feature profiles of the written garment at least 10x closer to
// their original shape than the warp alone") on a body the solve's held sample
// does not suit: the shared skirt on body A made 9 % shorter (the quality suite's
// F_shorter). The straightened side profile sank into the hip, and bending it
// clear left it 2.5x closer than the warp's (the report's figures); turned and
// scaled clear of the body as a whole first (ShapeMatchingOptions::placement_band),
// each given profile comes out at least 10x closer (the quality suite's own
// measure: 11x), the mirrored one 8.5x (the suite holds it to 3x, as a profile
// between the features). Skips when ../shared/data is absent.
#include "shared_case.hpp"

#include <refit/features/feature_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/resize.hpp>

#include <gtest/gtest.h>

#include <cstdio>

namespace refit {
namespace {

TEST(PlacementSharedData, TheSkirtOnAShorterBodyKeepsItsProfilesShape) {
  const auto shared = test::shared_case("skirt");
  if (!shared) GTEST_SKIP() << "../shared/data is absent: real-data placement test skipped";
  const auto& skirt = shared->garment;
  const BodyMesh& a = shared->body_a;
  const std::vector<FeatureSpec>& features = shared->features;
  BodyMesh b = a;  // 9 % shorter, as wide (its heights scaled about the soles)
  const double floor = a.vertices.col(1).minCoeff();
  b.vertices.col(1) = (a.vertices.col(1).array() - floor) * 0.91 + floor;
  const ResizeResult r = GarmentBinding(skirt, a, {}, features, Progress(false)).resize(b);
  double placed = 0.0;
  for (const auto& c : r.report.at("features")) {
    const double got = c.at("shape_error_output").get<double>(), warp = c.at("shape_error_output_warped").get<double>();
    std::printf("[ info ] skirt on A 9 %% shorter, %s: shape error warp %.6f, written %.6f (%.1fx), placed %.3f cm\n",
                c.at("name").get<std::string>().c_str(), warp, got, warp / got, c.at("placed").get<double>());
    const bool mirrored = c.at("name").get<std::string>().ends_with("~mirror");
    EXPECT_LE(got, (mirrored ? 0.2 : 0.1) * warp) << c.at("name").get<std::string>();
    placed = std::max(placed, c.at("placed").get<double>());
  }
  EXPECT_GT(placed, 0.0);  // the placement is what does it (2.5x without)
  EXPECT_LE(r.report.at("surface").at("feature_gap_written").get<double>(), 0.05);
}

}  // namespace
}  // namespace refit
