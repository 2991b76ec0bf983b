// Garment OBJ reader and writer: every index form, the line-for-line round trip,
// bad input with file:line messages, atomic writes and thread-count independence.
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/obj_detail.hpp>
#include <refit/io/obj_garment.hpp>

#include "support/test_support.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace refit {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

std::vector<Index> all(const Csr& c) { return {c.indices.begin(), c.indices.end()}; }
std::vector<Index> offsets(const Csr& c) { return c.offsets; }

std::vector<std::string> split(const std::string& text, const std::string& sep) {
  std::vector<std::string> out;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t e = text.find(sep, pos);
    if (e == std::string::npos) {
      out.push_back(text.substr(pos));
      break;
    }
    out.push_back(text.substr(pos, e - pos));
    pos = e + sep.size();
  }
  return out;
}

TEST(ObjRead, EveryIndexForm) {
  const Garment g = parse_garment_obj(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nvn 0 0 -1\n"
      "f 1 2 3\n"
      "f 1/1 2/2 3/3\n"
      "f 1//1 2//2 3//1\n"
      "f 1/1/1 2/2/2 3/3/1 4/1/2\n"
      "f -4 -3 -2\n"
      "f -1/-1/-1 -2/-2/-2 -3//-1\n"
      "v 2 2 2\n"
      "f -1 1 +2\n"
      "l 1 2 5\nl 1/1 2/2\np 3\np 4 -1\n",
      "forms.obj");
  EXPECT_EQ(g.vertex_count(), 5u);
  EXPECT_EQ(g.faces.rows(), 7u);
  EXPECT_EQ(offsets(g.faces), (std::vector<Index>{0, 3, 6, 9, 13, 16, 19, 22}));
  EXPECT_EQ(all(g.faces),
            (std::vector<Index>{0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 3, 0, 1, 2, 3, 2, 1, 4, 0, 1}));
  EXPECT_EQ(offsets(g.lines), (std::vector<Index>{0, 3, 5}));
  EXPECT_EQ(all(g.lines), (std::vector<Index>{0, 1, 4, 0, 1}));
  EXPECT_EQ(offsets(g.points), (std::vector<Index>{0, 1, 3}));
  EXPECT_EQ(all(g.points), (std::vector<Index>{2, 3, 4}));
  EXPECT_EQ(g.positions(4, 0), 2.0);
  ASSERT_TRUE(g.source);
  EXPECT_EQ(g.source->texcoords, 3u);
  EXPECT_EQ(g.source->normals.rows(), 2);
  EXPECT_EQ(g.source->corner_normals,
            (std::vector<Index>{ObjSource::kNoNormal, ObjSource::kNoNormal, ObjSource::kNoNormal,
                                ObjSource::kNoNormal, ObjSource::kNoNormal, ObjSource::kNoNormal, 0, 1, 0, 0, 1,
                                0, 1, ObjSource::kNoNormal, ObjSource::kNoNormal, ObjSource::kNoNormal, 1, 0, 1,
                                ObjSource::kNoNormal, ObjSource::kNoNormal, ObjSource::kNoNormal}));
}

TEST(ObjRead, ManyUnknownStatementsGiveFewWarnings) {
  std::string text = "v 0 0 0\n";
  for (int i = 0; i < 100; ++i) text += "vp 0.5\n";
  const Garment g = parse_garment_obj(text, "many.obj");
  ASSERT_EQ(g.source->warnings.size(), 21u);
  EXPECT_EQ(g.source->warnings[0], "many.obj:2: unknown statement 'vp' kept verbatim");
  EXPECT_EQ(g.source->warnings[20], "many.obj: 80 more unknown statements kept verbatim");
  EXPECT_EQ(format_garment_obj(g), text);
}

