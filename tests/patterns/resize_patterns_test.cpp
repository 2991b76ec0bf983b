// `refit resize --patterns-out DIR`: each result's pattern files appear with the
// garment (the original cut once, graded against the result), and a bad folder
// is refused before any work with one line and no outputs.
#include "cli/cli_case.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>

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

}  // namespace
}  // namespace refit
