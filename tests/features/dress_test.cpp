// Feature curves on the procedural dress (tools/mannequin): the manifold dress and
// its non-manifold soup variant give the same slices and boundaries.
#include <refit/core/error.hpp>
#include <refit/features/bspline.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/features/slice.hpp>

#include <gtest/gtest.h>

#include "curve_distance.hpp"
#include "mannequin/mannequin.hpp"

using namespace refit;
using test::hausdorff;

TEST(Dress, SlicesAndBoundariesAgreeOnTheDressAndItsSoup) {
  const mannequin::BodyParams body;
  mannequin::GarmentParams gp;
  gp.target_vertices = 8000;
  const Garment dress = mannequin::make_garment(body, gp);
  gp.soup = true;
  const Garment soup = mannequin::make_garment(body, gp);
  ASSERT_GT(soup.vertex_count(), dress.vertex_count());  // really a different mesh
  ASSERT_GT(soup.lines.rows(), 0u);
  const auto specs = parse_feature_json(mannequin::dress_features_json(body, gp), "dress.json");
  ASSERT_EQ(specs.size(), 5u);
  const auto a = build_feature_curves(dress, specs);
  const auto b = build_feature_curves(soup, specs);
  ASSERT_EQ(a.size(), b.size());
  const double diag = bounding_box_diagonal(dress.positions);
  for (std::size_t i = 0; i < a.size(); ++i) {
    SCOPED_TRACE(a[i].name);
    EXPECT_EQ(a[i].closed, b[i].closed);
    EXPECT_EQ(a[i].samples.rows(), b[i].samples.rows());
    // Same curve: every sample of one within a small distance of the other's polyline.
    const double h = hausdorff(a[i].samples, a[i].closed, b[i].samples, b[i].closed);
    std::printf("[ info ] %s: dress vs soup Hausdorff %.2e cm (bbox diagonal %.1f cm)\n", a[i].name.c_str(), h, diag);
    EXPECT_LT(h, 1e-3 * diag);
    // And the same samples (same start, same direction).
    EXPECT_LT((a[i].samples - b[i].samples).rowwise().norm().maxCoeff(), 1e-3 * diag);
  }
  // The hem is closed and goes all the way round (through the soup's split seams too).
  EXPECT_EQ(b.front().name, "hem");
  EXPECT_TRUE(b.front().closed);
  EXPECT_GT(polyline_length(b.front().samples, true), 100.0);
}

TEST(Dress, SoupSliceChainsThroughDuplicatedSeams) {
  const mannequin::BodyParams body;
  mannequin::GarmentParams gp;
  gp.target_vertices = 8000;
  const Garment dress = mannequin::make_garment(body, gp);
  gp.soup = true;
  const Garment soup = mannequin::make_garment(body, gp);
  // A horizontal cut through the skirt: one closed loop in both.
  const mannequin::Landmarks lv = mannequin::landmarks(body);
  const FeaturePlane plane = FeaturePlane::from_point_normal(Vec3(0, 0.5 * (lv.hip + lv.knee), 0), Vec3::UnitY());
  auto longest = [](const SliceResult& r) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < r.pieces.size(); ++i)
      if (polyline_length(r.pieces[i].points, r.pieces[i].closed) > polyline_length(r.pieces[best].points, r.pieces[best].closed)) best = i;
    return r.pieces.at(best);
  };
  const SlicePiece pa = longest(slice_garment(dress, plane));
  const SlicePiece pb = longest(slice_garment(soup, plane));
  EXPECT_TRUE(pa.closed);
  EXPECT_TRUE(pb.closed);
  EXPECT_LT(hausdorff(pa.points, true, pb.points, true), 1e-6 * bounding_box_diagonal(dress.positions) + 1e-9);
}
