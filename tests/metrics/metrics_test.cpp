// Metrics and rendering.
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/metrics/metrics.hpp>
#include <refit/metrics/render.hpp>

#include <mannequin/mannequin.hpp>

#include "support/shapes.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wsign-compare"
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>
#pragma GCC diagnostic pop

#include <Eigen/Geometry>

#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

namespace refit {
namespace {

BodyMesh sphere_body(int levels, double radius) { return test::icosphere(levels, radius); }

Garment sphere_garment(int levels, double radius) { return test::icosphere_garment(levels, radius); }

// -- profile straightness ----------------------------------------------------

TEST(Metrics, StraightnessIsZeroForSimilarCopiesAndSeesABulge) {
  Points line(11, 3);
  for (int i = 0; i < 11; ++i) line.row(i) << i, 0.0, 0.0;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  Points copy = ((2.5 * line * r.transpose()).rowwise() + Eigen::RowVector3d(4, -1, 2)).eval();
  EXPECT_NEAR(profile_straightness(copy, line, false), 0.0, 1e-12);
  Points bent = line;
  bent(5, 1) = 1.0;
  // Least squares spreads the bump: about (1 - 1/11) / 10 remains at the bent point.
  const double s = profile_straightness(bent, line, false);
  EXPECT_GT(s, 0.08);
  EXPECT_LT(s, 0.1);
  EXPECT_THROW(profile_straightness(bent.topRows(5), line, false), Error);
}

// -- compute_metrics on a known case --------------------------------------------

TEST(Metrics, SphereShellScaledAndShiftedGivesTheExpectedNumbers) {
  const BodyMesh a = sphere_body(4, 10.0), b = sphere_body(4, 11.0);
  const Garment g = sphere_garment(3, 10.5);
  const BodySurface sa(a), sb(b);
  // Facets sit inside the sphere by at most this much (level 4, r = 11).
  const double facet = 11.0 * (1.0 - std::cos(0.04));

  // Scaled to r = 11.3 around B (r = 11): every vertex was 0.5 from A and is 0.3 from B.
  Points scaled = g.positions * (11.3 / 10.5);
  ResizeMetrics m = compute_metrics(g, scaled, sa, sb);
  EXPECT_EQ(m.vertices, g.vertex_count());
  EXPECT_EQ(m.fit.vertices, g.vertex_count());
  EXPECT_NEAR(m.fit.mean_change, -0.2, facet);
  EXPECT_NEAR(m.fit.max_abs_change, 0.2, facet);
  EXPECT_EQ(m.penetration.inside, 0u);
  EXPECT_EQ(m.sanity.nan_vertices, 0u);
  EXPECT_EQ(m.sanity.flipped_faces, 0u);
  EXPECT_EQ(m.sanity.faces_checked, g.faces.rows());
  EXPECT_NEAR(m.sanity.edge_ratio_p1, 11.3 / 10.5, 1e-12);
  EXPECT_NEAR(m.sanity.edge_ratio_p99, 11.3 / 10.5, 1e-12);

  // Shifted by 3 along +z on the unchanged shell around B: the vertices that
  // land inside r = 11 (less the facet margin) are inside.
  Points shifted = g.positions.rowwise() + Eigen::RowVector3d(0, 0, 3);
  std::size_t expected = 0, ambiguous = 0;
  double deepest = 0.0;
  for (Eigen::Index i = 0; i < shifted.rows(); ++i) {
    const double r = shifted.row(i).norm();
    if (r < 11.0 - facet) {
      ++expected;
      deepest = std::max(deepest, 11.0 - r);
    } else if (r < 11.0) {
      ++ambiguous;
    }
  }
  m = compute_metrics(g, shifted, sa, sb);
  EXPECT_GE(m.penetration.inside, expected);
  EXPECT_LE(m.penetration.inside, expected + ambiguous);
  EXPECT_NEAR(m.penetration.fraction, double(m.penetration.inside) / double(g.vertex_count()), 1e-15);
  EXPECT_NEAR(m.penetration.deepest, deepest, facet);
  EXPECT_EQ(m.sanity.flipped_faces, 0u);
  EXPECT_NEAR(m.sanity.edge_ratio_p50, 1.0, 1e-12);

  // A NaN row is counted and never reaches the numbers (JSON has no null).
  Points broken = g.positions;
  broken(0, 1) = std::nan("");
  const SanityMetrics s = measure_sanity(g, broken);
  EXPECT_EQ(s.nan_vertices, 1u);
  EXPECT_EQ(s.flipped_faces, 0u);
  EXPECT_EQ(s.faces_checked, g.faces.rows() - 5);  // the five faces around vertex 0 are skipped
  const auto j = compute_metrics(g, broken, sa, sb).to_json();
  EXPECT_EQ(j.dump().find("null"), std::string::npos) << j.dump();
  EXPECT_EQ(j["penetration"]["checked"], g.vertex_count() - 1);

  EXPECT_THROW(compute_metrics(g, Points(3, 3), sa, sb), Error);
}

TEST(Metrics, FeatureScoresOfASimilarCopyAreZero) {
  MetricsOptions o;
  FeatureCurveInput c;
  c.name = "hem";
  c.closed = true;
  c.original.resize(12, 3);
  for (int i = 0; i < 12; ++i) c.original.row(i) << std::cos(i * M_PI / 6), 0.3 * std::sin(i * M_PI / 6), 0.0;
  c.result = (c.original * 1.2).rowwise() + Eigen::RowVector3d(0, 1, 0);
  c.warped = c.original;
  c.warped(3, 2) = 0.2;
  o.features.push_back(c);
  const Garment g = sphere_garment(1, 10.5);
  const BodySurface a(sphere_body(2, 10.0));
  const ResizeMetrics m = compute_metrics(g, g.positions, a, a, o);
  ASSERT_EQ(m.features.size(), 1u);
  EXPECT_NEAR(m.features[0].result.shape_error, 0.0, 1e-12);
  EXPECT_NEAR(m.features[0].result.turning_change_deg, 0.0, 1e-9);
  EXPECT_NEAR(m.features[0].result.straightness, 0.0, 1e-12);
  EXPECT_TRUE(m.features[0].has_warp);
  EXPECT_GT(m.features[0].warp.straightness, 0.005);
  EXPECT_GT(m.features[0].warp.turning_change_deg, 0.1);
}

TEST(Metrics, FlippedFacesOfAMirroredSheet) {
  Garment sheet;
  sheet.positions.resize(9, 3);
  for (int i = 0; i < 9; ++i) sheet.positions.row(i) << i % 3, i / 3, 0.0;
  for (Index r = 0; r < 2; ++r)
    for (Index c = 0; c < 2; ++c) {
      const std::array<Index, 4> q = {3 * r + c, 3 * r + c + 1, 3 * r + c + 4, 3 * r + c + 3};
      sheet.faces.push_row(q);
    }
  Points mirrored = sheet.positions;
  mirrored.col(0) *= -1.0;
  EXPECT_EQ(measure_sanity(sheet, mirrored).flipped_faces, 4u);
  Points folded = sheet.positions;
  folded(0, 0) = 1.5;  // corner vertex pulled over: only its quad turns over
  folded(0, 1) = 1.5;
  const SanityMetrics s = measure_sanity(sheet, folded);
  EXPECT_EQ(s.flipped_faces, 1u);
  EXPECT_EQ(s.faces_checked, 4u);
}

// -- render ---------------------------------------------------------------------

// The default mannequin and a 4000-vertex dress on it.
struct Dressed {
  mannequin::BodyParams bp;
  BodyMesh body = mannequin::make_body(bp);
  Garment dress = mannequin::make_garment(bp, [] {
    mannequin::GarmentParams gp;
    gp.target_vertices = 4000;
    return gp;
  }());
};

TEST(Render, WritesAPngOfTheRequestedSizeWithContent) {
  const Dressed d;
  const BodyMesh& body = d.body;
  const Garment& dress = d.dress;
  std::vector<Points> curves(1, Points(2, 3));
  curves[0] << -20, 100, 30, 20, 100, 30;
  RenderOptions o;
  o.width = 240;
  o.height = 300;
  o.views = {View::front, View::side};
  const Image img = render(body, dress, &dress, curves, o);
  ASSERT_EQ(img.width, 240);
  ASSERT_EQ(img.height, 300);
  test::TempDir dir;
  const std::string path = dir.file("pic.png");
  write_png(path, img);
  int w = 0, h = 0, ch = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &ch, 3);
  ASSERT_NE(data, nullptr);
  EXPECT_EQ(w, 240);
  EXPECT_EQ(h, 300);
  std::size_t background = 0, red = 0, garment_blue = 0, garment_orange = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const unsigned char* p = data + 3 * (y * w + x);
      if (p[0] == 255 && p[1] == 255 && p[2] == 255) ++background;
      if (p[0] == 220 && p[1] == 20 && p[2] == 60) ++red;
      if (p[2] > p[0] + 40) (x < w / 2 ? garment_blue : garment_orange) += 1;
      if (p[0] > p[2] + 60 && p[1] < 150 && x >= w / 2) ++garment_orange;
    }
  stbi_image_free(data);
  EXPECT_LT(background, std::size_t(w * h));
  EXPECT_GT(background, std::size_t(w * h / 3));
  EXPECT_GT(red, 20u);
  EXPECT_GT(garment_blue, 200u);
  EXPECT_GT(garment_orange, 200u);
  // Same input, same picture.
  EXPECT_TRUE(render(body, dress, &dress, curves, o).rgb == img.rgb);
  o.width = 4;
  EXPECT_THROW(render(body, dress, nullptr, curves, o), Error);
}

