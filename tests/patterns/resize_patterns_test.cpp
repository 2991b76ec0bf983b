// `refit resize --patterns-out DIR`: each result's pattern files appear with the
// garment (the original cut once, graded against the result), and a bad folder
// is refused before any work with one line and no outputs; a piece that cannot
// be flattened stops the run unless --skip-unflattenable leaves it out.
#include "cli/cli_case.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <sstream>

namespace refit {
namespace {

using ::testing::ElementsAre;

TEST(ResizePatterns, WritesThePatternsOfTheResultBesideTheGarment) {
  const test::Case c(2000);
  const std::string out = c.dir.file("r.obj"), report = c.dir.file("r.json"), dir = c.dir.file("patterns");
  const auto r = test::run_cli(c.resize(out, "--report '" + report + "' --patterns-out '" + dir + "'"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(test::files_in(dir), ElementsAre("B-grading.svg", "B.dxf", "B.json", "B.svg"));
  const nlohmann::json summary = nlohmann::json::parse(test::read_text(report))["patterns"];
  EXPECT_EQ(summary["svg"], dir + "/B.svg");
  EXPECT_EQ(summary["panels"], 1);
  // The pattern's report is of the result: its pieces are the resized garment's,
  // graded against the original's (the belly and hips of B make them larger).
  const nlohmann::json patterns = nlohmann::json::parse(test::read_text(dir + "/B.json"));
  ASSERT_EQ(patterns["grading"]["panels"].size(), 1u);
  EXPECT_GT(patterns["grading"]["panels"][0]["area_change"].get<double>(), 0.0);
  EXPECT_EQ(summary["stretch_p95"], patterns["stretch_p95"]);
}

TEST(ResizePatterns, AFolderThatIsAFileIsRefusedBeforeAnyWork) {
  const test::Case c(2000);
  const std::string out = c.dir.file("r.obj"), not_a_folder = c.dir.file("taken");
  test::write_text(not_a_folder, "x");
  const auto r = test::run_cli(c.resize(out, "--patterns-out '" + not_a_folder + "'"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err.rfind("refit: error: " + not_a_folder + ": ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_EQ(test::read_text(not_a_folder), "x");
}

// The dress with a small closed box (its own group) at its first vertex: a piece
// that no flattening takes.
void add_closed_box(const std::string& garment) {
  std::istringstream in(test::read_text(garment));
  std::string line, text;
  std::size_t vertices = 0;
  double x = 0, y = 0, z = 0;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0 && vertices++ == 0) std::istringstream(line.substr(2)) >> x >> y >> z;
    text += line + "\n";
  }
  for (int i = 0; i < 8; ++i)
    text += "v " + std::to_string(x + (i & 1)) + " " + std::to_string(y + ((i >> 1) & 1)) + " " + std::to_string(z + ((i >> 2) & 1)) + "\n";
  const auto f = [&](int a, int b, int c, int d) {
    text += "f " + std::to_string(vertices + a) + " " + std::to_string(vertices + b) + " " + std::to_string(vertices + c) +
            " " + std::to_string(vertices + d) + "\n";
  };
  text += "g box\n";
  f(1, 3, 4, 2), f(5, 6, 8, 7), f(1, 2, 6, 5), f(3, 7, 8, 4), f(1, 5, 7, 3), f(2, 4, 8, 6);
  test::write_text(garment, text);
}

TEST(ResizePatterns, AClosedPieceStopsTheRunUnlessSkipped) {
  const test::Case c(2000);
  add_closed_box(c.garment);
  const std::string out = c.dir.file("r.obj"), dir = c.dir.file("patterns");
  const auto refused = test::run_cli(c.resize(out, "--patterns-out '" + dir + "'"));
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_EQ(refused.err.rfind("refit: error: " + c.garment + ": panel 'box' (6 faces) cannot be flattened: it is closed", 0), 0u)
      << refused.err;
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_FALSE(std::filesystem::exists(dir + "/B.svg"));

  const auto skipped = test::run_cli(c.resize(out, "--patterns-out '" + dir + "' --skip-unflattenable"));
  ASSERT_EQ(skipped.exit_code, 0) << skipped.err;
  EXPECT_THAT(test::files_in(dir), ElementsAre("B-grading.svg", "B.dxf", "B.json", "B.svg"));
  const nlohmann::json patterns = nlohmann::json::parse(test::read_text(dir + "/B.json"));
  bool box_left_out = false, dress_flattened = false;
  for (const auto& p : patterns["panels"]) {
    if (p["name"] == "box") box_left_out = !p["flattened"].get<bool>();
    else dress_flattened = dress_flattened || p["flattened"].get<bool>();
  }
  EXPECT_TRUE(box_left_out);
  EXPECT_TRUE(dress_flattened);
  ASSERT_FALSE(patterns["warnings"].empty());
  EXPECT_THAT(patterns["warnings"][0].get<std::string>(), ::testing::HasSubstr("panel 'box' (6 faces) cannot be flattened"));
}

}  // namespace
}  // namespace refit
