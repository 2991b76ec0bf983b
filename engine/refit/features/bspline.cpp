#include <refit/features/bspline.hpp>

#include <refit/core/error.hpp>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace refit {
namespace {

// Knot vector and the control point behind each basis function: open curves are
// clamped on [0, 1]; closed curves use integer knots with the control polygon
// wrapped p times, domain [p, n + p].
struct Knots {
  std::vector<double> u;
  std::size_t count = 0;  // number of basis functions
  double lo = 0.0, hi = 1.0;
  int p = 3;
  bool closed = false;
  std::size_t n = 0;  // control points
  std::size_t control(std::size_t j) const { return closed ? j % n : j; }
  double param(double t) const {
    if (closed) {
      t -= std::floor(t);
      return lo + t * (hi - lo);
    }
    return lo + std::clamp(t, 0.0, 1.0) * (hi - lo);
  }
};

Knots make_knots(std::size_t n, int p, bool closed) {
  if (p < 1) throw Error("B-spline: degree must be at least 1, got " + std::to_string(p));
  if (n < static_cast<std::size_t>(p) + 1)
    throw Error("B-spline: " + std::to_string(n) + " control points are too few for degree " + std::to_string(p) +
                " (need at least " + std::to_string(p + 1) + ")");
  Knots k;
  k.p = p;
  k.closed = closed;
  k.n = n;
  if (closed) {
    k.count = n + static_cast<std::size_t>(p);
    for (std::size_t i = 0; i <= k.count + static_cast<std::size_t>(p); ++i) k.u.push_back(static_cast<double>(i));
    k.lo = p;
    k.hi = static_cast<double>(n + p);
  } else {
    k.count = n;
    const std::size_t inner = n - static_cast<std::size_t>(p);
    for (int i = 0; i <= p; ++i) k.u.push_back(0.0);
    for (std::size_t i = 1; i < inner; ++i) k.u.push_back(static_cast<double>(i) / static_cast<double>(inner));
    for (int i = 0; i <= p; ++i) k.u.push_back(1.0);
    k.lo = 0.0;
    k.hi = 1.0;
  }
  return k;
}

// The p + 1 non-zero basis functions at u (The NURBS Book, A2.1 + A2.2); returns
// the index of the first of them.
std::size_t basis(const Knots& k, double u, double* N) {
  const int p = k.p;
  std::size_t span = static_cast<std::size_t>(p);
  const std::size_t last = k.count - 1;
  if (u >= k.u[last + 1]) {
    span = last;
  } else {
    auto it = std::upper_bound(k.u.begin() + p, k.u.begin() + static_cast<long>(last) + 1, u);
    span = static_cast<std::size_t>(it - k.u.begin()) - 1;
  }
  double left[16], right[16];
  N[0] = 1.0;
  for (int j = 1; j <= p; ++j) {
    left[j] = u - k.u[span + 1 - static_cast<std::size_t>(j)];
    right[j] = k.u[span + static_cast<std::size_t>(j)] - u;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      const double tmp = N[r] / (right[r + 1] + left[j - r]);
      N[r] = saved + right[r + 1] * tmp;
      saved = left[j - r] * tmp;
    }
    N[j] = saved;
  }
  return span - static_cast<std::size_t>(p);
}

void check_degree(int p) {
  if (p < 1 || p > 15) throw Error("B-spline: degree must be between 1 and 15, got " + std::to_string(p));
}

}  // namespace

Vec3 evaluate(const BSpline& s, double t) {
  check_degree(s.degree);
  const Knots k = make_knots(static_cast<std::size_t>(s.control.rows()), s.degree, s.closed);
  double N[16];
  const std::size_t first = basis(k, k.param(t), N);
  Vec3 p = Vec3::Zero();
  for (int r = 0; r <= s.degree; ++r) p += N[r] * row3(s.control, static_cast<Index>(k.control(first + r)));
  return p;
}

double polyline_length(const Points& poly, bool closed) {
  double len = 0.0;
  const Eigen::Index n = poly.rows();
  for (Eigen::Index i = 1; i < n; ++i) len += (poly.row(i) - poly.row(i - 1)).norm();
  if (closed && n > 2) len += (poly.row(0) - poly.row(n - 1)).norm();
  return len;
}

PolylinePoint nearest_on_polyline(const Points& poly, bool closed, const Vec3& q) {
  const std::size_t n = static_cast<std::size_t>(poly.rows());
  PolylinePoint best;
  best.distance = std::numeric_limits<double>::infinity();
  if (n == 0) return best;
  if (n == 1) {
    best.point = row3(poly, 0);
    best.distance = (best.point - q).norm();
    return best;
  }
  const std::size_t edges = closed ? n : n - 1;
  double best2 = std::numeric_limits<double>::infinity();
  for (std::size_t e = 0; e < edges; ++e) {
    const auto [t, p] = closest_on_segment(q, row3(poly, static_cast<Index>(e)), row3(poly, static_cast<Index>((e + 1) % n)));
    const double d2 = (p - q).squaredNorm();
    if (d2 < best2) {
      best2 = d2;
      best.segment = e;
      best.t = t;
      best.point = p;
    }
  }
  best.distance = std::sqrt(best2);
  return best;
}