// Pixels that are not background within [x0, x1) x [y0, y1).
std::size_t content(const Image& img, int x0, int y0, int x1, int y1) {
  std::size_t count = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const std::uint8_t* p = &img.rgb[3 * (std::size_t(y) * std::size_t(img.width) + std::size_t(x))];
      count += p[0] != kBackground[0] || p[1] != kBackground[1] || p[2] != kBackground[2];
    }
  return count;
}

TEST(Render, AZoomMagnifiesEachPanelAboutTheGivenPoint) {
  const Dressed d;
  const BodyMesh& body = d.body;
  const Garment& dress = d.dress;
  RenderOptions o;
  o.width = 300;
  o.height = 400;
  o.views = {View::front};
  const Image whole = render(body, dress, nullptr, {}, o);
  // Zoomed 2x about a point, the picture shows the window of half its size
  // around that point of the whole picture: 4x the pixels for the same content.
  const auto check = [&](double cx, double cy) {
    o.zoom = 2.0;
    o.centre_x = cx;
    o.centre_y = cy;
    const Image zoomed = render(body, dress, nullptr, {}, o);
    const int x0 = int(std::lround(cx * o.width - o.width / 4.0)), y0 = int(std::lround(cy * o.height - o.height / 4.0));
    const double window = double(content(whole, x0, y0, x0 + o.width / 2, y0 + o.height / 2));
    ASSERT_GT(window, 1000.0);
    EXPECT_NEAR(double(content(zoomed, 0, 0, o.width, o.height)) / (4.0 * window), 1.0, 0.03) << cx << ", " << cy;
  };
  check(0.5, 0.5);
  check(0.4, 0.3);   // the chest, left of the middle
  check(0.55, 0.75); // the legs
  o.zoom = 0.5;
  EXPECT_THROW(render(body, dress, nullptr, {}, o), Error);
  o.zoom = 2.0;
  o.centre_y = 1.5;
  EXPECT_THROW(render(body, dress, nullptr, {}, o), Error);
}

