// Cutting garments into panels (patterns/panels.hpp, seams.hpp, seam_paths.hpp):
// separate pieces, OBJ groups, UV seams, seam curves, non-manifold edges, turned
// faces, and the panels that cannot be flattened.
#include "patterns/pattern_fixtures.hpp"

#include <refit/core/error.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/io/obj_attributes.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/patterns/panels.hpp>
#include <refit/patterns/pattern.hpp>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>

namespace refit {
namespace {

using ::testing::HasSubstr;

PanelSet cut(const std::string& obj) {
  const Garment g = parse_garment_obj(obj, "t.obj");
  return cut_panels(g, obj_face_attributes(g));
}

TEST(Panels, OneGridIsOnePanel) {
  const PanelSet s = cut(test::grid_obj(4, 3));
  ASSERT_EQ(s.panels.size(), 1u);
  const Panel& p = s.panels[0];
  EXPECT_EQ(p.name, "piece-1");
  EXPECT_EQ(p.faces.size(), 12u);
  EXPECT_EQ(p.vertices.size(), 20u);
  EXPECT_EQ(p.triangles.size(), 24u);
  EXPECT_EQ(p.loops.size(), 1u);
  EXPECT_EQ(p.loops[0].size(), 14u);
  EXPECT_EQ(p.genus, 0);
  EXPECT_TRUE(p.problem.empty());
  EXPECT_TRUE(s.seams.empty());
}

TEST(Panels, GroupsCutAndTheSeamHasTwoSides) {
  // Left two columns in group "front", the rest in "back".
  std::string last;
  const PanelSet s = cut(test::grid_obj(4, 3, [&](int i, int) {
    const std::string g = i < 2 ? "front" : "back";
    if (g == last) return std::string();
    last = g;
    return "g " + g + "\n";
  }));
  ASSERT_EQ(s.panels.size(), 2u);
  // Every row switches group, so the names are per group, numbered only when needed.
  EXPECT_EQ(s.panels[0].name, "front");
  EXPECT_EQ(s.panels[1].name, "back");
  EXPECT_EQ(s.group_edges, 3u);
  ASSERT_EQ(s.seams.size(), 1u);
  const Seam& seam = s.seams[0];
  EXPECT_NE(seam.panel[0], seam.panel[1]);
  ASSERT_EQ(seam.garment_path.size(), 4u);
  for (std::size_t i = 0; i < seam.garment_path.size(); ++i)
    for (int side = 0; side < 2; ++side)
      EXPECT_EQ(s.panels[seam.panel[side]].vertices[seam.path[side][i]], seam.garment_path[i]);
}

TEST(Panels, UvSeamsCut) {
  const PanelSet s = cut(test::grid_obj(4, 3, [](int, int) { return std::string(); }, 3));
  ASSERT_EQ(s.panels.size(), 2u);
  EXPECT_EQ(s.uv_seam_edges, 3u);
  EXPECT_EQ(s.panels[0].faces.size() + s.panels[1].faces.size(), 12u);
}

TEST(Panels, SeparatePiecesAndNonManifoldEdges) {
  // Two triangles apart, then three faces on one edge.
  const PanelSet apart = cut("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf 1 2 3\nf 4 5 6\n");
  EXPECT_EQ(apart.panels.size(), 2u);
  const PanelSet fin = cut("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n");
  EXPECT_EQ(fin.non_manifold_edges, 1u);
  EXPECT_EQ(fin.panels.size(), 3u);
}

TEST(Panels, TurnedFacesAreWoundLikeTheirNeighbours) {
  // Three quads in a row, the middle one written the other way round.
  const PanelSet s = cut("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nv 3 0 0\nv 3 1 0\n"
                         "f 1 2 5 4\nf 2 5 6 3\nf 3 7 8 6\n");
  ASSERT_EQ(s.panels.size(), 1u);
  const Panel& p = s.panels[0];
  // Every interior edge is used once in each direction.
  std::map<std::pair<Index, Index>, int> directed;
  for (const Triangle& t : p.triangles)
    for (int i = 0; i < 3; ++i) ++directed[{t[i], t[(i + 1) % 3]}];
  for (const auto& [e, n] : directed) EXPECT_EQ(n, 1) << e.first << "-" << e.second;
  EXPECT_EQ(p.loops.size(), 1u);
}

TEST(Panels, ClosedAndNonOrientablePanelsSayWhy) {
  // A cube: closed.
  const PanelSet cube = cut("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                            "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  ASSERT_EQ(cube.panels.size(), 1u);
  EXPECT_THAT(cube.panels[0].problem, HasSubstr("closed"));
  // A Moebius band of four quads.
  std::string mobius;
  const int n = 4;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    for (int s = -1; s <= 1; s += 2) {
      const double w = 0.3 * s, t = a / 2;
      mobius += "v " + std::to_string((1 + w * std::cos(t)) * std::cos(a)) + " " +
                std::to_string((1 + w * std::cos(t)) * std::sin(a)) + " " + std::to_string(w * std::sin(t)) + "\n";
    }
  }
  for (int i = 0; i < n; ++i) {
    const int a = 2 * i + 1, b = a + 1, c = 2 * ((i + 1) % n) + 1, d = c + 1;
    // The last quad joins the band's ends with a half twist.
    mobius += i + 1 < n ? "f " + std::to_string(a) + " " + std::to_string(c) + " " + std::to_string(d) + " " + std::to_string(b) + "\n"
                        : "f " + std::to_string(a) + " " + std::to_string(d) + " " + std::to_string(c) + " " + std::to_string(b) + "\n";
  }
  const PanelSet band = cut(mobius);
  ASSERT_EQ(band.panels.size(), 1u);
  EXPECT_THAT(band.panels[0].problem, HasSubstr("not orientable"));
}

TEST(Panels, FlatteningAClosedPanelNamesIt) {
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                          "g box\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n"
                          "g flap\nv 3 0 0\nv 4 0 0\nv 3 1 0\nf 9 10 11\n";
  const Garment g = parse_garment_obj(obj, "box.obj");
  const PatternCut c = cut_pattern(g, {}, "box.obj");
  try {
    flatten_pattern(g, c, g.positions);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("box.obj: panel 'box' (6 faces) cannot be flattened: it is closed"));
  }
  PatternOptions skip;
  skip.skip_unflattenable = true;
  const Pattern p = flatten_pattern(g, c, g.positions, skip);
  EXPECT_FALSE(p.pieces[0].flattened);
  EXPECT_TRUE(p.pieces[1].flattened);
  ASSERT_FALSE(p.warnings.empty());
  EXPECT_THAT(p.warnings[0], HasSubstr("panel 'box'"));
}

// A panel of degenerate faces flattens to nothing a cutter can use: said, not silently drawn.
TEST(Panels, APanelWithNoAreaIsSaid) {
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 2 0 0\ng line\nf 1 2 3\n"
                          "g flap\nv 3 0 0\nv 4 0 0\nv 3 1 0\nf 4 5 6\n";
  const Garment g = parse_garment_obj(obj, "line.obj");
  const Pattern p = flatten_pattern(g, cut_pattern(g, {}, "line.obj"), g.positions);
  ASSERT_EQ(p.pieces.size(), 2u);
  ASSERT_EQ(p.warnings.size(), 1u);
  EXPECT_THAT(p.warnings[0], HasSubstr("panel 'line' has no area in 3D"));
}

TEST(Panels, SeamCurvesCutAlongTheNearestEdges) {
  // A 6 x 4 grid cut down the middle by a seam curve at x = 3.1 (between edges).
  const std::string obj = test::grid_obj(6, 4);
  const Garment g = parse_garment_obj(obj, "g.obj");
  const std::string features = R"({"features": [{"name": "middle", "role": "seam",
      "plane": {"point": [3.1, 0, 0], "normal": [1, 0, 0]},
      "curve": {"kind": "bspline", "degree": 1, "control_points": [[3.1, -0.2, 0], [3.1, 4.2, 0]]},
      "samples": 20}]})";
  const PatternCut c = cut_pattern(g, parse_feature_json(features, "f.json"), "g.obj", "f.json");
  ASSERT_EQ(c.seam_paths.size(), 1u);
  EXPECT_EQ(c.seam_paths[0].vertices.size(), 5u);  // the column x = 3, ends snapped to the border
  EXPECT_LT(c.seam_paths[0].deviation, 0.15);
  ASSERT_EQ(c.panels.panels.size(), 2u);
  EXPECT_EQ(c.panels.curve_edges, 4u);
  EXPECT_EQ(c.panels.panels[0].faces.size(), 12u);
  // The shape curves of the same file are not cuts.
  const std::string shape = R"({"features": [{"name": "middle",
      "plane": {"point": [3.1, 0, 0], "normal": [1, 0, 0]},
      "curve": {"kind": "bspline", "degree": 1, "control_points": [[3.1, -0.2, 0], [3.1, 4.2, 0]]},
      "samples": 20}]})";
  const PatternCut s = cut_pattern(g, parse_feature_json(shape, "f.json"), "g.obj", "f.json");
  EXPECT_EQ(s.panels.panels.size(), 1u);
  ASSERT_EQ(s.lines.size(), 1u);
  EXPECT_EQ(s.lines[0].samples.size(), 20u);
}

}  // namespace
}  // namespace refit
