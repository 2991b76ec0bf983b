// `refit flatten` and its files: the SVG renders (rsvg-convert) at true scale,
// the DXF is read back by an independent reader (ezdxf) with the same pieces,
// outline lengths and layers as the report, the grading view, and bad input.
#include "patterns/pattern_fixtures.hpp"
#include "support/test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

namespace refit {
namespace {

using ::testing::HasSubstr;
using json = nlohmann::json;

// A skirt-like closed tube of two groups (front: angles 0 to pi, back: the
// rest) around y, 15 cm radius, 40 cm tall, `bump` cm of bumps; `grow` scales x
// and z (a "resized" copy with the same elements).
std::string tube_obj(double bump, double grow = 1.0) {
  const int nu = 24, nv = 10;
  std::string s;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double a = 2 * M_PI * i / nu, y = 4.0 * j;
      const double r = grow * (15.0 + bump * std::sin(3 * a) * std::sin(2 * M_PI * j / 5.0));
      s += "v " + std::to_string(r * std::cos(a)) + " " + std::to_string(y) + " " + std::to_string(r * std::sin(a)) + "\n";
    }
  const auto idx = [&](int i, int j) { return std::to_string(j * nu + i % nu + 1); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      if (i == 0 || i == nu / 2) s += i == 0 ? "g front\n" : "g back\n";
      s += "f " + idx(i, j) + " " + idx(i, j + 1) + " " + idx(i + 1, j + 1) + " " + idx(i + 1, j) + "\n";
    }
  return s;
}

// A shape curve down the front: a vertical line at angle 0.25 rad.
const char* kFeatures = R"({"features": [{"name": "crease",
  "plane": {"point": [0, 0, 0], "normal": [-0.2474, 0, 0.9689]},
  "curve": {"kind": "slice", "near": [14.53, 20, 3.71], "from": [14.53, 1, 3.71], "to": [14.53, 39, 3.71]},
  "samples": 30}]})";

bool have(const char* program) { return test::run_shell(std::string("command -v ") + program).exit_code == 0; }

TEST(FlattenCli, WritesSvgDxfAndReportThatAgree) {
  test::TempDir dir;
  test::write_text(dir.file("tube.obj"), tube_obj(0.5));
  test::write_text(dir.file("f.json"), kFeatures);
  const auto r = test::run_cli("flatten --garment '" + dir.file("tube.obj") + "' --features '" + dir.file("f.json") +
                               "' --out-dir '" + dir.file("out") + "' --stretch-map");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("2 panels"));
  const json report = json::parse(test::read_text(dir.file("out/tube.json")));
  ASSERT_EQ(report["panels"].size(), 2u);
  EXPECT_EQ(report["panels"][0]["name"], "front");
  EXPECT_EQ(report["units"], "cm");
  std::vector<double> outlines;
  for (const auto& p : report["panels"]) {
    EXPECT_TRUE(p["flattened"].get<bool>());
    EXPECT_LT(std::abs(p["area_change"].get<double>()), 0.02);
    for (const auto& l : p["outline_lengths"]) outlines.push_back(l.get<double>());
  }
  // The crease runs over the front only, drawn as an internal line.
  ASSERT_EQ(report["panels"][0]["feature_lines"].size(), 1u);
  EXPECT_EQ(report["panels"][0]["feature_lines"][0]["name"], "crease");
  EXPECT_NEAR(report["panels"][0]["feature_lines"][0]["length_2d"].get<double>(), 38.0, 1.0);
  // The two side seams: sewn edges agree.
  ASSERT_EQ(report["seams"].size(), 2u);
  for (const auto& s : report["seams"]) EXPECT_LT(s["mismatch"].get<double>(), 0.005);

  // The SVG: true scale in cm, and it renders.
  const std::string svg = test::read_text(dir.file("out/tube.svg"));
  EXPECT_THAT(svg, HasSubstr("width=\""));
  EXPECT_THAT(svg, HasSubstr("cm\" height=\""));
  EXPECT_THAT(svg, HasSubstr("<g id=\"FEATURES\""));
  if (have("rsvg-convert")) {
    const auto png = test::run_shell("rsvg-convert -o '" + dir.file("tube.png") + "' '" + dir.file("out/tube.svg") + "'");
    EXPECT_EQ(png.exit_code, 0) << png.err;
    EXPECT_GT(std::filesystem::file_size(dir.file("tube.png")), 1000u);
  } else {
    ADD_FAILURE() << "rsvg-convert not found (Debian: librsvg2-bin, tools/setup.sh installs it)";
  }

  // The DXF through ezdxf: the same closed outlines (count and lengths) on CUT,
  // the crease on FEATURES, centimetres in the header.
  const auto dxf = test::run_shell("/usr/bin/python3 '" REFIT_SOURCE_DIR "/tests/patterns/read_dxf.py' '" +
                                   dir.file("out/tube.dxf") + "'");
  if (dxf.exit_code == 77) GTEST_SKIP() << dxf.out;
  ASSERT_EQ(dxf.exit_code, 0) << dxf.err;
  const json back = json::parse(dxf.out);
  EXPECT_EQ(back["errors"], 0);
  EXPECT_EQ(back["insunits"], 5);
  for (const char* layer : {"CUT", "FEATURES", "GRAIN", "TEXT"})
    EXPECT_NE(std::find(back["layers"].begin(), back["layers"].end(), layer), back["layers"].end()) << layer;
  std::vector<double> read;
  for (const auto& p : back["polylines"]["CUT"]) {
    EXPECT_TRUE(p["closed"].get<bool>());
    read.push_back(p["length"].get<double>());
  }
  std::sort(outlines.begin(), outlines.end());
  std::sort(read.begin(), read.end());
  ASSERT_EQ(read.size(), outlines.size());
  for (std::size_t i = 0; i < read.size(); ++i) EXPECT_NEAR(read[i], outlines[i], 1e-4 * outlines[i]);
  ASSERT_EQ(back["polylines"]["FEATURES"].size(), 1u);
  EXPECT_FALSE(back["polylines"]["FEATURES"][0]["closed"].get<bool>());
  EXPECT_EQ(back["texts"]["TEXT"], json({"front", "back"}));
}

