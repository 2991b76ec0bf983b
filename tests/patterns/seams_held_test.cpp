// Which pieces flatten_pattern flattens a second time with their seams held
// (PatternOptions::seam_tolerance): only those with a seam whose two sides plain
// ARAP leaves apart; and a third time, held harder, where a seam is still apart
// (PatternOptions::seam_agreement). Three pieces in a row, left | middle |
// right, as OBJ groups of one grid: left and middle flat (plain ARAP keeps their
// lengths, so the seam between them agrees), the right one bumpy (its side of the
// middle | right seam comes out shorter or longer than the middle's).
#include "patterns/pattern_fixtures.hpp"

#include <refit/io/obj_garment.hpp>
#include <refit/patterns/pattern.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace refit {
namespace {

constexpr int kColumns = 12, kRows = 8;

Garment three_pieces() {
  std::string last;
  Garment g = parse_garment_obj(test::grid_obj(kColumns, kRows,
                                               [&](int i, int) {
                                                 const std::string group = i < 4 ? "left" : i < 8 ? "middle" : "right";
                                                 if (group == last) return std::string();
                                                 last = group;
                                                 return "g " + group + "\n";
                                               }),
                                "three.obj");
  // Bumps on the right piece, rising from 0 at its seam with the middle.
  for (int j = 0; j <= kRows; ++j)
    for (int i = 9; i <= kColumns; ++i)
      g.positions(test::grid_index(i, j, kColumns), 2) = 0.8 * std::sin(1.3 * i) * std::sin(0.9 * j + 0.4);
  return g;
}

std::size_t piece_named(const PatternCut& cut, const std::string& name) {
  for (std::size_t k = 0; k < cut.panels.panels.size(); ++k)
    if (cut.panels.panels[k].name == name) return k;
  ADD_FAILURE() << "no piece " << name;
  return 0;
}

std::size_t seam_between(const PatternCut& cut, std::size_t a, std::size_t b) {
  for (std::size_t i = 0; i < cut.panels.seams.size(); ++i) {
    const Seam& s = cut.panels.seams[i];
    if ((s.panel[0] == a && s.panel[1] == b) || (s.panel[0] == b && s.panel[1] == a)) return i;
  }
  ADD_FAILURE() << "no seam between pieces " << a << " and " << b;
  return 0;
}

TEST(SeamsHeld, OnlyPiecesWithASeamApartAreFlattenedAgain) {
  const Garment g = three_pieces();
  const PatternCut cut = cut_pattern(g, {}, "three.obj");
  ASSERT_EQ(cut.panels.panels.size(), 3u);
  const std::size_t left = piece_named(cut, "left"), middle = piece_named(cut, "middle"), right = piece_named(cut, "right");
  const std::size_t flat_seam = seam_between(cut, left, middle), bumpy_seam = seam_between(cut, middle, right);

  PatternOptions plain_options;
  plain_options.flatten.boundary_weight = 0;  // plain ARAP only
  const Pattern plain = flatten_pattern(g, cut, g.positions, plain_options);
  // The premise: plain ARAP leaves the bumpy seam apart, the flat one together.
  ASSERT_GT(plain.seams[bumpy_seam].mismatch, 0.005);
  ASSERT_LT(plain.seams[flat_seam].mismatch, 1e-6);

  const Pattern p = flatten_pattern(g, cut, g.positions, PatternOptions{});
  EXPECT_FALSE(p.pieces[left].seams_held);
  EXPECT_TRUE(p.pieces[middle].seams_held);
  EXPECT_TRUE(p.pieces[right].seams_held);
  // The left piece keeps its plain flattening (the layout only moves it).
  const Points2 l = p.pieces[left].uv, l0 = plain.pieces[left].uv;
  EXPECT_LT(((l.rowwise() - l.colwise().mean()) - (l0.rowwise() - l0.colwise().mean())).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(p.pieces[left].iterations, plain.pieces[left].iterations);
  // Both seams agree: the middle's side of the flat seam is held at the left's length.
  EXPECT_LT(p.seams[bumpy_seam].mismatch, 0.001);
  EXPECT_LT(p.seams[flat_seam].mismatch, 0.001);
}

TEST(SeamsHeld, ToleranceZeroFlattensEveryPieceWithASeamAgain) {
  const Garment g = three_pieces();
  const PatternCut cut = cut_pattern(g, {}, "three.obj");
  PatternOptions options;
  options.seam_tolerance = 0;
  const Pattern p = flatten_pattern(g, cut, g.positions, options);
  for (const PatternPiece& piece : p.pieces) EXPECT_TRUE(piece.seams_held);
  for (const SeamMeasure& s : p.seams) EXPECT_LT(s.mismatch, 0.001);
}

// A tab of 4 x 4 cells, raised to a dome, sewn on three sides into a notch of a
// flat piece (its three sides one seam): plain ARAP opens the dome and lengthens
// the tab's side, and held at weight 100 its sides stay more than 0.5 % apart, so
// both pieces are held again ten times as hard.
TEST(SeamsHeld, ASeamStillApartIsHeldHarder) {
  constexpr int n = 10;
  const auto in_tab = [](int i, int j) { return i >= 3 && i < 7 && j >= 6; };
  Garment g = parse_garment_obj(test::grid_obj(n, n,
                                               [&](int i, int j) {
                                                 return std::string(in_tab(i, j) ? "g tab\n" : "g body\n");
                                               }),
                                "tab.obj");
  for (int j = 7; j < n; ++j)
    for (int i = 4; i < 7; ++i)
      g.positions(test::grid_index(i, j, n), 2) = 5.0 * std::sin(M_PI * (i - 3) / 4.0) * std::sin(M_PI * (j - 6) / 4.0);
  const PatternCut cut = cut_pattern(g, {}, "tab.obj");
  ASSERT_EQ(cut.panels.panels.size(), 2u);
  PatternOptions once;
  once.seam_agreement = 1.0;  // no harder pass
  const Pattern p1 = flatten_pattern(g, cut, g.positions, once);
  ASSERT_GT(p1.seam_mismatch_max, 0.005);  // the premise
  const Pattern p = flatten_pattern(g, cut, g.positions, PatternOptions{});
  EXPECT_LE(p.seam_mismatch_max, 0.005);
  EXPECT_GT(p.pieces[0].iterations, p1.pieces[0].iterations);
}

}  // namespace
}  // namespace refit
