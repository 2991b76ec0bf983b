// The procedural mannequin: an analytic shape (profile keys along the height)
// sampled into five closed tubes.
#include "mannequin/mannequin.hpp"
#include "mannequin/shape_math.hpp"

#include <refit/core/error.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numbers>

namespace refit::mannequin {
namespace {


/// Perimeter of the ellipse with half axes 1 and k (Ramanujan; error < 1e-4 here).
double unit_ellipse_perimeter(double k) {
  return kPi * (3.0 * (1.0 + k) - std::sqrt((3.0 + k) * (1.0 + 3.0 * k)));
}

/// Half width a of a section made of two half ellipses (depth kf*a in front,
/// kb*a behind) whose perimeter is `girth`.
double half_width_for_girth(double girth, double kf, double kb) {
  return 2.0 * girth / (unit_ellipse_perimeter(kf) + unit_ellipse_perimeter(kb));
}

/// Rounded end: 1 away from the end, falling like a quarter circle to 0 at the
/// end over `length`.
double cap_factor(double distance_from_end, double length) {
  if (distance_from_end <= 0) return 0.0;
  if (distance_from_end >= length) return 1.0;
  const double t = 1.0 - distance_from_end / length;
  return std::sqrt(std::max(0.0, 1.0 - t * t));
}

void check_range(const char* name, double v, double lo, double hi) {
  if (!std::isfinite(v) || v < lo || v > hi)
    throw input_error("mannequin", std::string(name) + " = " + std::to_string(v) + " is outside " +
                                       std::to_string(lo) + " .. " + std::to_string(hi));
}

// Arm layout (fixed proportions): tilt from the vertical and gap to the torso.
constexpr double kArmTilt = 20.0 * kPi / 180.0;
constexpr double kArmGap = 3.0;

// Ring counts at resolution 1 (about 26k triangles in all).
constexpr int kTorsoRings = 90, kTorsoSegments = 64;
constexpr int kLegRings = 76, kLegSegments = 32;
constexpr int kArmRings = 52, kArmSegments = 24;

/// Parameters in [0, 1] of `rings` rings spaced evenly along the arc length of a
/// profile curve, ends excluded (they are the poles). profile(t) gives the
/// curve point (axial position, radius 1, radius 2); the arc length used is the
/// mean of the two radius profiles' lengths.
std::vector<double> rings_by_arc_length(int rings, const std::function<std::array<double, 3>(double)>& profile) {
  constexpr int kSamples = 4000;
  std::vector<double> cum(kSamples + 1, 0.0);
  std::array<double, 3> prev = profile(0.0);
  for (int i = 1; i <= kSamples; ++i) {
    const std::array<double, 3> cur = profile(static_cast<double>(i) / kSamples);
    const double dy = cur[0] - prev[0];
    const double l1 = std::hypot(dy, cur[1] - prev[1]), l2 = std::hypot(dy, cur[2] - prev[2]);
    cum[i] = cum[i - 1] + 0.5 * (l1 + l2);
    prev = cur;
  }
  std::vector<double> t(static_cast<std::size_t>(rings));
  std::size_t j = 0;
  for (int r = 0; r < rings; ++r) {
    const double target = cum.back() * (r + 1) / (rings + 1);
    while (j + 1 < cum.size() && cum[j + 1] < target) ++j;
    const double span = cum[j + 1] - cum[j];
    const double f = span > 0 ? (target - cum[j]) / span : 0.0;
    t[static_cast<std::size_t>(r)] = (static_cast<double>(j) + f) / kSamples;
  }
  return t;
}

/// Appends a closed tube: pole0, rings x segments, pole1. ring(i, k) is ring
/// i's point k; rings run along the tube axis t and points turn so that
/// (radial, turning direction, t) is right-handed, which makes these triangles
/// face outward.
void add_tube(BodyMesh& m, std::vector<Vec3>& v, int rings, int segments, const Vec3& pole0, const Vec3& pole1,
              const std::function<Vec3(int, int)>& ring) {
  const Index base = static_cast<Index>(v.size());
  v.push_back(pole0);
  for (int i = 0; i < rings; ++i)
    for (int k = 0; k < segments; ++k) v.push_back(ring(i, k));
  v.push_back(pole1);
  const Index top = static_cast<Index>(v.size() - 1);
  const auto at = [&](int i, int k) { return base + 1 + static_cast<Index>(i * segments + (k % segments)); };
  for (int k = 0; k < segments; ++k) m.triangles.push_back({base, at(0, k + 1), at(0, k)});
  for (int i = 0; i + 1 < rings; ++i)
    for (int k = 0; k < segments; ++k) {
      m.triangles.push_back({at(i, k), at(i, k + 1), at(i + 1, k + 1)});
      m.triangles.push_back({at(i, k), at(i + 1, k + 1), at(i + 1, k)});
    }
  for (int k = 0; k < segments; ++k) m.triangles.push_back({top, at(rings - 1, k), at(rings - 1, k + 1)});
}

/// Arm profile along the axis from the shoulder (d = 0) to the fingertips
/// (d = length): radius across (in the arm's plane) and radius front-back.
struct ArmModel {
  double length = 0, cap_top = 0, cap_bottom = 0, scale = 1;
  std::array<double, 3> at(double d) const {
    // d / length, r_across, r_depth
    static constexpr std::array<std::array<double, 3>, 7> keys{{{0.0, 4.0, 4.2},
                                                                 {0.12, 4.6, 4.8},
                                                                 {0.40, 3.4, 3.6},
                                                                 {0.52, 3.8, 4.0},
                                                                 {0.74, 2.3, 2.8},
                                                                 {0.86, 1.6, 4.4},
                                                                 {1.0, 1.2, 3.5}}};
    const double f = std::clamp(d / length, 0.0, 1.0);
    std::size_t j = 0;
    while (j + 2 < keys.size() && keys[j + 1][0] < f) ++j;
    const double s = smoothstep((f - keys[j][0]) / (keys[j + 1][0] - keys[j][0]));
    const double cap = cap_factor(d, cap_top) * cap_factor(length - d, cap_bottom);
    const double across = (keys[j][1] + s * (keys[j + 1][1] - keys[j][1])) * scale * cap;
    const double depth = (keys[j][2] + s * (keys[j + 1][2] - keys[j][2])) * scale * cap;
    return {d, across, depth};
  }
};

}  // namespace

void check_params(const BodyParams& p) {
  check_range("height", p.height, 100, 250);
  check_range("bust", p.bust, 30, 250);
  check_range("waist", p.waist, 30, 250);
  check_range("hip", p.hip, 30, 250);
  check_range("belly", p.belly, 0, 40);
  check_range("shoulder", p.shoulder, 20, 70);
  if (p.resolution < 1 || p.resolution > 8)
    throw input_error("mannequin", "resolution = " + std::to_string(p.resolution) + " is outside 1 .. 8");
  if (p.waist > p.hip + 40 || p.waist > p.bust + 40)
    throw input_error("mannequin", "waist is more than 40 cm above hip or bust: no sane torso");
}

Landmarks landmarks(const BodyParams& p) { return BodyShape(p).levels(); }

void BodyShape::interpolate(const std::vector<Key>& keys, double y, double out[4]) {
  std::size_t j = 0;
  while (j + 2 < keys.size() && keys[j + 1].y < y) ++j;
  const Key& k0 = keys[j];
  const Key& k1 = keys[j + 1];
  const double s = smoothstep((y - k0.y) / (k1.y - k0.y));
  for (int c = 0; c < 4; ++c) out[c] = k0.v[c] + s * (k1.v[c] - k0.v[c]);
}

BodyShape::BodyShape(const BodyParams& p) : params_(p) {
  check_params(p);
  const double H = p.height, s = H / 165.0;
  Landmarks& L = levels_;
  L.height = H;
  L.ankle = 0.045 * H;
  L.knee = 0.285 * H;
  L.crotch = 0.47 * H;
  L.hip = 0.52 * H;
  L.navel = 0.60 * H;
  L.waist = 0.625 * H;
  L.bust = 0.72 * H;
  L.armpit = 0.745 * H;
  L.shoulder = 0.815 * H;
  L.neck = 0.845 * H;
  navel_sigma_ = 0.045 * H;

  // Torso: a, front depth, back depth. Girth levels get the measured perimeter.
  const auto girth_key = [](double y, double girth, double kf, double kb) {
    const double a = half_width_for_girth(girth, kf, kb);
    return Key{y, {a, kf * a, kb * a, 0}};
  };
  const double sh = 0.5 * p.shoulder;
  torso_keys_ = {girth_key(L.crotch, 0.93 * p.hip, 0.60, 0.80),
                 girth_key(L.hip, p.hip, 0.62, 0.82),
                 girth_key(L.waist, p.waist, 0.75, 0.70),
                 girth_key(L.bust, p.bust, 0.80, 0.62),
                 girth_key(L.armpit, 0.96 * p.bust, 0.68, 0.62),
                 Key{L.shoulder, {sh, 0.36 * sh, 0.36 * sh, 0}},
                 Key{L.neck, {6.2 * s, 5.8 * s, 5.8 * s, 0}},
                 Key{0.87 * H, {5.4 * s, 5.6 * s, 5.6 * s, 0}},
                 Key{0.89 * H, {6.5 * s, 8.5 * s, 8.5 * s, 0}},
                 Key{0.94 * H, {7.8 * s, 9.8 * s, 9.8 * s, 0}},
                 Key{H, {7.0 * s, 8.5 * s, 8.5 * s, 0}}};
  torso_cap_bottom_ = 4.0 * s;
  torso_cap_top_ = 7.0 * s;

  // Legs: centre x, centre z, rx, rz. The thighs fit side by side under the hip
  // with a 3 cm gap between them (so trousers have room for their crotch seam).
  const double a_hip = half_width_for_girth(p.hip, 0.62, 0.82);
  const double thigh = std::max(3.0, (0.95 * a_hip - 1.5) / 2.0);
  const double xc_top = thigh + 1.5;
  const double lg = std::pow(p.hip / 96.0, 0.7) * std::sqrt(s);
  const double knee_r = 5.0 * lg;
  // Below the thighs the legs stand apart (knees and calves 6 cm or more
  // apart), so a leg of trousers, or of a second layer over them, has room.
  const double xc_knee = std::max(0.9 * xc_top, knee_r + 3.5);
  leg_top_ = L.crotch - 0.8 * s;
  leg_cap_top_ = 3.0 * s;
  leg_cap_bottom_ = 1.2 * s;
  leg_keys_ = {Key{0.0, {xc_knee, 3.5 * s, 3.9 * lg, 8.0 * s}},
               Key{0.015 * H, {xc_knee, 3.5 * s, 3.9 * lg, 8.0 * s}},
               Key{0.05 * H, {xc_knee, -0.5 * s, 3.2 * lg, 3.4 * lg}},
               Key{0.20 * H, {xc_knee, -1.0 * s, 5.2 * lg, 5.8 * lg}},
               Key{L.knee, {xc_knee, 0.0, knee_r, 5.3 * lg}},
               Key{0.40 * H, {0.5 * (xc_top + xc_knee), 0.0, 0.82 * thigh, 0.82 * 1.15 * thigh}},
               Key{leg_top_, {xc_top, -0.5 * s, thigh, 1.15 * thigh}}};
}

BodyShape::TorsoSection BodyShape::torso(double y) const {
  if (y <= levels_.crotch || y >= levels_.height) return {};
  double v[4];
  interpolate(torso_keys_, y, v);
  const double cap = cap_factor(y - levels_.crotch, torso_cap_bottom_) * cap_factor(levels_.height - y, torso_cap_top_);
  const double d = (y - levels_.navel) / navel_sigma_;
  return {v[0] * cap, v[1] * cap, v[2] * cap, params_.belly * std::exp(-d * d)};
}

double BodyShape::radius(const TorsoSection& s, double c, double sn) {
  if (s.a <= 0) return 0.0;
  const double b = sn >= 0 ? s.bf : s.bb;
  const double r = s.a * b / std::sqrt((b * c) * (b * c) + (s.a * sn) * (s.a * sn));
  const double front = std::max(0.0, sn);
  return r + s.bump * front * front * front;
}

BodyShape::LegSection BodyShape::leg(double y) const {
  if (y <= 0 || y >= leg_top_) return {};
  double v[4];
  interpolate(leg_keys_, y, v);
  const double cap = cap_factor(leg_top_ - y, leg_cap_top_) * cap_factor(y, leg_cap_bottom_);
  return {v[0], v[1], v[2] * cap, v[3] * cap};
}

double BodyShape::extent(double y, double c, double sn) const {
  double r = radius(torso(y), c, sn);
  const LegSection l = leg(y);
  if (l.rx > 0) {
    for (double side : {1.0, -1.0}) {
      // Far intersection of the ray t*(c, sn) with the leg ellipse.
      const double xc = side * l.xc;
      const double A = (c / l.rx) * (c / l.rx) + (sn / l.rz) * (sn / l.rz);
      const double B = -2.0 * (c * xc / (l.rx * l.rx) + sn * l.zc / (l.rz * l.rz));
      const double C = (xc / l.rx) * (xc / l.rx) + (l.zc / l.rz) * (l.zc / l.rz) - 1.0;
      const double disc = B * B - 4 * A * C;
      if (disc >= 0) r = std::max(r, (-B + std::sqrt(disc)) / (2 * A));
    }
  }
  return r;
}

BodyMesh make_body(const BodyParams& p) {
  const BodyShape shape(p);
  const Landmarks& L = shape.levels();
  const int res = p.resolution;
  const double s = p.height / 165.0;
  BodyMesh m;
  m.name = "mannequin";
  std::vector<Vec3> v;

  // Ring point k turns from the front (+z) towards the left (+x): with rings
  // going up (+y) that is right-handed, so the tube faces outward.
  const auto ring_dir = [](int k, int segments) {
    const double psi = 2.0 * kPi * k / segments;
    return std::array<double, 2>{std::sin(psi), std::cos(psi)};  // (x, z) = (cos phi, sin phi)
  };

  // Torso, neck and head.
  {
    const int rings = kTorsoRings * res, seg = kTorsoSegments * res;
    const double y0 = L.crotch, y1 = L.height;
    const auto ts = rings_by_arc_length(rings, [&](double t) {
      const double y = y0 + t * (y1 - y0);
      const auto sec = shape.torso(y);
      return std::array<double, 3>{y, sec.a, sec.bf + sec.bump};
    });
    add_tube(m, v, rings, seg, Vec3(0, y0, 0), Vec3(0, y1, 0), [&](int i, int k) {
      const double y = y0 + ts[static_cast<std::size_t>(i)] * (y1 - y0);
      const auto sec = shape.torso(y);
      const auto d = ring_dir(k, seg);
      const double r = BodyShape::radius(sec, d[0], d[1]);
      return Vec3(r * d[0], y, r * d[1]);
    });
  }

  // Legs (the right one is the left one moved to -x; its sections are symmetric).
  {
    const int rings = kLegRings * res, seg = kLegSegments * res;
    const double y1 = shape.leg_top();
    const auto ts = rings_by_arc_length(rings, [&](double t) {
      const double y = t * y1;
      const auto sec = shape.leg(y);
      return std::array<double, 3>{y, sec.rx, sec.rz};
    });
    for (double side : {1.0, -1.0}) {
      const auto bottom = shape.leg(1e-9), top = shape.leg(y1 - 1e-9);
      add_tube(m, v, rings, seg, Vec3(side * bottom.xc, 0, bottom.zc), Vec3(side * top.xc, y1, top.zc),
               [&](int i, int k) {
                 const double y = ts[static_cast<std::size_t>(i)] * y1;
                 const auto sec = shape.leg(y);
                 const auto d = ring_dir(k, seg);
                 return Vec3(side * sec.xc + sec.rx * d[0], y, sec.zc + sec.rz * d[1]);
               });
    }
  }

  // Arms, hanging kArmTilt away from the vertical, kArmGap clear of the torso.
  {
    const int rings = kArmRings * res, seg = kArmSegments * res;
    ArmModel arm;
    arm.length = 0.43 * p.height;
    arm.cap_top = 3.5 * s;
    arm.cap_bottom = 2.5 * s;
    arm.scale = 0.5 * s + 0.5 * p.bust / 88.0;
    const double top_y = L.shoulder + 1.0 * s;
    const double st = std::sin(kArmTilt), ct = std::cos(kArmTilt);
    // d runs from the fingertips (t = 0) to the shoulder (t = 1).
    const auto ts = rings_by_arc_length(rings, [&](double t) { return arm.at((1.0 - t) * arm.length); });
    // Left arm frame: axis t (hand -> shoulder), u = +z, v = t x u; u x v = t.
    const Vec3 down(st, -ct, 0), across(ct, st, 0), depth(0, 0, 1);
    const auto local = [&](double d, int k, int segments) {
      const auto r = arm.at(d);
      const double psi = 2.0 * kPi * k / segments;
      return Vec3(d * down + r[2] * std::cos(psi) * depth + r[1] * std::sin(psi) * across);
    };
    // Shift the arm out until every point clears the torso by kArmGap.
    double x0 = 0;
    for (int i = 0; i <= 200; ++i)
      for (int k = 0; k < 48; ++k) {
        const Vec3 q = local(arm.length * i / 200.0, k, 48);
        const double y = top_y + q.y();
        x0 = std::max(x0, shape.torso(y).a + kArmGap - q.x());
      }
    for (double side : {1.0, -1.0}) {
      const Vec3 top(side * x0, top_y, 0);
      const Vec3 dn(side * st, -ct, 0), ac(ct, side * st, 0);  // ac = t x depth for this side
      add_tube(m, v, rings, seg, top + arm.length * dn, top, [&](int i, int k) {
        const double d = (1.0 - ts[static_cast<std::size_t>(i)]) * arm.length;
        const auto r = arm.at(d);
        const double psi = 2.0 * kPi * k / seg;
        return Vec3(top + d * dn + r[2] * std::cos(psi) * depth + r[1] * std::sin(psi) * ac);
      });
    }
  }

  m.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.vertices.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  return m;
}

}  // namespace refit::mannequin