TEST(ObjRead, LargeFacesTabsTrailingCommentsUnknownStatements) {
  const Garment g = parse_garment_obj(
      "v\t0 0 0\n  v 1 0 0 # a comment\nv 1 1 0\nv 0.5 1.5 0\nv 0 1 0\n"
      "f 1 2 3 4 5   # pentagon\nf 1 2 2\ncurv 0 1 1 2\n",
      "big.obj");
  EXPECT_EQ(g.faces.row_size(0), 5u);
  EXPECT_EQ(g.faces.rows(), 2u);  // the degenerate face with a repeated vertex is kept
  ASSERT_EQ(g.source->warnings.size(), 1u);
  EXPECT_THAT(g.source->warnings[0], HasSubstr("big.obj:8: unknown statement 'curv'"));
}

// A file with every kind of element a CAD tool writes, CRLF line endings.
std::string rich_obj() {
  const char* lines[] = {"# rich test garment",
                         "mtllib cloth.mtl",
                         "o shirt",
                         "v 0 0 0 1 0 0",
                         "v 1 0 0 0 1 0",
                         "v 1 1 0 0 0 1",
                         "v 0 1 0 0.5 0.5 0.5",
                         "v 5 5 5",
                         "v 2.0 0.0 0.0",
                         "v 3 0 0",
                         "vt 0 0",
                         "vt 1 0",
                         "vt 1 1",
                         "vt 0 1",
                         "vn 0 0 1",
                         "vn 0.0 0.0 1.0",
                         "vn 1 0 0",
                         "g front",
                         "usemtl cloth",
                         "s 1",
                         "f 1/1/1 2/2/1 3/3/2",
                         "f 1/1/1 3/3/2 4/4/1",
                         "s off",
                         "l 2 6",
                         "p 7",
                         "# end"};
  std::string text;
  for (const char* l : lines) text += std::string(l) + "\r\n";
  return text;
}

TEST(ObjWrite, RoundTripChangesOnlyVertexAndNormalLines) {
  test::TempDir dir;
  const std::string in = dir.file("rich.obj"), out = dir.file("moved.obj");
  test::write_text(in, rich_obj());
  Garment g = read_garment_obj(in);
  ASSERT_EQ(g.vertex_count(), 7u);
  EXPECT_TRUE(g.source->crlf);
  // Moved positions: rotate the z = 0 quad into the plane y = 0.3, with
  // coordinates that need all 17 digits.
  Points moved(7, 3);
  for (Eigen::Index i = 0; i < 7; ++i) {
    const double x = g.positions(i, 0), y = g.positions(i, 1), z = g.positions(i, 2);
    moved.row(i) << x / 3.0 + 0.1, z + 0.3, y * std::sqrt(2.0);
  }
  g.positions = moved;
  const ObjWriteReport report = write_garment_obj(out, g);
  EXPECT_EQ(report.normals_recomputed, 2u);  // normal 3 is used by no face

  const std::string before = rich_obj(), after = test::read_text(out);
  const auto a = split(before, "\r\n"), b = split(after, "\r\n");
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].rfind("v ", 0) == 0 || a[i].rfind("vn ", 0) == 0) {
      EXPECT_EQ(a[i].substr(0, 2), b[i].substr(0, 2));
      continue;
    }
    EXPECT_EQ(a[i], b[i]) << "line " << i + 1 << " changed";
  }
  EXPECT_EQ(split(after, "\n").size(), a.size()) << "no bare LF line endings";
  // Colours and the unused normal kept.
  EXPECT_THAT(b[3], ::testing::EndsWith(" 1 0 0"));
  EXPECT_THAT(b[6], ::testing::EndsWith(" 0.5 0.5 0.5"));
  EXPECT_EQ(b[16], "vn 1 0 0");

  const Garment r = read_garment_obj(out);
  EXPECT_TRUE((r.positions.array() == moved.array()).all()) << "re-read positions are not exact";
  EXPECT_EQ(all(r.faces), all(g.faces));
  EXPECT_EQ(all(r.lines), all(g.lines));
  EXPECT_EQ(all(r.points), all(g.points));
  // The recomputed normals: unit, along the face normal of the moved quad.
  const Vec3 face_n = (row3(moved, 1) - row3(moved, 0)).cross(row3(moved, 2) - row3(moved, 0)).normalized();
  for (Eigen::Index k = 0; k < 2; ++k) {
    const Vec3 n = r.source->normals.row(k).transpose();
    EXPECT_NEAR(n.norm(), 1.0, 1e-15);
    EXPECT_NEAR(n.dot(face_n), 1.0, 1e-15);
  }
  EXPECT_EQ(r.source->normals(2, 0), 1.0);
}

