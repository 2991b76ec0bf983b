// Feature file parsing and validation: every error names the file and the feature.
#include <refit/core/error.hpp>
#include <refit/features/feature_file.hpp>

#include <gtest/gtest.h>

#include "support/test_support.hpp"

using namespace refit;

namespace {

const char* kValid = R"({
  "units": "cm",
  "features": [
    { "name": "left-profile",
      "plane": { "point": [0, 0, 0], "normal": [0, 0, 2] },
      "curve": { "kind": "slice", "near": [10, 50, 0], "from": [10, 80, 0], "to": [20, 20, 0], "control_points": 12 },
      "samples": 80 },
    { "name": "hem", "curve": { "kind": "boundary", "near": [0, 10, 20] }, "samples": 120 },
    { "name": "waist",
      "plane": { "segment": [[-20, 90, 0], [20, 90, 0]], "view": [0, 0, -1] },
      "curve": { "kind": "bspline", "degree": 3, "closed": false,
                 "control_points": [[-20, 90, 0], [-10, 91, 5], [0, 92, 10], [10, 91, 5], [20, 90, 0]] },
      "samples": 60 }
  ]
})";

// The message of the refit::Error that parsing `text` throws ("" if none).
std::string error_of(const std::string& text, const std::string& units = "cm") {
  try {
    parse_feature_json(text, "f.json", units);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

std::string one(const std::string& feature) { return R"({"features": [)" + feature + "]}"; }

const std::string kPlane = R"("plane": {"point": [0,0,0], "normal": [0,0,1]})";

}  // namespace

TEST(FeatureFile, ParsesAllThreeKinds) {
  const auto specs = parse_feature_json(kValid, "f.json");
  ASSERT_EQ(specs.size(), 3u);
  EXPECT_EQ(specs[0].name, "left-profile");
  EXPECT_EQ(specs[0].kind, CurveKind::slice);
  ASSERT_TRUE(specs[0].plane.has_value());
  EXPECT_NEAR(specs[0].plane->normal.z(), 1.0, 1e-15);  // normalised
  ASSERT_TRUE(specs[0].from && specs[0].to);
  EXPECT_EQ(specs[0].fit_control_points, 12u);
  EXPECT_EQ(specs[0].samples, 80u);
  EXPECT_EQ(specs[1].kind, CurveKind::boundary);
  EXPECT_FALSE(specs[1].plane.has_value());
  EXPECT_TRUE(specs[1].closed);
  EXPECT_EQ(specs[2].kind, CurveKind::bspline);
  EXPECT_EQ(specs[2].control_points.rows(), 5);
  // Segment along x swept along z: the plane y = 90.
  ASSERT_TRUE(specs[2].plane.has_value());
  EXPECT_NEAR(std::abs(specs[2].plane->normal.y()), 1.0, 1e-12);
  EXPECT_NEAR(specs[2].plane->signed_distance(Vec3(5, 90, 3)), 0.0, 1e-12);
}

TEST(FeatureFile, ConvertsUnitsToTheGarments) {
  std::string mm = kValid;
  mm.replace(mm.find("\"cm\""), 4, "\"mm\"");
  const auto specs = parse_feature_json(mm, "f.json", "cm");
  EXPECT_NEAR(specs[0].near.x(), 1.0, 1e-12);        // 10 mm = 1 cm
  EXPECT_NEAR(specs[0].plane->normal.z(), 1.0, 1e-12);  // directions are not scaled
  EXPECT_NEAR(specs[2].control_points(2, 1), 9.2, 1e-12);
  const auto in_m = parse_feature_json(kValid, "f.json", "m");
  EXPECT_NEAR(in_m[0].near.y(), 0.5, 1e-12);
  EXPECT_NE(error_of(kValid, "furlong").find("unknown units 'furlong'"), std::string::npos);
}

TEST(FeatureFile, ErrorsNameTheFileAndTheFeature) {
  struct Case {
    std::string feature, expect;
  };
  const std::vector<Case> cases = {
      {R"({"name": "a", )" + kPlane + R"(, "curve": {"kind": "spiral"}, "samples": 10})", "unknown curve kind 'spiral'"},
      {R"({"name": "b", )" + kPlane + R"(, "curve": {"kind": "slice", "near": [0,0,0]}})", "missing 'samples'"},
      {R"({"name": "c", )" + kPlane + R"(, "curve": {"kind": "bspline", "control_points": [[0,0,0],[1,0,0],[2,1,0],[3,0,0]]}, "samples": 4})",
       "an open curve needs at least 5 samples"},
      {R"({"name": "d", "plane": {"point": [0,0,0], "normal": [0,0,0]}, "curve": {"kind": "boundary", "near": [0,0,0]}, "samples": 9})",
       "plane normal is zero"},
      {R"({"name": "e", "plane": {"point": [0,0,0], "normal": [0,"x",1]}, "curve": {"kind": "boundary", "near": [0,0,0]}, "samples": 9})",
       "plane normal must be a number"},
      {R"({"name": "f", "plane": {"segment": [[1,1,1],[1,1,1]], "view": [0,0,1]}, "curve": {"kind": "boundary", "near": [0,0,0]}, "samples": 9})",
       "segment has zero length"},
      {R"({"name": "g", "plane": {"segment": [[0,0,0],[0,0,1]], "view": [0,0,-3]}, "curve": {"kind": "boundary", "near": [0,0,0]}, "samples": 9})",
       "parallel to the segment"},
      {R"({"name": "h", )" + kPlane + R"(, "curve": {"kind": "bspline", "degree": 3, "control_points": [[0,0,0],[1,0,0],[2,1,0]]}, "samples": 9})",
       "needs at least 4 control points, got 3"},
      {R"({"name": "i", )" + kPlane + R"(, "curve": {"kind": "slice", "near": [0,0,0], "control_points": 2}, "samples": 9})",
       "at least 4 control points"},
      {R"({"name": "j", "curve": {"kind": "slice", "near": [0,0,0]}, "samples": 9})", "missing 'plane'"},
      {R"({"name": "k", )" + kPlane + R"(, "curve": {"kind": "slice", "near": [0,0]}, "samples": 9})", "curve 'near' must be an array of 3 numbers"},
      {R"({"name": "l", )" + kPlane + R"(, "curve": {"kind": "slice", "near": [0,0,0], "colour": 1}, "samples": 9})", "unknown key 'colour'"},
      {R"({"name": "m", )" + kPlane + R"(, "curve": {"kind": "slice", "near": [0,0,0]}, "samples": 9.5})", "'samples' must be an integer"},
      {R"({"name": "o", )" + kPlane + R"(, "curve": {"kind": "bspline", "closed": true, "control_points": [[0,0,0],[1,0,0],[2,1,0],[3,0,0]]}, "samples": 2})",
       "a closed curve needs at least 3 samples"},
      {R"({"name": "p", )" + kPlane + R"(, "curve": {"kind": "slice", "near": [0,0,0], "from": [1,0,0]}, "samples": 9})", "must be given together"},
      {R"({"name": "q", )" + kPlane + R"(, "curve": {"kind": "slice", "near": [0,0,0]}, "samples": 5001})",
       "'samples' is out of range (5001; at most 5000)"},
      {R"({"name": "r", )" + kPlane + R"(, "curve": {"kind": "slice", "near": [0,0,0], "control_points": 501}, "samples": 9})",
       "curve 'control_points' is out of range (501; at most 500)"},
  };
  for (const Case& c : cases) {
    const std::string msg = error_of(one(c.feature));
    const std::string name = c.feature.substr(10, 1);
    EXPECT_EQ(msg.rfind("f.json: feature '" + name + "': ", 0), 0u) << "message: " << msg;
    EXPECT_NE(msg.find(c.expect), std::string::npos) << "expected '" << c.expect << "' in: " << msg;
  }
}

TEST(FeatureFile, FileLevelErrors) {
  EXPECT_NE(error_of("{\"features\": [\n  {\"name\": \"a\",,}\n]}").find("f.json:2: invalid JSON"), std::string::npos)
      << error_of("{\"features\": [\n  {\"name\": \"a\",,}\n]}");
  EXPECT_NE(error_of(R"({"features": [{"name": "n", "curve": {"kind": "boundary", "near": [0,0,1e999]}, "samples": 9}]})")
                .find("f.json: invalid JSON: number overflow"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"features": []})").find("'features' is empty"), std::string::npos);
  EXPECT_NE(error_of(R"({"feature": []})").find("unknown key 'feature'"), std::string::npos);
  EXPECT_NE(error_of(R"({"features": [{"curve": {"kind": "boundary", "near": [0,0,0]}, "samples": 9}]})").find("feature #1: missing 'name'"),
            std::string::npos);
  const std::string dup = R"({"name": "x", "curve": {"kind": "boundary", "near": [0,0,0]}, "samples": 9})";
  EXPECT_NE(error_of(R"({"features": [)" + dup + "," + dup + "]}").find("feature 'x': the name is used twice"), std::string::npos);
  test::TempDir dir;
  try {
    read_feature_file(dir.file("missing.json"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.json: cannot open"), std::string::npos) << e.what();
  }
  test::write_text(dir.file("ok.json"), kValid);
  EXPECT_EQ(read_feature_file(dir.file("ok.json")).size(), 3u);
}

namespace {

// Seam curves (issue 16): a role of their own, checked like the rest.
TEST(FeatureFile, RolesShapeAndSeam) {
  const auto specs = parse_feature_json(one(R"({"name": "side", "role": "seam",
      "plane": {"point": [0, 0, 0], "normal": [1, 0, 0]},
      "curve": {"kind": "slice", "near": [0, 1, 0]}, "samples": 20})"), "f.json");
  ASSERT_EQ(specs.size(), 1u);
  EXPECT_EQ(specs[0].role, CurveRole::seam);
  EXPECT_EQ(parse_feature_json(kValid, "f.json")[0].role, CurveRole::shape);
  EXPECT_EQ(features_with_role(specs, CurveRole::shape).size(), 0u);
  EXPECT_EQ(features_with_role(specs, CurveRole::seam).size(), 1u);
  EXPECT_EQ(error_of(one(R"({"name": "x", "role": "dart", "curve": {"kind": "boundary", "near": [0, 0, 0]},
      "samples": 20})")),
            "f.json: feature 'x': 'role' must be \"shape\" or \"seam\", got \"dart\"");
  EXPECT_EQ(error_of(one(R"({"name": "hem", "role": "seam", "curve": {"kind": "boundary", "near": [0, 0, 0]},
      "samples": 20})")),
            "f.json: feature 'hem': a seam cannot be a boundary curve (the garment is already cut along its boundary)");
}

}  // namespace