TEST(FlattenCli, GradingComparesTheResizedPieces) {
  test::TempDir dir;
  test::write_text(dir.file("tube.obj"), tube_obj(0.0));
  test::write_text(dir.file("big.obj"), tube_obj(0.0, 1.1));
  test::write_text(dir.file("f.json"), kFeatures);
  const auto r = test::run_cli("flatten --garment '" + dir.file("big.obj") + "' --original '" + dir.file("tube.obj") +
                               "' --features '" + dir.file("f.json") + "' --out-dir '" + dir.file("out") +
                               "' --sheet-units mm --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(dir.file("out/big-grading.svg")));
  EXPECT_THAT(test::read_text(dir.file("out/big.svg")), HasSubstr("mm\" height=\""));
  const json g = json::parse(test::read_text(dir.file("out/big.json")))["grading"];
  ASSERT_EQ(g["panels"].size(), 2u);
  for (const auto& p : g["panels"]) {
    // 10 % wider all round, as tall: 10 % more area.
    EXPECT_NEAR(p["area_change"].get<double>(), 0.1, 0.005);
    EXPECT_NEAR(p["height_change"].get<double>(), 0.0, 0.02);
  }
  // A uniform growth around a vertical line keeps the crease's shape.
  ASSERT_EQ(g["feature_lines"], 1);
  EXPECT_LT(g["straightness_max"].get<double>(), 2e-3);
}

TEST(FlattenCli, BadInputIsOneLineAndNoFiles) {
  test::TempDir dir;
  // A closed box: its panel cannot be flattened.
  test::write_text(dir.file("box.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                                        "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  const auto r = test::run_cli("flatten --garment '" + dir.file("box.obj") + "' --out-dir '" + dir.file("out") + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err, "refit: error: " + dir.file("box.obj") +
                       ": panel 'piece-1' (6 faces) cannot be flattened: it is closed (no boundary): cut it with an "
                       "OBJ group, a UV seam or a seam curve\n");
  EXPECT_FALSE(std::filesystem::exists(dir.file("out/box.svg")));
  // A resized garment that is not the original's.
  test::write_text(dir.file("tube.obj"), tube_obj(0.0));
  const auto other = test::run_cli("flatten --garment '" + dir.file("box.obj") + "' --original '" +
                                   dir.file("tube.obj") + "' --out-dir '" + dir.file("out") + "'");
  EXPECT_EQ(other.exit_code, 1);
  EXPECT_THAT(other.err, HasSubstr("not the same garment as --original"));
  const auto usage = test::run_cli("flatten --garment '" + dir.file("tube.obj") + "' --out-dir '" + dir.file("out") +
                                   "' --sheet-units km");
  EXPECT_EQ(usage.exit_code, 2);
}

}  // namespace
}  // namespace refit