TEST(ObjWrite, OtherPositionsWriteLikeACopyWithThemAndCheckTheirCount) {
  // A resize result is written with the original garment's elements and source
  // (no copy of the garment): the same bytes as a copy given those positions.
  test::TempDir dir;
  const Garment g = parse_garment_obj(rich_obj(), "rich.obj");
  Points moved = g.positions;
  moved.col(1).array() += 0.25;
  Garment copy = g;
  copy.positions = moved;
  const std::string a = dir.file("a.obj"), b = dir.file("b.obj");
  const ObjWriteReport ra = write_garment_obj(a, copy), rb = write_garment_obj(b, g, moved);
  EXPECT_EQ(test::read_text(a), test::read_text(b));
  EXPECT_EQ(ra.normals_recomputed, rb.normals_recomputed);
  try {
    write_garment_obj(dir.file("c.obj"), g, Points(moved.topRows(3)));
    FAIL() << "no error for 3 positions";
  } catch (const Error& e) {
    EXPECT_THAT(std::string(e.what()), ::testing::HasSubstr("c.obj"));
    EXPECT_THAT(std::string(e.what()), ::testing::HasSubstr("3 positions"));
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("c.obj")));
}

TEST(ObjWrite, UnchangedGarmentIsByteIdentical) {
  const std::string text = rich_obj() + "v 1.50 -0.0 1e2\n";
  const Garment g = parse_garment_obj(text, "same.obj");
  ObjWriteReport report;
  EXPECT_EQ(format_garment_obj(g, &report), text);
  EXPECT_EQ(report.normals_recomputed, 0u);
}