// -- the commands ---------------------------------------------------------------

bool cli_built() { return std::filesystem::exists(REFIT_CLI_PATH); }

TEST(CompareCommand, ShiftedGarmentGivesTheExpectedNumbers) {
  if (!cli_built()) GTEST_SKIP() << "the refit command line is not built";
  const std::string dir = test::shared_data_dir();
  if (dir.empty()) GTEST_SKIP() << "shared data (../shared/data) not found";
  test::TempDir tmp;
  // The skirt moved 0.5 cm up: same body, so fit and sanity are known.
  const std::string garment = dir + "/garments/skirt_on_A_female.obj", body = dir + "/bodies/A_female.obj";
  std::string text = test::read_text(garment), shifted;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("v ", 0) == 0) {
      std::istringstream ss(line.substr(2));
      double x, y, z;
      ss >> x >> y >> z;
      std::ostringstream os;
      os.precision(17);
      os << "v " << x << ' ' << y + 0.5 << ' ' << z;
      line = os.str();
    }
    shifted += line + "\n";
  }
  test::write_text(tmp.file("shifted.obj"), shifted);
  const auto r = test::run_cli("compare --garment '" + garment + "' --from '" + body + "' --to '" + body +
                               "' --result '" + tmp.file("shifted.obj") + "' --report '" + tmp.file("c.json") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(test::read_text(tmp.file("c.json")));
  EXPECT_EQ(j["vertices"], 720);
  EXPECT_EQ(j["sanity"]["flipped_faces"], 0);
  EXPECT_NEAR(j["sanity"]["edge_ratio_p1"].get<double>(), 1.0, 1e-9);
  EXPECT_NEAR(j["sanity"]["edge_ratio_p99"].get<double>(), 1.0, 1e-9);
  EXPECT_EQ(j["sanity"]["nan_vertices"], 0);
  // A shift of 0.5 changes no distance by more than 0.5.
  EXPECT_LE(j["fit"]["max_abs_change"].get<double>(), 0.5 + 1e-9);
  EXPECT_GT(j["fit"]["vertices"].get<int>(), 0);

  // Different vertex count: a clear one-line error naming the file.
  test::write_text(tmp.file("small.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const auto bad = test::run_cli("compare --garment '" + garment + "' --from '" + body + "' --to '" + body +
                                 "' --result '" + tmp.file("small.obj") + "'");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("small.obj"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("same vertex order"), std::string::npos) << bad.err;
}

TEST(RenderCommand, WritesThePicture) {
  if (!cli_built()) GTEST_SKIP() << "the refit command line is not built";
  const std::string dir = test::shared_data_dir();
  if (dir.empty()) GTEST_SKIP() << "shared data (../shared/data) not found";
  test::TempDir tmp;
  const auto r = test::run_cli("render --body '" + dir + "/bodies/A_female.obj' --garment '" + dir +
                               "/garments/skirt_on_A_female.obj' --views front,side --size 320x200 --out '" +
                               tmp.file("p.png") + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int w = 0, h = 0, ch = 0;
  unsigned char* data = stbi_load(tmp.file("p.png").c_str(), &w, &h, &ch, 3);
  ASSERT_NE(data, nullptr);
  EXPECT_EQ(w, 320);
  EXPECT_EQ(h, 200);
  std::size_t content = 0;
  for (int i = 0; i < w * h; ++i) content += !(data[3 * i] == 255 && data[3 * i + 1] == 255 && data[3 * i + 2] == 255);
  stbi_image_free(data);
  EXPECT_GT(content, 1000u);
  const auto bad = test::run_cli("render --body '" + dir + "/bodies/A_female.obj' --garment '" + dir +
                                 "/garments/skirt_on_A_female.obj' --size 320by200 --out '" + tmp.file("q.png") + "'");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--size"), std::string::npos) << bad.err;
  // A detail: the waist magnified 6 times fills the picture (--center: --centre's other spelling).
  const auto zoomed = test::run_cli("render --body '" + dir + "/bodies/A_female.obj' --garment '" + dir +
                                    "/garments/skirt_on_A_female.obj' --size 320x200 --zoom 6 --center 0.5,0.45 --out '" +
                                    tmp.file("z.png") + "'");
  ASSERT_EQ(zoomed.exit_code, 0) << zoomed.err;
  data = stbi_load(tmp.file("z.png").c_str(), &w, &h, &ch, 3);
  ASSERT_NE(data, nullptr);
  std::size_t background = 0;
  for (int i = 0; i < w * h; ++i) background += data[3 * i] == 255 && data[3 * i + 1] == 255 && data[3 * i + 2] == 255;
  stbi_image_free(data);
  EXPECT_LT(background, (std::size_t(w * h) - content) / 2);  // the whole body's picture is mostly background
  for (const char* centre : {"0.5", "0.5;0.4", "2,0.5"}) {
    const auto wrong = test::run_cli("render --body '" + dir + "/bodies/A_female.obj' --garment '" + dir +
                                     "/garments/skirt_on_A_female.obj' --zoom 2 --centre '" + centre + "' --out '" +
                                     tmp.file("w.png") + "'");
    EXPECT_NE(wrong.exit_code, 0) << centre;
    EXPECT_NE(wrong.err.find("centre"), std::string::npos) << wrong.err;
    EXPECT_FALSE(std::filesystem::exists(tmp.file("w.png")));
  }
}

}  // namespace
}  // namespace refit
