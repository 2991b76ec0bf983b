// Slicing hand-made meshes: manifold, soup, non-manifold, hanging edges.
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/features/bspline.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/features/slice.hpp>

#include "curve_distance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace refit;

using test::hausdorff;

namespace {

// An open tube (radius 10, y from 0 to 20) of quads: `around` x `rings`.
Garment tube(int around = 32, int rings = 10) {
  Garment g;
  g.positions.resize(around * (rings + 1), 3);
  for (int r = 0; r <= rings; ++r)
    for (int a = 0; a < around; ++a) {
      const double t = 2 * std::numbers::pi * a / around;
      g.positions.row(r * around + a) << 10 * std::cos(t), 20.0 * r / rings, 10 * std::sin(t);
    }
  for (int r = 0; r < rings; ++r)
    for (int a = 0; a < around; ++a) {
      const Index q[4] = {Index(r * around + a), Index(r * around + (a + 1) % around), Index((r + 1) * around + (a + 1) % around),
                          Index((r + 1) * around + a)};
      g.faces.push_row(q);
    }
  return g;
}

// The same surface as a soup: every face has its own vertex copies, and is split into two triangles.
Garment soup_of(const Garment& g) {
  Garment s;
  s.positions.resize(g.faces.indices.size() + 2, 3);
  Index next = 0;
  for (std::size_t f = 0; f < g.faces.rows(); ++f) {
    const auto row = g.faces.row(f);
    std::vector<Index> copy;
    for (Index v : row) {
      s.positions.row(next) = g.positions.row(v);
      copy.push_back(next++);
    }
    const Index t0[3] = {copy[0], copy[1], copy[2]}, t1[3] = {copy[0], copy[2], copy[3]};
    s.faces.push_row(t0);
    s.faces.push_row(t1);
  }
  s.positions.row(next++) << 0, 100, 0;  // unreferenced
  s.positions.row(next++) << 0, -100, 0;
  return s;
}


}  // namespace

TEST(Slice, HorizontalCutOfATubeIsOneClosedCircle) {
  const Garment g = tube();
  const SliceResult r = slice_garment(g, FeaturePlane::from_point_normal(Vec3(0, 5, 0), Vec3::UnitY()));
  ASSERT_EQ(r.pieces.size(), 1u);
  EXPECT_TRUE(r.pieces[0].closed);
  EXPECT_EQ(r.pieces[0].points.rows(), 32);
  for (Eigen::Index i = 0; i < 32; ++i) {
    EXPECT_NEAR(r.pieces[0].points(i, 1), 5.0, 1e-12);
    EXPECT_NEAR(std::hypot(r.pieces[0].points(i, 0), r.pieces[0].points(i, 2)), 10.0, 1e-9);
  }
}

TEST(Slice, VerticalCutGivesTwoOpenProfilesAndSoupAgrees) {
  const Garment g = tube();
  const FeaturePlane plane = FeaturePlane::from_point_normal(Vec3(0.5, 0, 0), Vec3::UnitX());
  const SliceResult r = slice_garment(g, plane);
  ASSERT_EQ(r.pieces.size(), 2u);
  for (const SlicePiece& p : r.pieces) {
    EXPECT_FALSE(p.closed);
    EXPECT_EQ(p.points.rows(), 11);
    EXPECT_NEAR(std::abs(p.points(0, 1) - p.points(10, 1)), 20.0, 1e-12);
  }
  const SliceResult s = slice_garment(soup_of(g), plane);
  ASSERT_EQ(s.pieces.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    EXPECT_FALSE(s.pieces[k].closed);
    // Same curves (triangulation adds the diagonal crossings as extra points on the same lines).
    const double h = std::min(hausdorff(r.pieces[k].points, false, s.pieces[0].points, false),
                              hausdorff(r.pieces[k].points, false, s.pieces[1].points, false));
    EXPECT_LT(h, 1e-9);
  }
  // And the closed loop too, through the soup's duplicated vertices.
  const SliceResult loop = slice_garment(soup_of(g), FeaturePlane::from_point_normal(Vec3(0, 7, 0), Vec3::UnitY()));
  ASSERT_EQ(loop.pieces.size(), 1u);
  EXPECT_TRUE(loop.pieces[0].closed);
}

