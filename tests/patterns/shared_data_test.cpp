// Patterns of the real MakeHuman garments (issue 16), skipped when ../shared/data
// is absent. Asserts what holds today: every garment flattens with no face of a
// piece of 100 faces or more turned over; the skirt's and the jeans' pieces keep
// their 3D area within 1 %, the dress's and the suit's (curved over bust, seat
// and shoulders) within 6 %; the sewn edges of every garment (the jeans and the
// suit cut by bench/quality/features/jeans.json and male_suit.json) agree within
// 0.5 %; the DXF of the jeans reads back (ezdxf) with the report's pieces
// and lengths; the feature lines of the resized patterns are closer to their
// original pattern shape after the full pipeline than after the warp alone.
// Prints the stretch of every garment (issue 16's 0.02 is not reached: about
// 0.09 on skirt and jeans; with automatic darts 0.034 on the skirt and at most
// 0.09 on the jeans' pieces, asserted) and the straightness ratios of the paper's claim
// (Fig. 10), whose 3x target is reached on the suit's trousers resized to F_heavier
// and F_thinner (asserted), not on the jeans (docs/patterns.md).
#include "support/test_support.hpp"

#include <refit/features/feature_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/patterns/darts.hpp>
#include <refit/patterns/grading.hpp>
#include <refit/patterns/pattern.hpp>
#include <refit/pipeline/resize.hpp>

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