Points resample_polyline(const Points& poly, std::size_t m, bool closed) {
  const std::size_t n = static_cast<std::size_t>(poly.rows());
  if (n < 2) throw Error("resample: a polyline needs at least 2 points, got " + std::to_string(n));
  if (m < 2) throw Error("resample: need at least 2 samples");
  // Walk the edges once; closing edge last for closed curves.
  const std::size_t edges = closed ? n : n - 1;
  std::vector<double> cum(edges + 1, 0.0);
  for (std::size_t e = 0; e < edges; ++e)
    cum[e + 1] = cum[e] + (poly.row(static_cast<Eigen::Index>((e + 1) % n)) - poly.row(static_cast<Eigen::Index>(e))).norm();
  const double total = cum[edges];
  if (!(total > 0.0) || !std::isfinite(total)) throw Error("resample: the polyline has zero or non-finite length");
  Points out(static_cast<Eigen::Index>(m), 3);
  const double step = total / static_cast<double>(closed ? m : m - 1);
  std::size_t e = 0;
  for (std::size_t j = 0; j < m; ++j) {
    const double s = (!closed && j + 1 == m) ? total : step * static_cast<double>(j);
    while (e + 1 < edges && cum[e + 1] < s) ++e;
    const double len = cum[e + 1] - cum[e];
    const double t = len > 0.0 ? std::clamp((s - cum[e]) / len, 0.0, 1.0) : 0.0;
    const auto a = poly.row(static_cast<Eigen::Index>(e));
    const auto b = poly.row(static_cast<Eigen::Index>((e + 1) % n));
    out.row(static_cast<Eigen::Index>(j)) = (1.0 - t) * a + t * b;
  }
  return out;
}

Points sample_by_arc_length(const BSpline& s, std::size_t m) {
  check_degree(s.degree);
  const Knots k = make_knots(static_cast<std::size_t>(s.control.rows()), s.degree, s.closed);
  const std::size_t dense = std::max<std::size_t>(1024, 32 * m);
  const std::size_t rows = s.closed ? dense : dense + 1;
  Points poly(static_cast<Eigen::Index>(rows), 3);
  double N[16];
  for (std::size_t i = 0; i < rows; ++i) {
    const double t = static_cast<double>(i) / static_cast<double>(dense);
    const std::size_t first = basis(k, k.param(t), N);
    Vec3 p = Vec3::Zero();
    for (int r = 0; r <= s.degree; ++r) p += N[r] * row3(s.control, static_cast<Index>(k.control(first + r)));
    poly.row(static_cast<Eigen::Index>(i)) = p.transpose();
  }
  return resample_polyline(poly, m, s.closed);
}

BSpline fit_bspline(const Points& polyline, std::size_t n, int degree, bool closed) {
  check_degree(degree);
  const Knots k = make_knots(n, degree, closed);
  if (polyline.rows() < 2) throw Error("B-spline fit: the polyline has fewer than 2 points");
  // Dense enough data that every control point is supported; chord-length
  // parameters then follow from the sample index.
  const std::size_t count = std::max<std::size_t>(static_cast<std::size_t>(polyline.rows()), 8 * n + 16);
  const Points data = resample_polyline(polyline, count, closed);
  std::vector<double> t(count);
  {
    double acc = 0.0;
    t[0] = 0.0;
    for (std::size_t i = 1; i < count; ++i) {
      acc += (data.row(static_cast<Eigen::Index>(i)) - data.row(static_cast<Eigen::Index>(i - 1))).norm();
      t[i] = acc;
    }
    const double total = closed ? acc + (data.row(0) - data.row(static_cast<Eigen::Index>(count - 1))).norm() : acc;
    for (double& v : t) v /= total;
  }
  // Normal equations of the n unknown control points (banded, small: dense LDLT).
  Eigen::MatrixXd AtA = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  Eigen::MatrixXd Atb = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), 3);
  double N[16];
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t first = basis(k, k.param(t[i]), N);
    for (int a = 0; a <= degree; ++a) {
      const auto ca = static_cast<Eigen::Index>(k.control(first + a));
      Atb.row(ca) += N[a] * data.row(static_cast<Eigen::Index>(i));
      for (int b = 0; b <= degree; ++b) AtA(ca, static_cast<Eigen::Index>(k.control(first + b))) += N[a] * N[b];
    }
  }
  BSpline out;
  out.degree = degree;
  out.closed = closed;
  out.control.resize(static_cast<Eigen::Index>(n), 3);
  if (!closed) {
    // Pin the ends: move their known contribution to the right-hand side.
    const Eigen::Index last = static_cast<Eigen::Index>(n) - 1;
    const Eigen::RowVector3d p0 = data.row(0), p1 = data.row(static_cast<Eigen::Index>(count - 1));
    out.control.row(0) = p0;
    out.control.row(last) = p1;
    if (n > 2) {
      const Eigen::Index inner = last - 1;
      Eigen::MatrixXd rhs = Atb.middleRows(1, inner) - AtA.block(1, 0, inner, 1) * p0 - AtA.block(1, last, inner, 1) * p1;
      out.control.middleRows(1, inner) = AtA.block(1, 1, inner, inner).ldlt().solve(rhs);
    }
  } else {
    out.control = AtA.ldlt().solve(Atb);
  }
  if (!out.control.allFinite()) throw Error("B-spline fit: the fit has no unique solution (degenerate polyline)");
  return out;
}

}  // namespace refit
