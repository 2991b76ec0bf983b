#include <refit/core/parallel.hpp>
#include <refit/surface/clearance.hpp>

#include <limits>
#include <numeric>

namespace refit {

Vec3 clear_point(const std::function<double(const Vec3&)>& distance, double clearance, double step, Vec3 p,
                 const Vec3& fallback) {
  const double c = clearance;
  const Vec3& w = fallback;
  for (int k = 0; k < 4; ++k) {
    const double d = distance(p);
    if (d >= c && d < c + 1e-3 * step) return p;
    Vec3 g;
    for (int i = 0; i < 3; ++i) {
      Vec3 e = Vec3::Zero();
      e[i] = step;
      g[i] = (distance(p + e) - distance(p - e)) / (2.0 * step);
    }
    if (!(g.squaredNorm() > 0.25)) break;
    p += ((c - d) / g.squaredNorm()) * g;
  }
  if (distance(p) >= c) return p;
  double lo = 0.0, hi = 1.0;
  for (int k = 0; k < 16; ++k) {
    const double mid = 0.5 * (lo + hi);
    (distance(p + mid * (w - p)) >= c ? hi : lo) = mid;
  }
  return p + hi * (w - p);
}

std::size_t hold_clear_of_body(const std::function<double(const Vec3&)>& distance, double clearance, double step,
                               const std::vector<std::uint8_t>& free, const Points& warped, Points& x,
                               std::vector<std::uint8_t>& fixed) {
  const std::size_t n = free.size();
  std::vector<std::uint8_t> pin(n, 0);
  parallel_for(0, n, 256, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      if (!free[a]) continue;
      const Vec3 p = row3(x, Index(a));
      if (distance(p) >= clearance) continue;
      pin[a] = 1;
      x.row(Eigen::Index(a)) = clear_point(distance, clearance, step, p, row3(warped, Index(a))).transpose();
    }
  });
  const std::size_t added = std::accumulate(pin.begin(), pin.end(), std::size_t{0});
  for (std::size_t a = 0; a < n; ++a)
    if (pin[a]) fixed[a] = 3;
  return added;
}

namespace {

// The point nearest p (farther than `ceiling` from body B) at that distance.
Vec3 point_within(const std::function<double(const Vec3&)>& distance, double ceiling, double step, Vec3 p,
                  const Vec3& fallback) {
  for (int k = 0; k < 4; ++k) {
    const double d = distance(p);
    if (d <= ceiling && d > ceiling - 1e-3 * step) return p;
    Vec3 g;
    for (int i = 0; i < 3; ++i) {
      Vec3 e = Vec3::Zero();
      e[i] = step;
      g[i] = (distance(p + e) - distance(p - e)) / (2.0 * step);
    }
    if (!(g.squaredNorm() > 0.25)) break;
    p += ((ceiling - d) / g.squaredNorm()) * g;
  }
  if (distance(p) <= ceiling) return p;
  double lo = 0.0, hi = 1.0;
  for (int k = 0; k < 16; ++k) {
    const double mid = 0.5 * (lo + hi);
    (distance(p + mid * (fallback - p)) <= ceiling ? hi : lo) = mid;
  }
  return p + hi * (fallback - p);
}

}  // namespace

std::size_t hold_near_body(const std::function<double(const Vec3&)>& distance, const std::vector<double>& ceiling,
                           double step, const std::vector<std::uint8_t>& free, const Points& warped, Points& x,
                           std::vector<std::uint8_t>& fixed) {
  const std::size_t n = free.size();
  std::vector<std::uint8_t> pin(n, 0);
  parallel_for(0, n, 256, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      if (!free[a] || !(ceiling[a] < std::numeric_limits<double>::infinity())) continue;
      const Vec3 p = row3(x, Index(a));
      if (distance(p) <= ceiling[a]) continue;
      pin[a] = 1;
      x.row(Eigen::Index(a)) = point_within(distance, ceiling[a], step, p, row3(warped, Index(a))).transpose();
    }
  });
  const std::size_t added = std::accumulate(pin.begin(), pin.end(), std::size_t{0});
  for (std::size_t a = 0; a < n; ++a)
    if (pin[a]) fixed[a] = 4;
  return added;
}

}  // namespace refit