TEST(ObjWrite, PlainGarmentRoundTripsExactly) {
  Garment g;
  g.positions.resize(5, 3);
  g.positions << 0.1, 1.0 / 3.0, -0.0, 1e-300, 2.5e300, 7, 1, 2, 3, 4, 5, 6, std::nextafter(1.0, 2.0), -1e-7, 0;
  g.faces.push_row(std::vector<Index>{0, 1, 2, 3});
  g.lines.push_row(std::vector<Index>{3, 4});
  g.points.push_row(std::vector<Index>{4});
  test::TempDir dir;
  const std::string path = dir.file("plain.obj");
  write_garment_obj(path, g);
  const Garment r = read_garment_obj(path);
  ASSERT_EQ(r.vertex_count(), 5u);
  for (Eigen::Index i = 0; i < 5; ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(std::signbit(r.positions(i, k)), std::signbit(g.positions(i, k)));
  EXPECT_TRUE((r.positions.array() == g.positions.array()).all());
  EXPECT_EQ(all(r.faces), all(g.faces));
  EXPECT_EQ(all(r.lines), all(g.lines));
  EXPECT_EQ(all(r.points), all(g.points));
  EXPECT_EQ(test::read_text(path).substr(0, 6), "v 0.1 ");
}

struct BadCase {
  const char* text;
  std::size_t line;  // 0: no line in the message
  const char* problem;
};

TEST(ObjRead, BadInputNamesFileLineAndProblem) {
  const BadCase cases[] = {
      {"v 0 0 0\nv 1 2 abc\n", 2, "malformed number 'abc'"},
      {"v 0 0 0\nv 1 2\n", 2, "needs 3 coordinates"},
      {"v 0 0 0\nv 1 2 3 4 5 6 7 8\n", 2, "too many numbers"},
      {"# c\nv nan 0 0\n", 2, "non-finite"},
      {"v 0 inf 0\n", 1, "non-finite"},
      {"v 0 0 1e999\n", 1, "out of range"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", 4, "vertex index 9 out of range"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", 4, "index 0 is invalid"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 -5 2\n", 4, "relative vertex index -5 out of range"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 -9223372036854775808 2\n", 4, "relative vertex index -9223372036854775808"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/4 2 3\n", 4, "texture coordinate index 4 out of range"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//2 2 3\n", 5, "normal index 2 out of range"},
      {"v 0 0 0\nv 1 0 0\nf 1 2\n", 3, "face with 2 vertices"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/x 2 3\n", 4, "malformed index '1/x'"},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/ 2 3\n", 4, "malformed index"},
      {"v 0 0 0\nv 1 0 0\nl 1\n", 3, "'l' with 1 vertices"},
      {"v 0 0 0\nv 1 0 0\nl 1//1 2\n", 3, "malformed index"},
      {"v 0 0 0\np\n", 2, "'p' with no vertex"},
      {"v 0 0 0\r\nvn 0 0\r\n", 2, "'vn' needs 3 numbers"},
      {"v 0 0 0\nvt\n", 2, "'vt' needs 1 to 3 numbers"},
      {"# only a comment\ng empty\n", 0, "empty garment"},
      {"", 0, "empty garment"},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      parse_garment_obj(c.text, "bad.obj");
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      const std::string msg = e.what();
      if (c.line > 0)
        EXPECT_THAT(msg, StartsWith("bad.obj:" + std::to_string(c.line) + ": "));
      else
        EXPECT_THAT(msg, StartsWith("bad.obj: "));
      EXPECT_THAT(msg, HasSubstr(c.problem));
      EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line";
    }
  }
}

TEST(ObjRead, MissingFileAndFolderAreErrors) {
  test::TempDir dir;
  const std::string missing = dir.file("nope.obj");
  try {
    read_garment_obj(missing);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), StartsWith(missing + ": cannot open"));
  }
  try {
    read_garment_obj(dir.path().string());
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("not a regular file"));
  }
}

TEST(ObjWrite, FailedFormatLeavesNoFile) {
  test::TempDir dir;
  const std::string path = dir.file("out.obj");
  Garment g = parse_garment_obj(rich_obj(), "rich.obj");
  g.positions(2, 1) = std::numeric_limits<double>::quiet_NaN();
  try {
    write_garment_obj(path, g);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), StartsWith(path + ": vertex 3 has a non-finite coordinate"));
  }
  EXPECT_EQ(test::folder_entries(dir.path()), 0u) << "no file and no temporary file";

  // A garment that no longer matches its source text.
  Garment h = parse_garment_obj(rich_obj(), "rich.obj");
  h.positions.conservativeResize(6, 3);
  EXPECT_THROW(write_garment_obj(path, h), Error);
  EXPECT_EQ(test::folder_entries(dir.path()), 0u);

  // An existing file is left as it was.
  test::write_text(path, "old");
  EXPECT_THROW(write_garment_obj(path, g), Error);
  EXPECT_EQ(test::read_text(path), "old");
  EXPECT_EQ(test::folder_entries(dir.path()), 1u);
}

// A text spanning several parse chunks, with relative indices crossing chunk
// boundaries: a strip of triangles each written right after its last vertex.
std::string strip_obj(std::size_t n, bool relative, std::size_t bad_line = 0) {
  std::ostringstream s;
  std::size_t line = 0;
  for (std::size_t i = 0; i < n; ++i) {
    ++line;
    if (line == bad_line) s << "v 1 2 x\n";
    else s << "v " << i * 0.001 << ' ' << (i % 2) * 0.5 << ' ' << std::sin(double(i)) << " 0.25 0.5 0.75\n";
    if (i >= 2) {
      ++line;
      if (relative) s << "f -3 -2 -1\n";
      else s << "f " << i - 1 << ' ' << i << ' ' << i + 1 << '\n';
    }
  }
  return s.str();
}

