// Face attributes of a garment OBJ read on demand (io/obj_attributes.hpp):
// corner texture coordinates (every index form, relative ones too) and the
// `o` / `g` group of every face.
#include <refit/io/obj_attributes.hpp>
#include <refit/core/error.hpp>
#include <refit/io/obj_garment.hpp>

#include "support/test_support.hpp"

#include <gtest/gtest.h>

namespace refit {
namespace {

TEST(ObjAttributes, TexcoordsAndGroupsPerFace) {
  const std::string obj =
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0.5 0.25 0\n"
      "f 1 2 3\n"                // before any group, no texture coordinates
      "o shirt\ng front # the front\nf 1/1 2/2 3/3/1\n"
      "g back\nf 1/-1 3/-2 4//1\n"
      "o pants\nf 2/4 3/4 4/4\n";
  const Garment g = parse_garment_obj(obj + "vn 0 0 1\n", "t.obj");
  const ObjFaceAttributes a = obj_face_attributes(g);
  ASSERT_EQ(a.texcoords.rows(), 4);
  EXPECT_EQ(a.texcoords(3, 0), 0.5);
  EXPECT_EQ(a.texcoords(3, 1), 0.25);
  const Index none = ObjFaceAttributes::kNoTexcoord;
  const std::vector<Index> corners = {none, none, none, 0, 1, 2, 3, 2, none, 3, 3, 3};
  EXPECT_EQ(a.corner_texcoords, corners);
  ASSERT_EQ(a.face_groups.size(), 4u);
  std::vector<std::string> names;
  for (Index f : a.face_groups) names.push_back(a.group_names[f]);
  EXPECT_EQ(names, (std::vector<std::string>{"", "shirt/front", "shirt/back", "pants"}));
}

TEST(ObjAttributes, SameAcrossChunksAndWithoutASource) {
  // Enough faces for several reader chunks: the groups carry over chunk boundaries.
  std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n";
  for (int i = 0; i < 40000; ++i) {
    if (i % 9000 == 0) obj += "g part" + std::to_string(i / 9000) + "\n";
    obj += "f 1/1 2/1 3/1\n";
  }
  const Garment g = parse_garment_obj(obj, "big.obj");
  const ObjFaceAttributes a = obj_face_attributes(g);
  ASSERT_EQ(a.face_groups.size(), 40000u);
  for (int i = 0; i < 40000; i += 997) EXPECT_EQ(a.group_names[a.face_groups[i]], "part" + std::to_string(i / 9000));
  Garment bare;
  bare.positions = g.positions;
  bare.faces = g.faces;
  const ObjFaceAttributes b = obj_face_attributes(bare);
  EXPECT_TRUE(b.corner_texcoords.empty());
  EXPECT_EQ(b.face_groups.size(), 40000u);
  // A source whose text was released (the resize command's) is read again from its file.
  test::TempDir dir;
  test::write_text(dir.file("big.obj"), obj);
  const Garment released = read_garment_obj(dir.file("big.obj"), SourceText::released);
  ASSERT_TRUE(released.source->released());
  const ObjFaceAttributes c = obj_face_attributes(released);
  EXPECT_EQ(c.face_groups, a.face_groups);
  EXPECT_EQ(c.group_names, a.group_names);
  EXPECT_EQ(c.corner_texcoords, a.corner_texcoords);
  test::write_text(dir.file("big.obj"), obj + "f 1 2 3\n");
  EXPECT_THROW(obj_face_attributes(released), Error) << "a file changed since it was read";
}

}  // namespace
}  // namespace refit
