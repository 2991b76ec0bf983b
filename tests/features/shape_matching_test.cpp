// Shape matching on feature curves (paper section 4.3, eqs. 5-9), on hand-made curves.
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/features/bspline.hpp>
#include <refit/features/curve_metrics.hpp>
#include <refit/features/shape_matching.hpp>

#include "deformations.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <numbers>

using namespace refit;

namespace {

Points zigzag(std::size_t m, int teeth, double width, double height) {
  Points corners(2 * teeth + 1, 3);
  for (int i = 0; i <= 2 * teeth; ++i) corners.row(i) << i * width / (2 * teeth), (i % 2) * height, 0.0;
  return resample_polyline(corners, m, false);
}

using test::bend;
using test::map_rows;

FeaturePlane plane_z0() { return FeaturePlane::from_point_normal(Vec3::Zero(), Vec3::UnitZ()); }

// The paper's rule: curves one at a time in order, two fixed samples each.
ShapeMatchingOptions in_order() {
  ShapeMatchingOptions o;
  o.joint = false;
  return o;
}

}  // namespace

TEST(ShapeMatching, SimilarityCopyIsLeftUnchanged) {
  // A curvy open curve in z = 0, warped by rotation + uniform scaling + translation.
  Points s(40, 3);
  for (int i = 0; i < 40; ++i) s.row(i) << i * 0.5, 2.0 * std::sin(i * 0.3) + 0.1 * i, 0.0;
  const FeatureCurve c = make_feature_curve("wave", s, false, plane_z0());
  const Eigen::Matrix3d R = Eigen::AngleAxisd(1.1, Vec3(0.3, -1, 0.5).normalized()).toRotationMatrix();
  const double scale = 1.37;
  const Eigen::RowVector3d t(4, -2, 9);
  auto sim = [&](const Points& p) { return Points(((scale * p * R.transpose()).rowwise() + t).eval()); };
  const Points ws = sim(c.samples);
  for (const bool joint : {false, true}) {
    SCOPED_TRACE(joint ? "joint" : "in order");
    ShapeMatchingOptions o;
    o.joint = joint;
    const ShapeModel model = prepare_shape_model({c}, o);
    const FeatureResult r = match_shapes(model, {ws}, {sim(c.aux)}, [](const Vec3& p) { return std::abs(p.y()); });
    ASSERT_EQ(r.curves.size(), 1u);
    const CurveResult& cr = r.curves[0];
    EXPECT_LT((cr.optimised - ws).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT(cr.energy_warped, 1e-18);
    EXPECT_LT(cr.energy_result, 1e-18);
    EXPECT_LT(cr.shape_error_result, 1e-12);
    EXPECT_NEAR(cr.scale_result, scale, 1e-9);
    ASSERT_EQ(cr.fixed.size(), joint ? 1u : 2u);
    EXPECT_EQ(cr.fixed[0].reason, "body");
    if (!joint) {
      EXPECT_NE(cr.fixed[0].index, cr.fixed[1].index);
    }
    // The new plane is the transformed old one, not mirrored.
    EXPECT_NEAR(cr.plane.normal.dot(R * Vec3::UnitZ()), 1.0, 1e-9);
  }
}

TEST(ShapeMatching, Fig6ZigZagKeepsItsAnglesWhenOneEndIsDragged) {
  const std::size_t m = 61;
  const FeatureCurve c = make_feature_curve("zigzag", zigzag(m, 4, 20.0, 3.0), false, plane_z0());
  // Drag the last sample by (6, 5): the samples follow with a quadratic falloff
  // (a non-similar distortion), the first sample stays.
  static const Vec3 drag(6, 5, 0);
  auto warp = [](const Vec3& p) -> Vec3 {
    const double f = std::clamp(p.x() / 20.0, 0.0, 1.0);
    return p + f * f * drag;
  };
  Points ws(m, 3), wa(c.aux.rows(), 3);
  for (std::size_t i = 0; i < m; ++i) ws.row(i) = warp(row3(c.samples, static_cast<Index>(i))).transpose();
  for (Eigen::Index i = 0; i < c.aux.rows(); ++i) wa.row(i) = warp(row3(c.aux, static_cast<Index>(i))).transpose();
  // "Body B" touches the two ends: they are the fixed samples.
  const Vec3 e0 = row3(ws, 0), e1 = row3(ws, m - 1);
  const FeatureResult r = match_shapes(prepare_shape_model({c}, in_order()), {ws}, {wa},
                                       [&](const Vec3& p) { return std::min((p - e0).norm(), (p - e1).norm()); });
  const CurveResult& cr = r.curves[0];
  ASSERT_EQ(cr.fixed.size(), 2u);
  EXPECT_EQ(std::min(cr.fixed[0].index, cr.fixed[1].index), 0u);
  EXPECT_EQ(std::max(cr.fixed[0].index, cr.fixed[1].index), m - 1);
  EXPECT_LT((row3(cr.optimised, m - 1) - e1).norm(), 1e-9);
  std::printf("[ info ] Fig. 6 zig-zag: turning-angle change %.3f deg warped -> %.3f deg optimised; shape error %.4f -> %.4f\n",
              cr.turning_angle_change_warped_deg, cr.turning_angle_change_result_deg, cr.shape_error_warped,
              cr.shape_error_result);
  EXPECT_GT(cr.turning_angle_change_warped_deg, 1.5);
  EXPECT_LT(cr.turning_angle_change_result_deg, 1.0);
  EXPECT_LT(cr.shape_error_result, 0.2 * cr.shape_error_warped);
}

TEST(ShapeMatching, Fig5CrossingCurvesDependOnOrderAndShareTheCrossing) {
  // A runs along x in z = 0; B runs along y in x = 0.3 (off the sample grid); they cross near (0.3, 0, 0).
  Points a(41, 3), b(37, 3);
  for (int i = 0; i < 41; ++i) a.row(i) << -10 + 0.5 * i, 1.5 * std::sin(0.25 * (-10 + 0.5 * i)), 0.0;
  const double ya = 1.5 * std::sin(0.25 * 0.3);  // A at x = 0.3
  for (int i = 0; i < 37; ++i) {
    const double y = -9 + 0.5 * i;
    b.row(i) << 0.3, y, 2.0 * std::sin(0.4 * (y - ya));  // through (0.3, ya, 0), on A
  }
  const FeatureCurve ca = make_feature_curve("A", a, false, plane_z0(), {}, 0);
  const FeatureCurve cb =
      make_feature_curve("B", b, false, FeaturePlane::from_point_normal(Vec3(0.3, 0, 0), Vec3::UnitX()), {}, 1);
  auto warped = [](const FeatureCurve& c) { return std::pair(map_rows(c.samples, bend), map_rows(c.aux, bend)); };
  const auto [wsa, waa] = warped(ca);
  const auto [wsb, wab] = warped(cb);
  auto dist = [](const Vec3& p) { return std::abs(p.y() + 12.0) + 0.1 * std::abs(p.x()); };

  const ShapeModel ab = prepare_shape_model({ca, cb}, in_order());
  const ShapeModel ba = prepare_shape_model({cb, ca}, in_order());
  ASSERT_EQ(ab.crossings[1].size(), 1u);
  ASSERT_EQ(ba.crossings[1].size(), 1u);
  const FeatureResult rab = match_shapes(ab, {wsa, wsb}, {waa, wab}, dist);
  const FeatureResult rba = match_shapes(ba, {wsb, wsa}, {wab, waa}, dist);

  // Self-consistent: the later curve's crossing sample lies on the earlier curve's result.
  const CurveResult& a1 = rab.curves[0];
  const CurveResult& b2 = rab.curves[1];
  ASSERT_EQ(b2.crossings.size(), 1u);
  EXPECT_LT(nearest_on_polyline(a1.optimised, false, row3(b2.optimised, b2.crossings[0].index)).distance, 1e-9);
  const CurveResult& b1 = rba.curves[0];
  const CurveResult& a2 = rba.curves[1];
  ASSERT_EQ(a2.crossings.size(), 1u);
  EXPECT_LT(nearest_on_polyline(b1.optimised, false, row3(a2.optimised, a2.crossings[0].index)).distance, 1e-9);
  // The crossing is a "crossing" candidate for the later curve too.
  EXPECT_EQ(b2.crossings[0].reason, "crossing");

  // Different orders give different results.
  const double da = (a1.optimised - a2.optimised).rowwise().norm().maxCoeff();
  const double db = (b2.optimised - b1.optimised).rowwise().norm().maxCoeff();
  std::printf("[ info ] Fig. 5: max difference between orders: A %.4f, B %.4f\n", da, db);
  EXPECT_GT(da + db, 1e-3);
  // Each still gets its shape back better than the warp left it.
  for (const CurveResult* c : {&a1, &b2, &b1, &a2}) EXPECT_LT(c->shape_error_result, c->shape_error_warped) << c->name;
}

TEST(ShapeMatching, ACrossingOffTheLaterCurvesPlaneMovesThePlaneNotOneSample) {
  // B crosses A; the warp moves A 0.8 along B's plane normal and leaves B alone, so
  // the crossing A puts on B lies 0.8 off B's new (PCA) plane. B keeps its shape
  // exactly by moving its plane there; fixing that one sample off the plane instead
  // kinks B (shape error 0.0059).
  Points a(41, 3), b(37, 3);
  for (int i = 0; i < 41; ++i) a.row(i) << -10 + 0.5 * i, 1.5 * std::sin(0.25 * (-10 + 0.5 * i)), 0.0;
  const double ya = 1.5 * std::sin(0.25 * 0.3);
  for (int i = 0; i < 37; ++i) {
    const double y = -9 + 0.5 * i;
    b.row(i) << 0.3, y, 2.0 * std::sin(0.4 * (y - ya));
  }
  const FeatureCurve ca = make_feature_curve("A", a, false, plane_z0(), {}, 0);
  const FeatureCurve cb =
      make_feature_curve("B", b, false, FeaturePlane::from_point_normal(Vec3(0.3, 0, 0), Vec3::UnitX()), {}, 1);
  const ShapeModel model = prepare_shape_model({ca, cb}, in_order());
  ASSERT_EQ(model.crossings[1].size(), 1u);
  const Vec3 shift(0.8, 0.0, 0.0);
  const FeatureResult r = match_shapes(model, {a.rowwise() + shift.transpose(), b},
                                       {ca.aux.rowwise() + shift.transpose(), cb.aux},
                                       [](const Vec3& p) { return std::abs(p.y() + 12.0) + 0.1 * std::abs(p.x()); });
  const CurveResult& rb = r.curves[1];
  ASSERT_EQ(rb.crossings.size(), 1u);
  EXPECT_LT(nearest_on_polyline(r.curves[0].optimised, false, row3(rb.optimised, rb.crossings[0].index)).distance, 1e-9);
  for (Eigen::Index i = 0; i < rb.optimised.rows(); ++i)
    EXPECT_NEAR(rb.plane.signed_distance(row3(rb.optimised, Index(i))), 0.0, 1e-9) << i;
  EXPECT_LT(rb.shape_error_result, 1e-5);  // 1.3e-6: the crossing sample moves onto A
}

TEST(ShapeMatching, ClosedHemLoopStaysClosed) {
  const std::size_t m = 60;
  Points s(m, 3);
  for (std::size_t i = 0; i < m; ++i) {
    const double t = 2 * std::numbers::pi * static_cast<double>(i) / m;
    s.row(i) << 12 * std::cos(t) + 0.8 * std::cos(5 * t), 0.0, 9 * std::sin(t);
  }
  const FeatureCurve c = make_feature_curve("hem", s, true, FeaturePlane::from_point_normal(Vec3::Zero(), Vec3::UnitY()));
  const ShapeModel model = prepare_shape_model({c});
  // Every term wraps: nothing dropped at the "ends".
  for (std::size_t i = 0; i < m; ++i) EXPECT_TRUE(model.shapes[0].valid_plus[i] && model.shapes[0].valid_minus[i]);
  const FeatureResult r = match_shapes(model, {map_rows(c.samples, bend)}, {map_rows(c.aux, bend)},
                                       [](const Vec3& p) { return std::abs(p.z() - 9.0); });
  const CurveResult& cr = r.curves[0];
  EXPECT_TRUE(cr.closed);
  const double spacing = polyline_length(cr.optimised, true) / m;
  EXPECT_LT((cr.optimised.row(m - 1) - cr.optimised.row(0)).norm(), 2.0 * spacing);
  for (std::size_t i = 1; i < m; ++i) EXPECT_LT((cr.optimised.row(i) - cr.optimised.row(i - 1)).norm(), 2.0 * spacing);
  EXPECT_LT(cr.shape_error_result, cr.shape_error_warped);
  EXPECT_LT(cr.turning_angle_change_result_deg, cr.turning_angle_change_warped_deg);
}

TEST(ShapeMatching, OpenCurveWithFewerThanFiveSamplesIsRefused) {
  Points s(4, 3);
  s << 0, 0, 0, 1, 0, 0, 2, 1, 0, 3, 0, 0;
  try {
    make_feature_curve("short", s, false, plane_z0());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("feature 'short': 4 samples: an open curve needs at least 5 samples"),
              std::string::npos)
        << e.what();
  }
  FeatureCurve c;
  c.name = "short";
  c.samples = s;
  EXPECT_THROW(prepare_shape_model({c}), Error);
  // Closed curves need 3.
  EXPECT_NO_THROW(make_feature_curve("tri", s.topRows(3), true, plane_z0()));
}

TEST(ShapeMatching, ResultDoesNotDependOnThreadCount) {
  const FeatureCurve c = make_feature_curve("zigzag", zigzag(301, 6, 30.0, 2.0), false, plane_z0());
  const ShapeModel model = prepare_shape_model({c});
  auto run = [&](std::size_t threads) {
    ThreadLimit limit(threads);
    return match_shapes(model, {map_rows(c.samples, bend)}, {map_rows(c.aux, bend)},
                        [](const Vec3& p) { return p.norm(); });
  };
  const FeatureResult one = run(1), two = run(2);
  EXPECT_TRUE((one.curves[0].optimised.array() == two.curves[0].optimised.array()).all());
}
