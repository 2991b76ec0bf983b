#include <refit/core/parallel.hpp>
#include <refit/surface/clearance.hpp>

#include <cmath>
#include <numeric>

namespace refit {

namespace {

// The point nearest p at distance `target` from body B, approached from the side
// `above` says (at least target: clear_point; at most: hold_near_body): Newton
// steps along the distance's gradient (central differences of width `step`);
// where they fail, the point on the way from p back to `fallback` on that side.
Vec3 point_at_distance(const std::function<double(const Vec3&)>& distance, double target, bool above, double step,
                       Vec3 p, const Vec3& fallback) {
  const auto on_side = [&](double d) { return above ? d >= target : d <= target; };
  // The steps aim at the middle of the band they accept, not at its edge: where
  // the distance grows slower than linearly (in a crease of the body) they
  // approach the target from one side and ended a rounding error short of it,
  // and then the fallback below took over (an agent of the shared skirt on
  // F_thinner went to its warped place, 0.8 cm away and inside the clearance,
  // or not, as the solve's tolerance went from 1e-8 to 1e-10).
  const double band = 1e-3 * step, aim = above ? target + 0.5 * band : target - 0.5 * band;
  for (int k = 0; k < 4; ++k) {
    const double d = distance(p);
    if (on_side(d) && (above ? d < target + band : d > target - band)) return p;
    Vec3 g;
    for (int i = 0; i < 3; ++i) {
      Vec3 e = Vec3::Zero();
      e[i] = step;
      g[i] = (distance(p + e) - distance(p - e)) / (2.0 * step);
    }
    if (!(g.squaredNorm() > 0.25)) break;
    p += ((aim - d) / g.squaredNorm()) * g;
  }
  if (on_side(distance(p))) return p;
  double lo = 0.0, hi = 1.0;
  for (int k = 0; k < 16; ++k) {
    const double mid = 0.5 * (lo + hi);
    (on_side(distance(p + mid * (fallback - p))) ? hi : lo) = mid;
  }
  return p + hi * (fallback - p);
}

}  // namespace

Vec3 clear_point(const std::function<double(const Vec3&)>& distance, double clearance, double step, Vec3 p,
                 const Vec3& fallback) {
  return point_at_distance(distance, clearance, true, step, p, fallback);
}

namespace {

// Moves every free agent on the wrong side of its target distance (target(a):
// at least it when `above`, at most otherwise; infinite: none) to
// point_at_distance, marks it fixed[a] = code and returns how many it moved.
template <class Target>
std::size_t hold_at_distance(const std::function<double(const Vec3&)>& distance, const Target& target, bool above,
                             std::uint8_t code, double step, const std::vector<std::uint8_t>& free,
                             const Points& warped, Points& x, std::vector<std::uint8_t>& fixed) {
  const std::size_t n = free.size();
  std::vector<std::uint8_t> pin(n, 0);
  parallel_for(0, n, 256, [&](std::size_t b, std::size_t e) {
    for (std::size_t a = b; a < e; ++a) {
      const double t = target(a);
      if (!free[a] || !std::isfinite(t)) continue;
      const Vec3 p = row3(x, Index(a));
      const double d = distance(p);
      if (above ? d >= t : d <= t) continue;
      pin[a] = 1;
      x.row(Eigen::Index(a)) = point_at_distance(distance, t, above, step, p, row3(warped, Index(a))).transpose();
    }
  });
  const std::size_t added = std::accumulate(pin.begin(), pin.end(), std::size_t{0});
  for (std::size_t a = 0; a < n; ++a)
    if (pin[a]) fixed[a] = code;
  return added;
}

}  // namespace

std::size_t hold_clear_of_body(const std::function<double(const Vec3&)>& distance, double clearance, double step,
                               const std::vector<std::uint8_t>& free, const Points& warped, Points& x,
                               std::vector<std::uint8_t>& fixed) {
  return hold_at_distance(distance, [clearance](std::size_t) { return clearance; }, true, 3, step, free, warped, x,
                          fixed);
}

std::size_t hold_near_body(const std::function<double(const Vec3&)>& distance, const std::vector<double>& ceiling,
                           double step, const std::vector<std::uint8_t>& free, const Points& warped, Points& x,
                           std::vector<std::uint8_t>& fixed) {
  return hold_at_distance(distance, [&ceiling](std::size_t a) { return ceiling[a]; }, false, 4, step, free, warped, x,
                          fixed);
}

}  // namespace refit
