// B-splines, polyline helpers and curve metrics.
#include <refit/core/error.hpp>
#include <refit/features/bspline.hpp>
#include <refit/features/curve_metrics.hpp>

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

using namespace refit;

namespace {

Points circle_arc(std::size_t n, double radius, double a0, double a1) {
  Points p(static_cast<Eigen::Index>(n), 3);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = a0 + (a1 - a0) * static_cast<double>(i) / static_cast<double>(n - 1);
    p.row(static_cast<Eigen::Index>(i)) << radius * std::cos(a), radius * std::sin(a), 0.0;
  }
  return p;
}

}  // namespace

TEST(BSpline, OpenClampedStartsAndEndsAtItsEndControlPoints) {
  BSpline s;
  s.degree = 3;
  s.control.resize(5, 3);
  s.control << 0, 0, 0, 1, 2, 0, 2, -1, 0, 3, 2, 0, 4, 0, 1;
  EXPECT_LT((evaluate(s, 0.0) - row3(s.control, 0)).norm(), 1e-12);
  EXPECT_LT((evaluate(s, 1.0) - row3(s.control, 4)).norm(), 1e-12);
}

TEST(BSpline, DegreeOneIsThePolygon) {
  BSpline s;
  s.degree = 1;
  s.control.resize(3, 3);
  s.control << 0, 0, 0, 1, 0, 0, 1, 1, 0;
  EXPECT_LT((evaluate(s, 0.5) - Vec3(1, 0, 0)).norm(), 1e-12);
  EXPECT_LT((evaluate(s, 0.25) - Vec3(0.5, 0, 0)).norm(), 1e-12);
}

TEST(BSpline, ClosedWrapsAndIsSmooth) {
  BSpline s;
  s.degree = 3;
  s.closed = true;
  s.control.resize(8, 3);
  for (int i = 0; i < 8; ++i) s.control.row(i) << std::cos(i * std::numbers::pi / 4), std::sin(i * std::numbers::pi / 4), 0;
  EXPECT_LT((evaluate(s, 0.0) - evaluate(s, 1.0)).norm(), 1e-12);
  // Uniform periodic spline of a regular octagon: a near-circle, equal radii at the knots.
  const double r0 = evaluate(s, 0.0).norm();
  for (int i = 1; i < 8; ++i) EXPECT_NEAR(evaluate(s, i / 8.0).norm(), r0, 1e-12);
}

TEST(BSpline, ArcLengthSamplesAreEquallySpaced) {
  BSpline s;
  s.degree = 3;
  s.control.resize(6, 3);
  s.control << 0, 0, 0, 2, 1, 0, 4, 0, 0, 6, 1, 0, 8, 0, 0, 10, 1, 1;
  const Points p = sample_by_arc_length(s, 50);
  ASSERT_EQ(p.rows(), 50);
  EXPECT_LT((row3(p, 0) - row3(s.control, 0)).norm(), 1e-12);
  EXPECT_LT((row3(p, 49) - row3(s.control, 5)).norm(), 1e-12);
  const double mean = polyline_length(p, false) / 49;
  for (int i = 1; i < 50; ++i) EXPECT_NEAR((p.row(i) - p.row(i - 1)).norm(), mean, 0.01 * mean);
}

TEST(BSpline, ResampleAndNearestOnPolyline) {
  Points sq(4, 3);
  sq << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  EXPECT_DOUBLE_EQ(polyline_length(sq, true), 4.0);
  EXPECT_DOUBLE_EQ(polyline_length(sq, false), 3.0);
  const Points r = resample_polyline(sq, 8, true);
  EXPECT_LT((row3(r, 1) - Vec3(0.5, 0, 0)).norm(), 1e-12);
  EXPECT_LT((row3(r, 7) - Vec3(0, 0.5, 0)).norm(), 1e-12);
  const PolylinePoint q = nearest_on_polyline(sq, true, Vec3(-1, 0.25, 0));
  EXPECT_EQ(q.segment, 3u);
  EXPECT_NEAR(q.t, 0.75, 1e-12);
  EXPECT_NEAR(q.distance, 1.0, 1e-12);
}

TEST(BSpline, LeastSquaresFitFollowsAnArc) {
  const Points arc = circle_arc(200, 10.0, 0.0, 2.0);
  const BSpline s = fit_bspline(arc, 10, 3, false);
  EXPECT_LT((row3(s.control, 0) - row3(arc, 0)).norm(), 1e-12);  // ends kept
  EXPECT_LT((row3(s.control, 9) - row3(arc, 199)).norm(), 1e-12);
  const Points p = sample_by_arc_length(s, 100);
  for (int i = 0; i < 100; ++i) EXPECT_NEAR(row3(p, i).norm(), 10.0, 1e-3);
  EXPECT_NEAR(polyline_length(p, false), 20.0, 0.01);
}

TEST(BSpline, ClosedFitOfACircle) {
  Points c = circle_arc(101, 5.0, 0.0, 2 * std::numbers::pi);
  c.conservativeResize(100, 3);  // drop the repeated start
  const BSpline s = fit_bspline(c, 12, 3, true);
  const Points p = sample_by_arc_length(s, 64);
  for (int i = 0; i < 64; ++i) EXPECT_NEAR(row3(p, i).norm(), 5.0, 2.5e-3);  // 12 control points: 0.05% of the radius
}

TEST(BSpline, TooFewControlPointsAreRefused) {
  BSpline s;
  s.degree = 3;
  s.control.resize(3, 3);
  s.control.setRandom();
  try {
    evaluate(s, 0.5);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("at least 4"), std::string::npos) << e.what();
  }
  EXPECT_THROW(fit_bspline(circle_arc(20, 1, 0, 1), 2, 3, false), Error);
}

TEST(CurveMetrics, SimilarCopyHasNoErrorAndDistortionHasSome) {
  const Points a = circle_arc(30, 4.0, 0.0, 2.5);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Points b = ((2.5 * a * R.transpose()).rowwise() + Eigen::RowVector3d(3, -1, 7)).eval();
  EXPECT_LT(shape_error(b, a, false), 1e-12);
  EXPECT_LT(turning_angle_change_deg(b, a, false), 1e-9);
  Points c = a;
  c.col(1) *= 2.0;  // non-uniform scaling changes the shape
  EXPECT_GT(shape_error(c, a, false), 1e-3);
  EXPECT_GT(turning_angle_change_deg(c, a, false), 0.1);
  EXPECT_THROW(shape_error(a.topRows(10), a, false), Error);
}
