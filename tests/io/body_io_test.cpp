// Body meshes: OBJ through the engine's parser, OFF/PLY/STL through mesh_formats,
// the same fan split for every format, validation and the OBJ writer.
#include <refit/core/error.hpp>
#include <refit/io/body_io.hpp>

#include "support/test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <limits>

namespace refit {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;
using Tri = std::array<Index, 3>;

// A square and a pentagon sharing the edge 1-2 (vertices 0..6).
const char* kObj =
    "# body\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2.5 0.5 0\nv 2 1 0\n"
    "vt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1 4/1/1\nf 2 5 6 7 3\n";
const char* kOff =
    "OFF\n7 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2.5 0.5 0\n2 1 0\n4 0 1 2 3\n5 1 4 5 6 2\n";
const char* kPly =
    "ply\nformat ascii 1.0\nelement vertex 7\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2.5 0.5 0\n2 1 0\n4 0 1 2 3\n5 1 4 5 6 2\n";
const std::vector<Tri> kTriangles = {{0, 1, 2}, {0, 2, 3}, {1, 4, 5}, {1, 5, 6}, {1, 6, 2}};

TEST(BodyIo, SameTrianglesFromObjOffAndPly) {
  test::TempDir dir;
  for (const auto& [name, text] : {std::pair{"square.obj", kObj}, {"square.off", kOff}, {"square.PLY", kPly}}) {
    SCOPED_TRACE(name);
    const std::string path = dir.file(name);
    test::write_text(path, text);
    const BodyMesh b = read_body(path);
    EXPECT_EQ(b.name, "square");
    EXPECT_EQ(b.path, path);
    ASSERT_EQ(b.vertices.rows(), 7);
    EXPECT_EQ(b.vertices(5, 0), 2.5);
    EXPECT_EQ(b.vertices(5, 1), 0.5);
    EXPECT_EQ(b.triangles, kTriangles);
  }
}

// Binary PLY, little- and big-endian, with an extra property and element to skip.
TEST(BodyIo, BinaryPly) {
  test::TempDir dir;
  for (const bool big : {false, true}) {
    SCOPED_TRACE(big ? "big-endian" : "little-endian");
    std::string bytes = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                        " 1.0\ncomment made by a test\nelement vertex 4\nproperty double x\nproperty double y\n"
                        "property double z\nproperty uchar red\nelement face 2\nproperty list uchar int vertex_indices\n"
                        "element edge 1\nproperty int a\nend_header\n";
    auto put = [&](const void* p, std::size_t n) {
      std::string b(static_cast<const char*>(p), n);
      if (big) std::reverse(b.begin(), b.end());
      bytes += b;
    };
    const double xyz[4][3] = {{0, 0, 0}, {1.5, 0, 0}, {1, 1, 0}, {0, 1, 0.25}};
    for (const auto& v : xyz) {
      for (double c : v) put(&c, 8);
      const unsigned char red = 200;
      put(&red, 1);
    }
    const std::int32_t faces[2][3] = {{0, 1, 2}, {0, 2, 3}};
    for (const auto& f : faces) {
      const unsigned char n = 3;
      put(&n, 1);
      for (std::int32_t i : f) put(&i, 4);
    }
    const std::int32_t edge = 7;
    put(&edge, 4);
    const std::string path = dir.file(big ? "be.ply" : "le.ply");
    test::write_text(path, bytes);
    const BodyMesh b = read_body(path);
    ASSERT_EQ(b.vertices.rows(), 4);
    EXPECT_EQ(b.vertices(1, 0), 1.5);
    EXPECT_EQ(b.vertices(3, 2), 0.25);
    EXPECT_EQ(b.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
  }
}

TEST(BodyIo, AsciiStl) {
  test::TempDir dir;
  const std::string path = dir.file("tri.stl");
  test::write_text(path,
                   "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
                   "endfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\n"
                   "endfacet\nendsolid t\n");
  const BodyMesh b = read_body(path);
  EXPECT_EQ(b.vertices.rows(), 4);  // STL corners are merged
  ASSERT_EQ(b.triangles.size(), 2u);
  EXPECT_EQ(b.name, "tri");
}

TEST(BodyIo, WriteRoundTripsExactly) {
  test::TempDir dir;
  BodyMesh b;
  b.vertices.resize(4, 3);
  b.vertices << 0.1, 0.2, 0.3, 1.0 / 3.0, -0.0, 1e-12, 5, 6, 7, -1.25, 2.0 / 7.0, 8;
  b.triangles = {{0, 1, 2}, {0, 2, 3}};
  const std::string path = dir.file("out.obj");
  write_body_obj(path, b);
  const BodyMesh r = read_body(path);
  EXPECT_TRUE((r.vertices.array() == b.vertices.array()).all());
  EXPECT_EQ(r.triangles, b.triangles);
  EXPECT_EQ(r.name, "out");
}

TEST(BodyIo, BadBodiesNameTheFile) {
  test::TempDir dir;
  const auto expect_error = [&](const std::string& name, const std::string& text, const std::string& problem) {
    SCOPED_TRACE(name);
    const std::string path = dir.file(name);
    if (!text.empty()) test::write_text(path, text);
    try {
      read_body(path);
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_THAT(e.what(), StartsWith(path));
      EXPECT_THAT(e.what(), HasSubstr(problem));
    }
  };
  expect_error("points.obj", "v 0 0 0\nv 1 0 0\n", "no triangles");
  expect_error("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", ":4: vertex index 4 out of range");
  expect_error("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", ":2: non-finite");
  expect_error("missing.off", "", "cannot open");
  expect_error("garbage.ply", "this is not a ply file\n", "not a PLY file");
  // OpenMesh, used before, looped for ever on these (found by tests/fuzz).
  expect_error("endless.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend$header\n0\n",
               "the PLY header has no end_header");
  expect_error("garbled.ply", "ply\nformat ascii \xff\xff" "1.0\nelement vertex 1\nend_header\n", "unknown PLY format");
  expect_error("corners.off", "OFF\n4 4 0\n0 0 0\n1 1 0\n0 1 0\n0 0 1\n344444444444 2\n",
               "a face needs a corner count from 0 to 1000");
  expect_error("negative.off", "OFF\n-4\n", "the OFF header needs vertex, face and edge counts");
  expect_error("negative3.off", "OFF\n-4 1 0\n", "bad count in the OFF header");
  expect_error("unended.ply", "ply\nformat ascii 1.0\nelement vertex 1\n", "the PLY header has no end_header");
  expect_error("body.xyz", "1 2 3\n", "unknown body format");
  // Counts in a header that the file cannot hold are refused before anything is allocated.
  expect_error("huge.ply", "ply\nformat ascii 1.0\nelement vertex 99999999999\nproperty float x\nend_header\n",
               "declares 99999999999 vertices but only 0 bytes follow");
  expect_error("huge.off", "OFF\n99999999 1 0\n0 0 0\n", "declares 99999999 vertices");
  expect_error("faces.ply",
               "ply\nformat binary_little_endian 1.0\nelement vertex 0\nelement face 4000000000\n"
               "property list uchar int vertex_indices\nend_header\n",
               "declares 4000000000 faces");
  expect_error("bad.ply", "ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", "negative element count -3");
  std::string stl(80, ' ');
  stl += std::string("\xff\xff\xff\x0f", 4);
  expect_error("huge.stl", stl, "declares 268435455 triangles but the file has 84 bytes");

  BodyMesh b;
  b.vertices = Points::Zero(3, 3);
  b.vertices(1, 1) = std::numeric_limits<double>::infinity();
  b.triangles = {{0, 1, 2}};
  EXPECT_THROW(write_body_obj(dir.file("never.obj"), b), Error);
  EXPECT_FALSE(std::filesystem::exists(dir.file("never.obj")));
}

TEST(BodyIo, SharedDataBodiesShareTheirTriangles) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "shared test data (../shared/data) not found";
  const BodyMesh a = read_body(data + "/bodies/A_female.obj");
  const BodyMesh b = read_body(data + "/bodies/F_heavier.obj");
  EXPECT_EQ(a.vertices.rows(), 13380);
  EXPECT_EQ(a.triangles.size(), 26756u);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.name, "A_female");
  EXPECT_FALSE((a.vertices.array() == b.vertices.array()).all());
}

}  // namespace
}  // namespace refit