TEST(Slice, NonManifoldFlapBranchesOffAndHangingEdgesGivePoints) {
  Garment g = tube();
  // A flap glued on the vertical edge at angle 0 (vertices 0 and 32): a third face on that edge.
  const Index base = static_cast<Index>(g.positions.rows());
  g.positions.conservativeResize(base + 2, 3);
  g.positions.row(base) << 15, 0, 0;
  g.positions.row(base + 1) << 15, 2, 0;
  const Index flap[4] = {0, base, base + 1, 32};
  g.faces.push_row(flap);
  const Index line[2] = {0, 32 * 10};
  g.lines.push_row(line);
  const SliceResult r = slice_garment(g, FeaturePlane::from_point_normal(Vec3(0, 1, 0), Vec3::UnitY()));
  ASSERT_EQ(r.pieces.size(), 2u);
  // The flap's single segment is an open piece; the tube's circle stays closed.
  int closed = 0;
  for (const SlicePiece& p : r.pieces) {
    if (p.closed) {
      ++closed;
      EXPECT_EQ(p.points.rows(), 32);
    } else {
      EXPECT_EQ(p.points.rows(), 2);
    }
  }
  EXPECT_EQ(closed, 1);
  ASSERT_EQ(r.line_points.rows(), 1);
  EXPECT_NEAR(r.line_points(0, 1), 1.0, 1e-12);
}

TEST(Slice, DoesNotDependOnThreadCount) {
  const Garment g = soup_of(tube(200, 120));
  const FeaturePlane plane = FeaturePlane::from_point_normal(Vec3(0.3, 0, 0.2), Vec3(1, 0.2, 0.1));
  auto run = [&](std::size_t threads) {
    ThreadLimit limit(threads);
    return slice_garment(g, plane);
  };
  const SliceResult a = run(1), b = run(2);
  ASSERT_EQ(a.pieces.size(), b.pieces.size());
  for (std::size_t i = 0; i < a.pieces.size(); ++i) EXPECT_TRUE((a.pieces[i].points.array() == b.pieces[i].points.array()).all());
}

TEST(FeatureCurves, SliceAndBsplineFeaturesOnATube) {
  const Garment g = tube();
  const std::string json = R"({"features": [
    {"name": "side", "plane": {"point": [0,0,0], "normal": [0,0,1]},
     "curve": {"kind": "slice", "near": [10, 10, 0], "from": [10, 2, 0], "to": [10, 18, 0], "control_points": 6}, "samples": 20},
    {"name": "ring", "plane": {"point": [0,10,0], "normal": [0,1,0]},
     "curve": {"kind": "slice", "near": [0, 10, 10]}, "samples": 40},
    {"name": "sketch", "plane": {"segment": [[-10, 15, 0], [10, 15, 0]], "view": [0, 0, 1]},
     "curve": {"kind": "bspline", "control_points": [[-10,15,3],[-5,16,0],[0,15,0],[5,16,0],[10,15,0]]}, "samples": 30}
  ]})";
  const auto curves = build_feature_curves(g, parse_feature_json(json, "t.json"));
  ASSERT_EQ(curves.size(), 3u);
  EXPECT_FALSE(curves[0].closed);
  EXPECT_EQ(curves[0].samples.rows(), 20);
  EXPECT_NEAR(curves[0].samples(0, 1), 2.0, 1e-9);  // clipped between from and to
  EXPECT_NEAR(curves[0].samples(19, 1), 18.0, 1e-9);
  EXPECT_NEAR(curves[0].samples.col(0).minCoeff(), 10.0, 1e-9);
  EXPECT_TRUE(curves[1].closed);
  for (Eigen::Index i = 0; i < 40; ++i) EXPECT_NEAR(std::hypot(curves[1].samples(i, 0), curves[1].samples(i, 2)), 10.0, 0.05);
  EXPECT_NEAR(curves[2].samples.col(1).maxCoeff(), 15.0, 1e-9);  // projected onto y = 15
  EXPECT_NEAR(curves[2].samples.col(1).minCoeff(), 15.0, 1e-9);
  // Auxiliary points lie on the plane, near the samples.
  EXPECT_EQ(curves[0].aux.rows(), 80);
  for (Eigen::Index i = 0; i < curves[0].aux.rows(); ++i)
    EXPECT_NEAR(curves[0].plane.signed_distance(row3(curves[0].aux, static_cast<Index>(i))), 0.0, 1e-9);
}

TEST(FeatureCurves, ErrorsNameTheFeature) {
  const Garment g = tube();
  auto error_of = [&](const std::string& feature) -> std::string {
    try {
      build_feature_curves(g, parse_feature_json(R"({"features": [)" + feature + "]}", "t.json"));
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of(R"({"name": "miss", "plane": {"point": [0,50,0], "normal": [0,1,0]}, "curve": {"kind": "slice", "near": [0,50,0]}, "samples": 9})")
                .find("t.json: feature 'miss': the plane misses the garment"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"name": "far", "plane": {"point": [0,5,0], "normal": [0,1,0]}, "curve": {"kind": "slice", "near": [40,5,0]}, "samples": 9})")
                .find("t.json: feature 'far': 'near' is 30 units from the nearest cut piece"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"name": "few", "plane": {"point": [0,0,0], "normal": [0,0,1]}, "curve": {"kind": "slice", "near": [10,5,0], "from": [10,2,0], "to": [10,8,0]}, "samples": 4})")
                .find("t.json: feature 'few': 'samples' is 4: an open curve needs at least 5 samples"),
            std::string::npos);
}