TEST(ObjRead, ChunkedParseIsIndependentOfThreads) {
  const std::string rel = strip_obj(20000, true), absolute = strip_obj(20000, false);
  ASSERT_GT(rel.size(), 3u * (1u << 18)) << "the text must span several chunks";
  Garment one, two;
  {
    ThreadLimit limit(1);
    one = parse_garment_obj(rel, "strip.obj");
  }
  {
    ThreadLimit limit(2);
    two = parse_garment_obj(rel, "strip.obj");
  }
  const Garment ref = parse_garment_obj(absolute, "strip.obj");
  EXPECT_EQ(one.vertex_count(), 20000u);
  EXPECT_TRUE((one.positions.array() == two.positions.array()).all());
  EXPECT_TRUE((one.positions.array() == ref.positions.array()).all());
  EXPECT_EQ(all(one.faces), all(ref.faces));
  EXPECT_EQ(all(two.faces), all(ref.faces));
  EXPECT_EQ(offsets(one.faces), offsets(ref.faces));

  // Formatting moved positions: the same bytes for any thread count.
  one.positions.array() += 0.125;
  std::string f1, f2;
  {
    ThreadLimit limit(1);
    f1 = format_garment_obj(one);
  }
  {
    ThreadLimit limit(2);
    f2 = format_garment_obj(one);
  }
  EXPECT_EQ(f1, f2);
  const Garment back = parse_garment_obj(f1, "back.obj");
  EXPECT_TRUE((back.positions.array() == one.positions.array()).all());
  EXPECT_EQ(format_garment_obj(ref), absolute);
}

TEST(ObjRead, AFileOfSeveralReadRangesIsReadByteForByte) {
  // read_garment_obj reads 8 MB ranges on several threads: a 20 MB file spans three.
  std::string text = "# big\n";
  for (int i = 0; text.size() < (std::size_t(20) << 20); ++i) text += "v " + std::to_string(i) + " 0.5 -1.25\n";
  text += "p 1 2 3\n";
  test::TempDir dir;
  const std::string path = dir.file("big.obj");
  test::write_text(path, text);
  const Garment parsed = parse_garment_obj(text, "big.obj");
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    const Garment g = read_garment_obj(path);
    ASSERT_TRUE(g.source);
    EXPECT_TRUE(g.source->text.view() == text) << threads;
    EXPECT_TRUE((g.positions.array() == parsed.positions.array()).all()) << threads;
    EXPECT_EQ(write_garment_obj(dir.file("back.obj"), g).warnings.size(), 0u);
    EXPECT_TRUE(test::read_text(dir.file("back.obj")) == text) << threads;
  }
}

