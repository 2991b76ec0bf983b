// `refit inspect`: the `name: value` lines, the --json object and bad input.
#include "support/test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

namespace refit {
namespace {

using ::testing::HasSubstr;

// The CLI is built by the refit_cli target, which test_io does not depend on.
bool cli_built() { return std::filesystem::exists(REFIT_CLI_PATH); }

// Two triangles sharing edge 1-3, a hanging line, a loose point, an unreferenced vertex.
const char* kGarment = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 2 2\nv 3 3 3\nv 9 9 9\n"
                       "f 1 2 3\nf 1 3 4\nl 3 5\np 6\n";

TEST(InspectCli, PrintsNameValueLines) {
  if (!cli_built()) GTEST_SKIP() << "refit CLI not built (build the refit_cli target first)";
  test::TempDir dir;
  const std::string path = dir.file("g.obj");
  test::write_text(path, kGarment);
  const auto r = test::run_cli("inspect '" + path + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out,
            "vertices: 7\nfaces: 2\nlines: 1\npoints: 1\nunreferenced_vertices: 1\nedges: 5\n"
            "boundary_edges: 4\nnon_manifold_edges: 0\nboundary_loops: 1\ncomponents: 2\nlayers: 1\n"
            "loose_vertices: 2\npanels: 1\npanel piece-1: 2 faces, 4 vertices, 1 boundary loops\n");
}

TEST(InspectCli, JsonHasTheSameNumbers) {
  if (!cli_built()) GTEST_SKIP() << "refit CLI not built (build the refit_cli target first)";
  test::TempDir dir;
  const std::string path = dir.file("g.obj");
  test::write_text(path, kGarment);
  const auto r = test::run_cli("inspect --json '" + path + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("vertices"), 7);
  EXPECT_EQ(j.at("unreferenced_vertices"), 1);
  EXPECT_EQ(j.at("edges"), 5);
  EXPECT_EQ(j.at("boundary_loops"), 1);
  EXPECT_EQ(j.at("components"), 2);
  EXPECT_EQ(j.at("layers"), 1);          // the two triangles and the line hanging from them
  EXPECT_EQ(j.at("loose_vertices"), 2);  // the point and the unreferenced vertex
  EXPECT_EQ(j.at("file"), path);
}

TEST(InspectCli, BadFileGivesOneLineError) {
  if (!cli_built()) GTEST_SKIP() << "refit CLI not built (build the refit_cli target first)";
  test::TempDir dir;
  const std::string path = dir.file("bad.obj");
  test::write_text(path, "v 0 0 0\nv 1 0 0\nf 1 2 7\n");
  const auto r = test::run_cli("inspect '" + path + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr(path + ":3: vertex index 7 out of range"));
  EXPECT_EQ(r.out, "");
}

}  // namespace
}  // namespace refit
