// Points bound to a garment's surface and carried to deformed states.
#include <refit/attach/attachment.hpp>
#include <refit/body/body_surface.hpp>

#include <gtest/gtest.h>

#include <random>

namespace refit {
namespace {

TEST(Attach, PointsLandOnTheirOwnFaceOfACoarseMesh) {
  // Two big quads (20 cm) and a hanging line beside them, with 200 samples
  // along one quad's diagonal: many samples share a nearest vertex that is nearer
  // another sample, the case that once attached points to far faces with a large
  // offset (which a deformation then carries rigidly).
  Garment g;
  g.positions.resize(8, 3);
  g.positions << 0, 0, 0, 20, 0, 0, 20, 20, 0, 0, 20, 0, 40, 0, 0, 40, 20, 0, 50, 0, 0, 50, 20, 0;
  g.faces.push_row(std::array<Index, 4>{0, 1, 2, 3});
  g.faces.push_row(std::array<Index, 4>{1, 4, 5, 2});
  g.lines.push_row(std::array<Index, 2>{6, 7});
  Points samples(201, 3);
  for (int i = 0; i < 200; ++i) samples.row(i) << 1.0 + 0.09 * i, 19.0 - 0.09 * i, 0.001 * (i % 3);
  samples.row(200) << 50.0, 7.0, 0.5;  // beside the hanging line
  const SurfaceAttachment at = attach_points(g, samples);
  for (Eigen::Index i = 0; i < samples.rows(); ++i) EXPECT_LT(at.offset.row(i).norm(), 0.51) << i;
  // A bend of the first quad about x = 20 moves every sample with it.
  Points bent = g.positions;
  for (int v : {0, 3}) bent(v, 2) = 20.0, bent(v, 0) = 20.0;
  bent.row(7) << 60, 20, 0;
  const Points carried = carry(at, bent);
  for (int i = 0; i < 200; ++i) {
    const double t = (samples(i, 0)) / 20.0;  // 1 at x = 20, 0 at x = 0
    EXPECT_NEAR(carried(i, 0), 20.0, 1e-9) << i;
    EXPECT_NEAR(carried(i, 2), 20.0 * (1.0 - t) + samples(i, 2), 1e-9) << i;
  }
  EXPECT_NEAR(carried(200, 0), 53.5, 1e-9);  // 7/20 of the way along the moved line
}

TEST(Attach, GarmentOfBarePointsUsesTheNearestVertex) {
  Garment g;
  g.positions.resize(3, 3);
  g.positions << 0, 0, 0, 10, 0, 0, 20, 0, 0;
  Points samples(2, 3);
  samples << 9, 1, 0, 50, 0, 0;
  const SurfaceAttachment at = attach_points(g, samples);
  Points moved = g.positions;
  moved.col(1).array() += 5.0;
  const Points carried = carry(at, moved);
  EXPECT_NEAR((carried.row(0) - Eigen::RowVector3d(9, 6, 0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((carried.row(1) - Eigen::RowVector3d(50, 5, 0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(at.vertex[1][0], 2);
}

}  // namespace
TEST(Attach, ClosestElementMatchesAScanOfEveryElement) {
  // Faces of very different sizes (a 1 mm grid beside a 2 m quad), a long hanging
  // line and loose points; samples on, near and far from them. The element tree
  // must find the same closest distance as a scan over every element.
  Garment g;
  std::vector<Vec3> v;
  for (int i = 0; i <= 30; ++i)
    for (int j = 0; j <= 30; ++j) v.push_back({0.1 * i, 0.1 * j, 0.0});
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) {
      const Index a = Index(31 * i + j);
      g.faces.push_row(std::array<Index, 4>{a, a + 31, a + 32, a + 1});
    }
  const Index big = Index(v.size());
  for (const Vec3& c : {Vec3(5, -100, -100), Vec3(5, 100, -100), Vec3(5, 100, 100), Vec3(5, -100, 100)}) v.push_back(c);
  g.faces.push_row(std::array<Index, 4>{big, Index(big + 1), Index(big + 2), Index(big + 3)});
  v.push_back({-50, 0, 3});
  v.push_back({50, 0, 3});
  g.lines.push_row(std::array<Index, 2>{Index(big + 4), Index(big + 5)});
  v.push_back({1, 1, -2});
  v.push_back({-7, 4, 9});
  g.points.push_row(std::array<Index, 2>{Index(big + 6), Index(big + 7)});
  g.positions.resize(Eigen::Index(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) g.positions.row(Eigen::Index(i)) = v[i].transpose();

  std::mt19937 rng(7);
  std::uniform_real_distribution<double> near(-0.5, 3.5), far(-120.0, 120.0);
  Points samples(2000, 3);
  for (Eigen::Index s = 0; s < samples.rows(); ++s)
    samples.row(s) = s % 2 ? Vec3(near(rng), near(rng), 0.05 * near(rng)).transpose()
                           : Vec3(far(rng), far(rng), far(rng)).transpose();
  samples.row(0) = g.positions.row(40);  // exactly on a vertex shared by four faces
  const SurfaceAttachment at = attach_points(g, samples);

  const auto distance_to = [&](const Vec3& p, const std::array<Index, 3>& e, int corners) {
    const Vec3 a = row3(g.positions, e[0]), b = row3(g.positions, e[1]), c = row3(g.positions, e[2]);
    if (corners == 1) return (p - a).norm();
    if (corners == 2) {
      const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      return (p - (a + t * (b - a))).norm();
    }
    return (p - closest_point_on_triangle(p, a, b, c)).norm();
  };
  for (Eigen::Index s = 0; s < samples.rows(); ++s) {
    const Vec3 p = samples.row(s).transpose();
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t f = 0; f < g.faces.rows(); ++f) {
      const auto r = g.faces.row(f);
      for (std::size_t k = 1; k + 1 < r.size(); ++k) best = std::min(best, distance_to(p, {r[0], r[k], r[k + 1]}, 3));
    }
    best = std::min(best, distance_to(p, {big + 4, big + 5, big + 5}, 2));
    best = std::min(best, std::min(distance_to(p, {big + 6, big + 6, big + 6}, 1),
                                   distance_to(p, {big + 7, big + 7, big + 7}, 1)));
    ASSERT_NEAR(at.offset.row(s).norm(), best, 1e-12 * (1.0 + best)) << "sample " << s;
  }
  EXPECT_EQ(at.offset.row(0).norm(), 0.0);
  // Of the four faces at that vertex, the first in file order: face 8 (corners
  // 8, 39, 40, 9), its first fan triangle, all the weight on vertex 40.
  EXPECT_EQ(at.vertex[0], (std::array<Index, 3>{8, 39, 40}));
  EXPECT_NEAR(at.weight[0][2], 1.0, 1e-12);
}

// The locator keeps two triangle faces that share an edge in one element of
// its tree: what it finds is still what a scan of the triangles in face order
// finds (the first of equally close ones), whichever faces it pairs.
TEST(Attach, TriangleFacesAttachAsAScanOfThemFinds) {
  Garment g;
  const int n = 24;
  std::vector<Vec3> v;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) v.push_back({0.5 * i, 0.5 * j, 0.2 * std::sin(0.6 * i) * std::cos(0.4 * j)});
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Index a = Index((n + 1) * i + j), b = a + 1, c = a + Index(n + 1), d = c + 1;
      if ((i * n + j) % 17 == 5) g.faces.push_row(std::array<Index, 3>{0, Index(n), Index((n + 1) * n)});  // a stray: the pairs shift
      g.faces.push_row(std::array<Index, 3>{a, c, d});
      g.faces.push_row(std::array<Index, 3>{a, d, b});
    }
  g.positions.resize(Eigen::Index(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) g.positions.row(Eigen::Index(i)) = v[i].transpose();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 13.0);
  Points samples(1500, 3);
  for (Eigen::Index s = 0; s < samples.rows(); ++s) samples.row(s) << u(rng), u(rng), 0.1 * u(rng);
  for (Eigen::Index s = 0; s < 100; ++s) samples.row(s) = g.positions.row(s * 7 % g.positions.rows());  // on vertices: ties
  const SurfaceAttachment at = attach_points(g, samples);
  for (Eigen::Index s = 0; s < samples.rows(); ++s) {
    const Vec3 p = samples.row(s).transpose();
    double best = std::numeric_limits<double>::infinity();
    std::array<Index, 3> want{};
    for (std::size_t f = 0; f < g.faces.rows(); ++f) {
      const auto r = g.faces.row(f);
      const double d2 = (p - closest_point_on_triangle(p, row3(g.positions, r[0]), row3(g.positions, r[1]),
                                                       row3(g.positions, r[2]))).squaredNorm();
      if (d2 < best) best = d2, want = {r[0], r[1], r[2]};
    }
    ASSERT_EQ(at.vertex[std::size_t(s)], want) << "sample " << s;
    ASSERT_NEAR(at.offset.row(s).squaredNorm(), best, 1e-12 * (1.0 + best)) << "sample " << s;
  }
}

}  // namespace refit
