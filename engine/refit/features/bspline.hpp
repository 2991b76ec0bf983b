#pragma once
// Uniform B-splines (paper section 4.1: feature curves are B-splines) and
// arc-length resampling of polylines.
#include <refit/core/types.hpp>

#include <algorithm>
#include <cstddef>

namespace refit {

/// A uniform B-spline of degree `degree` over the rows of `control`.
/// Open curves are clamped (they start at the first and end at the last
/// control point); closed curves are periodic (the control polygon wraps).
struct BSpline {
  int degree = 3;
  bool closed = false;
  Points control;  // n x 3, n >= degree + 1
};

/// Point at parameter t in [0, 1] (closed curves: t and t + 1 are the same point).
/// Throws refit::Error when the spline has fewer than degree + 1 control points
/// or a degree below 1.
Vec3 evaluate(const BSpline& spline, double t);

/// m points spaced uniformly by arc length (open: first and last are the curve's
/// ends; closed: the first point is not repeated). Arc length is measured on a
/// dense evaluation (at least 32 evaluations per output sample).
Points sample_by_arc_length(const BSpline& spline, std::size_t m);

/// Length of a polyline (closed: including the edge from the last row back to the first).
double polyline_length(const Points& polyline, bool closed);

/// The point of a polyline nearest to a query: on edge `segment` (from row
/// segment to row segment + 1, wrapping for closed polylines) at fraction t.
struct PolylinePoint {
  std::size_t segment = 0;
  double t = 0.0;
  double distance = 0.0;
  Vec3 point = Vec3::Zero();
  double param() const { return static_cast<double>(segment) + t; }
};

/// Closest point to q on the segment ab: parameter t in [0, 1] and the point.
struct SegmentPoint {
  double t = 0.0;
  Vec3 point = Vec3::Zero();
};
inline SegmentPoint closest_on_segment(const Vec3& q, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double dd = d.squaredNorm();
  const double t = dd > 0.0 ? std::clamp((q - a).dot(d) / dd, 0.0, 1.0) : 0.0;
  return {t, a + t * d};
}

/// Nearest point of a polyline (at least 1 row) to q; ties go to the first edge.
PolylinePoint nearest_on_polyline(const Points& polyline, bool closed, const Vec3& q);

/// The point at t (0..1) along segment `segment` of a polyline (a closed one's last wraps to row 0).
inline Vec3 point_on(const Points& polyline, std::size_t segment, double t) {
  const auto m = static_cast<std::size_t>(polyline.rows());
  return (1.0 - t) * row3(polyline, Index(segment)) + t * row3(polyline, Index((segment + 1) % m));
}

/// m points spaced uniformly by arc length along a polyline (closed: first not repeated).
/// Throws refit::Error when the polyline has fewer than 2 points or zero length.
Points resample_polyline(const Points& polyline, std::size_t m, bool closed);

/// Least-squares fit of a uniform B-spline with n control points to an ordered
/// polyline, chord-length parameters. Open fits keep the polyline's end points
/// (first and last control points are pinned to them). Throws refit::Error when
/// n < degree + 1 or the polyline is degenerate.
BSpline fit_bspline(const Points& polyline, std::size_t n, int degree, bool closed);

}  // namespace refit