namespace refit {
namespace {

std::string data(const std::string& rel) { return test::shared_data_dir() + "/" + rel; }
std::string features(const std::string& garment) {
  return std::string(REFIT_SOURCE_DIR) + "/bench/quality/features/" + garment + ".json";
}

struct Case {
  const char* garment;
  const char* file;
  const char* features;  // a feature file of bench/quality/features, or nullptr
  bool seams_agree;      // sewn edges within 0.5 % is asserted
  double area_change;    // largest |2D area / 3D area - 1| of a piece of 100 faces or more (measured, rounded up)
};

TEST(SharedPatterns, EveryGarmentFlattensAndTheSeamsAgree) {
  if (test::shared_data_dir().empty()) GTEST_SKIP() << "../shared/data is absent";
  const Case cases[] = {{"skirt", "garments/skirt_on_A_female.obj", nullptr, true, 0.01},
                        {"jeans", "garments/jeans_on_A_female.obj", "jeans", true, 0.01},
                        {"dress", "garments/dress_on_A_female.obj", nullptr, true, 0.06},
                        {"male_suit", "garments/male_suit_on_M_ref.obj", "male_suit", true, 0.06},
                        {"outfit_dress_jeans", "garments/outfit_dress_jeans_on_A_female.obj", nullptr, true, 0.06},
                        {"dress_soup", "garments/dress_soup_on_A_female.obj", nullptr, true, 0.06}};
  std::printf("| garment | panels | stretch p95 (faces) | worst panel p95 | seams | worst seam mismatch |\n");
  for (const Case& c : cases) {
    const Garment g = read_garment_obj(data(c.file));
    const std::vector<FeatureSpec> specs = c.features ? read_feature_file(features(c.features)) : std::vector<FeatureSpec>{};
    const PatternCut cut = cut_pattern(g, specs, c.file);
    PatternOptions options;
    options.skip_unflattenable = true;
    const Pattern p = flatten_pattern(g, cut, g.positions, options);
    double worst_piece = 0;
    for (std::size_t k = 0; k < p.pieces.size(); ++k) {
      const PatternPiece& piece = p.pieces[k];
      ASSERT_TRUE(piece.flattened) << c.garment << " " << cut.panels.panels[k].name;
      worst_piece = std::max(worst_piece, piece.measures.stretch_p95);
      // Pieces of a few faces are buttons and tabs (the suit's) that no flattening keeps.
      if (cut.panels.panels[k].faces.size() >= 100) {
        EXPECT_EQ(piece.measures.flipped, 0u) << c.garment << " " << cut.panels.panels[k].name;
        EXPECT_LT(std::abs(piece.measures.area_2d / piece.measures.area_3d - 1), c.area_change) << c.garment << " " << k;
      }
    }
    if (c.seams_agree) {
      for (std::size_t i = 0; i < p.seams.size(); ++i)
        EXPECT_LE(p.seams[i].mismatch, 0.005) << c.garment << " seam " << i << " between "
                                              << cut.panels.panels[cut.panels.seams[i].panel[0]].name << " and "
                                              << cut.panels.panels[cut.panels.seams[i].panel[1]].name;
    }
    std::printf("| %s | %zu | %.4f | %.4f | %zu | %.4f |\n", c.garment, cut.panels.panels.size(), p.stretch_p95,
                worst_piece, p.seams.size(), p.seam_mismatch_max);
  }
}

TEST(SharedPatterns, JeansDxfReadsBackWithTheSamePieces) {
  if (test::shared_data_dir().empty()) GTEST_SKIP() << "../shared/data is absent";
  test::TempDir dir;
  const auto r = test::run_cli("flatten --garment '" + data("garments/jeans_on_A_female.obj") + "' --features '" +
                               features("jeans") + "' --out-dir '" + dir.path().string() + "' --name jeans --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto dxf = test::run_shell("/usr/bin/python3 '" REFIT_SOURCE_DIR "/tests/patterns/read_dxf.py' '" +
                                   dir.file("jeans.dxf") + "'");
  if (dxf.exit_code == 77) GTEST_SKIP() << dxf.out;
  ASSERT_EQ(dxf.exit_code, 0) << dxf.err;
  const nlohmann::json back = nlohmann::json::parse(dxf.out);
  const nlohmann::json report = nlohmann::json::parse(test::read_text(dir.file("jeans.json")));
  std::vector<double> want, got;
  for (const auto& p : report["panels"])
    for (const auto& l : p["outline_lengths"]) want.push_back(l.get<double>());
  for (const auto& p : back["polylines"]["CUT"]) got.push_back(p["length"].get<double>());
  std::sort(want.begin(), want.end());
  std::sort(got.begin(), got.end());
  ASSERT_EQ(want.size(), 4u);  // front and back of each leg
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-5 * want[i]);
  EXPECT_EQ(back["polylines"]["FEATURES"].size(), 4u);  // the creases
}

// Automatic darts (darts.hpp) on the skirt and the jeans: the stretch p95 of
// every piece before and after, the darts' count and lengths, and their two
// sides sewn within 0.5 % like every other seam.
TEST(SharedPatterns, DartsBringTheStretchDown) {
  if (test::shared_data_dir().empty()) GTEST_SKIP() << "../shared/data is absent: no shared garments to cut darts in";
  struct DartCase {
    const char* garment;
    const char* file;
    const char* features;
    double reached;  // the stretch p95 of the worst piece with darts, measured (rounded up)
  };
  // Issue 16's 0.02 is not reached: the skirt's hip line and the jeans' knees
  // and seat stretch beyond the darts' reach from the waist (docs/patterns.md).
  // Cut at its sides as a pattern maker would, the skirt gets closer: its front
  // takes 4 darts, its back halves (0.022) none.
  const DartCase cases[] = {{"skirt", "garments/skirt_on_A_female.obj", nullptr, 0.035},
                            {"jeans", "garments/jeans_on_A_female.obj", "jeans", 0.09},
                            {"skirt cut at its sides", "garments/skirt_on_A_female.obj", "skirt_side_seams", 0.027}};
  std::printf("| garment | panel | p95 before | p95 with darts | darts | dart lengths | worst seam mismatch |\n");
  for (const DartCase& c : cases) {
    const Garment g = read_garment_obj(data(c.file));
    const std::vector<FeatureSpec> specs = c.features ? read_feature_file(features(c.features)) : std::vector<FeatureSpec>{};
    PatternCut cut = cut_pattern(g, specs, c.file);
    const PatternOptions options;
    const Pattern before = flatten_pattern(g, cut, g.positions, options);
    DartOptions darts;
    darts.max_stretch = 0.02;
    const Pattern after = cut_darts(g, cut, options, darts);
    EXPECT_FALSE(cut.darts.empty()) << c.garment;
    ASSERT_EQ(after.pieces.size(), before.pieces.size()) << c.garment;
    for (std::size_t k = 0; k < after.pieces.size(); ++k) {
      std::string lengths;
      std::size_t count = 0;
      for (const Dart& d : cut.darts)
        if (d.panel == k) {
          char buf[32];
          std::snprintf(buf, sizeof buf, "%s%.1f", count++ ? " " : "", d.length_3d);
          lengths += buf;
          EXPECT_GE(dart_seam(cut, d), 0) << c.garment << ": a dart is not a seam";
        }
      std::printf("| %s | %s | %.4f | %.4f | %zu | %s | %.4f |\n", c.garment, cut.panels.panels[k].name.c_str(),
                  before.pieces[k].measures.stretch_p95, after.pieces[k].measures.stretch_p95, count, lengths.c_str(),
                  after.seam_mismatch_max);
      if (count > 0)
        EXPECT_LT(after.pieces[k].measures.stretch_p95, before.pieces[k].measures.stretch_p95) << c.garment << " " << k;
      else  // no dart of its own: only its seams' shared lengths moved, and it is no worse for that
        EXPECT_LE(after.pieces[k].measures.stretch_p95, before.pieces[k].measures.stretch_p95 + 0.001) << c.garment << " " << k;
      EXPECT_LE(after.pieces[k].measures.stretch_p95, c.reached) << c.garment << " " << k;
      EXPECT_EQ(after.pieces[k].measures.flipped, 0u) << c.garment << " " << k;
    }
    for (std::size_t i = 0; i < after.seams.size(); ++i) EXPECT_LE(after.seams[i].mismatch, 0.005) << c.garment << " seam " << i;
  }
}

// `refit flatten --darts auto`: the darts in the report (per panel, with their
// two sides' 2D lengths) and in the printed summary.
TEST(SharedPatterns, FlattenCutsDartsIntoTheSkirt) {
  if (test::shared_data_dir().empty()) GTEST_SKIP() << "../shared/data is absent: no shared skirt to cut darts in";
  test::TempDir dir;
  const auto r = test::run_cli("flatten --garment '" + data("garments/skirt_on_A_female.obj") + "' --out-dir '" +
                               dir.path().string() + "' --name skirt --darts auto");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json report = nlohmann::json::parse(test::read_text(dir.file("skirt.json")));
  ASSERT_EQ(report["panels"].size(), 1u);
  const nlohmann::json& darts = report["panels"][0]["darts"];
  EXPECT_EQ(report["darts"], darts.size());
  EXPECT_GE(darts.size(), 2u);
  for (const auto& d : darts) {
    EXPECT_LE(d["mismatch"].get<double>(), 0.005);
    EXPECT_GT(d["length_2d"][0].get<double>(), 0.0);
  }
  EXPECT_LE(report["stretch_p95"].get<double>(), 0.035);
  EXPECT_NE(r.out.find(": " + std::to_string(darts.size()) + " darts, "), std::string::npos) << r.out;
}

// The paper's claim (section 6, Fig. 10): patterns of the resized trousers have
// fewer S-shaped distortions along the feature curves after the full pipeline
// than after the warp alone; issue 16 asks for 3x on the jeans or the suit's
// trousers resized to F_heavier and F_thinner.
TEST(SharedPatterns, FullPipelinePatternLinesAreStraighterThanTheWarps) {
  if (test::shared_data_dir().empty()) GTEST_SKIP() << "../shared/data is absent";
  struct Claim {
    const char* garment;
    const char* body_a;
    const char* body_b;
    double at_least;  // warp / full: issue 16's 3x where it is reached, else "closer" with a margin
  };
  // jeans / F_heavier: 1.18x before the joint feature solve, 1.14x with it (its
  // curves are kept clear of body B by the feature step itself); still closer
  // than the warp, the trade is stated in docs/method.md.
  const Claim claims[] = {{"jeans", "A_female", "F_heavier", 1.10},
                          {"jeans", "A_female", "F_thinner", 1.15},
                          {"male_suit", "M_ref", "M_heavier", 1.15},
                          {"male_suit", "M_ref", "F_heavier", 3.0},
                          {"male_suit", "M_ref", "F_thinner", 3.0}};
  std::printf("| garment | body | warp straightness (mean) | full | warp / full | worst line warp / full |\n");
  for (const Claim& c : claims) {
    auto g = std::make_shared<const Garment>(
        read_garment_obj(data(std::string("garments/") + c.garment + "_on_" + c.body_a + ".obj")));
    const std::vector<FeatureSpec> specs = read_feature_file(features(c.garment));
    const BodyMesh b = read_body(data(std::string("bodies/") + c.body_b + ".obj"));
    const PatternCut cut = cut_pattern(*g, specs, c.garment);
    PatternOptions options;
    options.skip_unflattenable = true;  // the suit's jacket has pieces that no flattening keeps; the trousers are graded
    const Pattern original = flatten_pattern(*g, cut, g->positions, options);
    std::array<Grading, 2> grading;
    for (int full = 0; full < 2; ++full) {
      ResizeOptions ro;
      ro.stage = full ? Stage::Full : Stage::Warp;
      const GarmentBinding binding(g, read_body(data(std::string("bodies/") + c.body_a + ".obj")), ro, specs);
      const ResizeResult r = binding.resize(b);
      grading[full] = grade_pattern(*g, cut, original, flatten_pattern(*g, cut, r.positions, options));
    }
    ASSERT_EQ(grading[0].lines, 4u);
    double worst = 1e30;
    for (std::size_t k = 0; k < grading[0].pieces.size(); ++k)
      for (std::size_t i = 0; i < grading[0].pieces[k].lines.size(); ++i)
        worst = std::min(worst, grading[0].pieces[k].lines[i].deviation / grading[1].pieces[k].lines[i].deviation);
    const double ratio = grading[0].deviation_mean / grading[1].deviation_mean;
    std::printf("| %s | %s | %.5f | %.5f | %.2f | %.2f |\n", c.garment, c.body_b, grading[0].deviation_mean,
                grading[1].deviation_mean, ratio, worst);
    EXPECT_GE(ratio, c.at_least) << c.garment << " to " << c.body_b;
  }
}

}  // namespace
}  // namespace refit
