// The real MakeHuman garments in ../shared/data: topology of the messy soup and
// byte-identical round trips.
#include <refit/core/topology.hpp>
#include <refit/io/obj_garment.hpp>

#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <filesystem>

namespace refit {
namespace {

TEST(SharedGarments, DressSoupTopology) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "shared test data (../shared/data) not found";
  const Garment g = read_garment_obj(data + "/garments/dress_soup_on_A_female.obj");
  const TopologyStats s = topology_stats(g);
  EXPECT_EQ(s.vertices, 3656u);
  EXPECT_EQ(s.faces, 2381u);
  EXPECT_EQ(s.lines, 3u);
  EXPECT_EQ(s.points, 2u);
  EXPECT_EQ(s.non_manifold_edges, 6u);
  EXPECT_EQ(s.unreferenced_vertices, 2u);
  // 561 face shells (558 soup triangles, bodice, two skirt panels); the hem
  // stitch polyline joins the two panels; the five buttons stand alone.
  EXPECT_EQ(s.components, 565u);
  EXPECT_GT(s.boundary_loops, 0u);
}

TEST(SharedGarments, DressHasTwoShells) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "shared test data (../shared/data) not found";
  const TopologyStats s = topology_stats(read_garment_obj(data + "/garments/dress_on_A_female.obj"));
  EXPECT_EQ(s.vertices, 2205u);
  EXPECT_EQ(s.faces, 2096u);
  EXPECT_EQ(s.components, 2u);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  EXPECT_EQ(s.unreferenced_vertices, 0u);
}

TEST(SharedGarments, EveryGarmentRoundTripsByteIdentically) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "shared test data (../shared/data) not found";
  test::TempDir dir;
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(data + "/garments")) {
    if (e.path().extension() != ".obj") continue;
    SCOPED_TRACE(e.path().string());
    ++files;
    const Garment g = read_garment_obj(e.path().string());
    const std::string out = dir.file(e.path().filename().string());
    write_garment_obj(out, g);
    EXPECT_TRUE(test::read_text(out) == test::read_text(e.path().string())) << "not byte-identical";
    // Moved positions re-read exactly.
    Garment moved = g;
    moved.positions.col(1).array() += 1.0 / 3.0;
    const Garment back = parse_garment_obj(format_garment_obj(moved), "moved.obj");
    EXPECT_TRUE((back.positions.array() == moved.positions.array()).all());
    EXPECT_EQ(back.faces.indices, g.faces.indices);
  }
  EXPECT_EQ(files, 6u);
}

}  // namespace
}  // namespace refit