TEST(ObjWrite, AReleasedSourceWritesTheSameBytesReadAgainFromItsFile) {
  // The resize command drops the file's text after parsing and reads each chunk
  // again when it writes: the bytes of a kept source, on a file of many chunks
  // with CRLF lines, normals and colours, and moved positions.
  std::string text = rich_obj();
  for (int i = 0; text.size() < 3u * (1u << 18); ++i)
    text += "v " + std::to_string(i) + " 0.5 -1.25 0.1 0.2 0.3\r\nvn 0 0 1\r\nf -1//-1 -2//-1 -3//-1\r\n";
  test::TempDir dir;
  const std::string in = dir.file("in.obj");
  test::write_text(in, text);
  const Garment kept = read_garment_obj(in);
  const Garment released = read_garment_obj(in, SourceText::released);
  ASSERT_TRUE(released.source->released());
  EXPECT_EQ(released.source->text.size(), 0u);
  EXPECT_GT(released.source->chunk_begin.size(), 3u) << "the text must span several chunks";
  EXPECT_TRUE((released.positions.array() == kept.positions.array()).all());
  Points moved = kept.positions;
  moved.col(1).array() += 0.375;
  moved.col(2) *= std::sqrt(2.0);
  for (int threads : {1, 2}) {
    ThreadLimit limit(threads);
    const std::string a = dir.file("kept.obj"), b = dir.file("released.obj");
    const ObjWriteReport ra = write_garment_obj(a, kept, moved), rb = write_garment_obj(b, released, moved);
    EXPECT_TRUE(test::read_text(a) == test::read_text(b)) << threads;
    EXPECT_EQ(ra.normals_recomputed, rb.normals_recomputed);
    write_garment_obj(b, released);  // unmoved: the file itself, byte for byte
    EXPECT_TRUE(test::read_text(b) == text) << threads;
  }
}

TEST(ObjWrite, AReleasedSourceWhoseFileChangedIsNotWritten) {
  const std::string text = strip_obj(20000, true);
  test::TempDir dir;
  const std::string in = dir.file("in.obj"), out = dir.file("out.obj");
  test::write_text(in, text);
  const Garment g = read_garment_obj(in, SourceText::released);
  Points moved = g.positions;
  moved.array() += 0.5;
  const auto expect_refused = [&](const std::string& changed) {
    test::write_text(in, changed);
    try {
      write_garment_obj(out, g, moved);
      ADD_FAILURE() << "no error for a changed source";
    } catch (const Error& e) {
      EXPECT_THAT(std::string(e.what()), StartsWith(in + ": "));
      EXPECT_THAT(std::string(e.what()), HasSubstr("changed"));
    }
    EXPECT_FALSE(std::filesystem::exists(out));
    EXPECT_EQ(test::folder_entries(dir.path()), 1u) << "no temporary file left";
  };
  std::string same_size = text;
  same_size[same_size.size() / 2 + 7] = same_size[same_size.size() / 2 + 7] == '1' ? '2' : '1';  // a digit, late
  expect_refused(same_size);
  expect_refused(text + "v 1 2 3\n");  // longer
  test::write_text(in, text);
  write_garment_obj(out, g, moved);  // the file as it was read again: written
  const Garment kept = read_garment_obj(in);
  write_garment_obj(dir.file("kept.obj"), kept, moved);
  EXPECT_TRUE(test::read_text(out) == test::read_text(dir.file("kept.obj")));
}

TEST(ObjRead, ErrorLineIsRightInALaterChunk) {
  const std::string text = strip_obj(12000, true, 20001);
  try {
    parse_garment_obj(text, "late.obj");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), StartsWith("late.obj:20001: malformed number 'x'"));
  }
}

TEST(ObjRead, AParseNeverWritesPastTheVerticesCounted) {
  // The counting pass saw one `v` line; the text parsed has two (the file
  // changed between the passes): an error, not a write past the sink's row.
  using namespace obj_detail;
  const std::string counted = "v 1 2 3\nf 1 1 1\n", parsed = "v 1 2 3\nv 4 5 6\n";
  Chunk chunk;
  count_chunk(counted, 0, counted.size(), chunk);
  ASSERT_EQ(chunk.nv, 1u);
  Points positions(1, 3), normals(0, 3);
  std::vector<ObjSource::Span> vspans(1), nspans;
  const Sink sink{positions, normals, vspans, nspans};
  parse_chunk(parsed, 0, parsed.size(), chunk, sink, {}, {1, 0, 0});
  ASSERT_TRUE(chunk.failure);
  EXPECT_EQ(chunk.failure->line, 2u);
  EXPECT_THAT(chunk.failure->message, HasSubstr("changed"));
  EXPECT_EQ(positions(0, 2), 3.0);
}

}  // namespace
}  // namespace refit
