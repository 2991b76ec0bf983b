// The streamed OBJ reader and writer (issue 14, out-of-core chunking): the same
// elements, errors and warnings as the in-memory reader, and byte for byte the
// in-memory writer's output, whatever the group size.
#include <refit/core/error.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/io/obj_stream.hpp>

#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace refit {
namespace {

// A grid garment as OBJ text with every kind of statement, about `rows` x 100
// vertices: v (some with colours), vt, vn, faces in every index form (some
// relative), l and p elements, groups, comments, unknown statements.
std::string grid_obj(int rows, bool crlf, bool normals) {
  const std::string nl = crlf ? "\r\n" : "\n";
  std::string t = "# a grid" + nl + "mtllib grid.mtl" + nl + "o grid" + nl;
  const int cols = 100;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      t += "v " + std::to_string(c * 0.5) + " " + std::to_string(r * 0.25 + 1e-3 * c) + " " + std::to_string(0.01 * (r % 7)) +
           ((c % 11 == 0) ? " 0.5 0.5 0.5" : "") + nl;
      t += "vt " + std::to_string(c / 100.0) + " " + std::to_string(r / double(rows)) + nl;
      if (normals) t += "vn 0 0 1" + nl;
    }
  t += "g panel" + nl + "usemtl cloth" + nl + "curv 1 2" + nl;
  for (int r = 0; r + 1 < rows; ++r)
    for (int c = 0; c + 1 < cols; ++c) {
      const int a = r * cols + c + 1, b = a + 1, d = a + cols, e = d + 1;
      if (normals && (r + c) % 3 == 0)
        t += "f " + std::to_string(a) + "/" + std::to_string(a) + "/" + std::to_string(a) + " " + std::to_string(b) + "//" +
             std::to_string(b) + " " + std::to_string(e) + "/" + std::to_string(e) + "/" + std::to_string(e) + nl;
      else if ((r + c) % 3 == 1)
        t += "f " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(e) + " " + std::to_string(d) + "  # quad" + nl;
      else
        t += "f " + std::to_string(a) + "/" + std::to_string(a) + " " + std::to_string(e) + "/" + std::to_string(e) + " " +
             std::to_string(d) + "/" + std::to_string(d) + nl;
      if (c == 50 && r % 10 == 0) t += "surf 0 1" + nl + "l " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(e) + nl;
    }
  t += "p 1 2 3" + nl + "v 1 2 3" + nl + "f -1 1 2" + nl + "l -1 1" + nl;
  return t;
}

struct Streamed {
  Points positions;
  Csr faces, lines, points;
  std::vector<Index> corner_normals;
  std::vector<std::string> warnings;
};

void append_csr(Csr& to, const Csr& rows) {
  for (std::size_t r = 0; r < rows.rows(); ++r) to.push_row(rows.row(r));
}

Streamed read_streamed(const std::string& path, std::size_t group_bytes) {
  const ObjStream s(path, group_bytes);
  Streamed out;
  out.positions.resize(Eigen::Index(s.vertex_count()), 3);
  std::size_t faces = 0, groups = 0;
  out.warnings = s.read([&](ObjGroup& g) {
    ++groups;
    EXPECT_EQ(g.first_face, out.faces.rows());
    out.positions.middleRows(Eigen::Index(g.first_vertex), g.positions.rows()) = g.positions;
    if (!g.corner_normals.empty()) {
      out.corner_normals.resize(out.faces.indices.size(), ObjSource::kNoNormal);
      out.corner_normals.insert(out.corner_normals.end(), g.corner_normals.begin(), g.corner_normals.end());
    }
    append_csr(out.faces, g.faces);
    append_csr(out.lines, g.lines);
    append_csr(out.points, g.points);
    faces += g.faces.rows();
  });
  if (!out.corner_normals.empty()) out.corner_normals.resize(out.faces.indices.size(), ObjSource::kNoNormal);
  EXPECT_EQ(faces, s.face_count());
  return out;
}

void expect_same_csr(const Csr& a, const Csr& b) {
  EXPECT_EQ(a.offsets, b.offsets);
  EXPECT_TRUE(std::equal(a.indices.begin(), a.indices.end(), b.indices.begin(), b.indices.end()));
}

