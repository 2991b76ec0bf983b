// `refit features`: writes the sampled curves, or one error line and nothing.
#include <gtest/gtest.h>

#include <filesystem>

#include "mannequin/mannequin.hpp"
#include "support/test_support.hpp"

using namespace refit;

TEST(CliFeatures, WritesCurvesOrRefusesWithOneLine) {
  if (!std::filesystem::exists(REFIT_CLI_PATH)) GTEST_SKIP() << "the refit command line is not built (ninja refit_cli)";
  test::TempDir dir;
  const auto r0 = test::run_cli("generate --vertices 3000 --garment-out " + dir.file("d.obj") + " --features-out " +
                                dir.file("d.json"));
  ASSERT_EQ(r0.exit_code, 0) << r0.err;
  const auto r = test::run_cli("features --garment " + dir.file("d.obj") + " --features " + dir.file("d.json") +
                               " --out " + dir.file("c.obj"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string obj = test::read_text(dir.file("c.obj"));
  for (const char* g : {"g left-profile_original", "g right-profile_original", "g front-profile_original",
                        "g back-profile_original", "g hem_original"})
    EXPECT_NE(obj.find(g), std::string::npos) << g;
  std::string bad = test::read_text(dir.file("d.json"));
  bad.replace(bad.find("\"kind\": \"slice\""), 15, "\"kind\": \"spline\"");
  test::write_text(dir.file("bad.json"), bad);
  const auto e = test::run_cli("features --garment " + dir.file("d.obj") + " --features " + dir.file("bad.json") +
                               " --out " + dir.file("c2.obj"));
  EXPECT_NE(e.exit_code, 0);
  EXPECT_NE(e.err.find("bad.json: feature 'left-profile': unknown curve kind 'spline'"), std::string::npos) << e.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("c2.obj")));
}