TEST(ObjStream, ReadsWhatTheInMemoryReaderReadsInAnyGroupSize) {
  test::TempDir dir;
  for (const bool crlf : {false, true}) {
    const std::string path = dir.file(crlf ? "crlf.obj" : "grid.obj");
    test::write_text(path, grid_obj(120, crlf, true));  // about 1.3 MB: several 256 kB chunks
    const Garment g = read_garment_obj(path);
    for (const std::size_t group : {std::size_t(1), std::size_t(600000), std::size_t(64) << 20}) {
      SCOPED_TRACE("group bytes " + std::to_string(group));
      const Streamed s = read_streamed(path, group);
      EXPECT_TRUE((s.positions.array() == g.positions.array()).all());
      expect_same_csr(s.faces, g.faces);
      expect_same_csr(s.lines, g.lines);
      expect_same_csr(s.points, g.points);
      EXPECT_EQ(s.corner_normals, g.source->corner_normals);
      EXPECT_EQ(s.warnings, g.source->warnings);
      EXPECT_FALSE(s.warnings.empty());
    }
    const ObjStream s(path, 1);
    EXPECT_EQ(s.crlf(), g.source->crlf);
    EXPECT_EQ(s.vertex_count(), g.vertex_count());
    EXPECT_EQ(s.normal_count(), std::size_t(g.source->normals.rows()));
    EXPECT_EQ(s.texcoord_count(), g.source->texcoords);
  }
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(ObjStream, GivesTheInMemoryReadersErrors) {
  test::TempDir dir;
  const std::string good = grid_obj(60, false, false);
  const std::vector<std::string> bad = {
      good + "f 1 2 999999\n",                       // index out of range, in the last chunk
      "v 1 2 nan\n" + good,                          // non-finite coordinate in the first
      good.substr(0, good.size() / 2) + "\nf 1 2\n" + good.substr(good.size() / 2),  // a face of 2 in the middle
      good + "f -999999 1 2\n",                      // relative index out of range
      "# nothing\nvt 0 0\n",                         // no vertices
      "v 1 2 3\nl 1\n",                              // a line of one vertex
  };
  for (std::size_t i = 0; i < bad.size(); ++i) {
    const std::string path = dir.file("bad" + std::to_string(i) + ".obj");
    test::write_text(path, bad[i]);
    const std::string expected = error_of([&] { read_garment_obj(path); });
    ASSERT_NE(expected, "no error") << i;
    for (const std::size_t group : {std::size_t(1), std::size_t(64) << 20})
      EXPECT_EQ(error_of([&] { read_streamed(path, group); }), expected) << i;
  }
}

// Every third vertex moved (the rest keep their bits, so their text stays).
Points moved_positions(const Points& p) {
  Points x = p;
  for (Eigen::Index i = 0; i < x.rows(); i += 3) x.row(i) += Eigen::RowVector3d(0.1, -0.2, 1.0 / 3.0);
  return x;
}

TEST(ObjStream, WritesWhatTheInMemoryWriterWrites) {
  test::TempDir dir;
  for (const bool crlf : {false, true}) {
    const std::string path = dir.file("in.obj");
    test::write_text(path, grid_obj(120, crlf, false));
    const Garment g = read_garment_obj(path);
    for (const bool move : {false, true}) {
      const Points x = move ? moved_positions(g.positions) : g.positions;
      write_garment_obj(dir.file("memory.obj"), g, x);
      const ObjStream s(path, 600000);
      ObjEdits edits;
      edits.positions = [&](std::size_t first, std::size_t count, Points& out) {
        out = x.middleRows(Eigen::Index(first), Eigen::Index(count));
      };
      s.write(dir.file("streamed.obj"), edits);
      const std::string expected = test::read_text(dir.file("memory.obj"));
      EXPECT_EQ(test::read_text(dir.file("streamed.obj")), expected) << "crlf " << crlf << " moved " << move;
      if (!move) {
        EXPECT_EQ(expected, test::read_text(path));
      }
    }
  }
}

TEST(ObjStream, WritesRecomputedNormalsWhereTheyAreGiven) {
  test::TempDir dir;
  const std::string path = dir.file("in.obj");
  test::write_text(path, "v 0 0 0\nv 1 0 0\nvn 0 0 1\nv 0 1 0\nvn 1 0 0\nf 1//1 2//2 3//1\n");
  const ObjStream s(path);
  ObjEdits edits;
  edits.positions = [](std::size_t first, std::size_t count, Points& out) {
    out.resize(Eigen::Index(count), 3);
    for (std::size_t i = 0; i < count; ++i) out.row(Eigen::Index(i)) = Eigen::RowVector3d(double(first + i), 0.5, 2.0);
  };
  edits.normals = [](std::size_t first, std::size_t count, Points& out, std::vector<std::uint8_t>& recomputed) {
    recomputed.assign(count, 0);
    for (std::size_t i = 0; i < count; ++i) {
      out.row(Eigen::Index(i)) = Eigen::RowVector3d(0.0, 0.0, -1.0);
      recomputed[i] = first + i == 1;  // the second normal only
    }
  };
  s.write(dir.file("out.obj"), edits);
  EXPECT_EQ(test::read_text(dir.file("out.obj")), "v 0 0.5 2\nv 1 0.5 2\nvn 0 0 1\nv 2 0.5 2\nvn 0 0 -1\nf 1//1 2//2 3//1\n");
}

}  // namespace
}  // namespace refit
