// The procedural mannequin: same connectivity for every parameter set, closed
// and outward, girths and belly as asked.
#include <mannequin/mannequin.hpp>
#include <refit/core/error.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

namespace refit {
namespace {

using mannequin::BodyParams;

BodyParams other_params() {
  BodyParams p;
  p.height = 180;
  p.bust = 102;
  p.waist = 86;
  p.hip = 106;
  p.belly = 6;
  p.shoulder = 43;
  return p;
}

/// Points where the body's edges cross the plane y = level.
std::vector<Eigen::Vector2d> slice(const BodyMesh& m, double level) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& t : m.triangles)
    for (int e = 0; e < 3; ++e) {
      const Index a = t[static_cast<std::size_t>(e)], b = t[static_cast<std::size_t>((e + 1) % 3)];
      if (a > b) continue;  // each edge once (the other face has it reversed)
      const Vec3 pa = row3(m.vertices, a), pb = row3(m.vertices, b);
      if ((pa.y() - level) * (pb.y() - level) >= 0) continue;
      const double f = (level - pa.y()) / (pb.y() - pa.y());
      const Vec3 p = pa + f * (pb - pa);
      out.emplace_back(p.x(), p.z());
    }
  return out;
}

/// Perimeter of the convex hull (monotone chain), as a tape measure reads a girth.
double hull_perimeter(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  if (p.size() < 3) return 0;
  std::vector<Eigen::Vector2d> h(2 * p.size());
  std::size_t k = 0;
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i - 1]) <= 0) --k;
    h[k++] = p[i - 1];
  }
  double len = 0;
  for (std::size_t i = 0; i + 1 < k; ++i) len += (h[i + 1] - h[i]).norm();
  return len;
}

/// Torso slice only: the arms hang at least 3 cm clear of the torso's half width.
std::vector<Eigen::Vector2d> torso_slice(const BodyMesh& m, const BodyParams& p, double level) {
  const double a = mannequin::BodyShape(p).torso(level).a;
  auto s = slice(m, level);
  std::erase_if(s, [&](const Eigen::Vector2d& q) { return std::abs(q.x()) > a + 1.5; });
  return s;
}

TEST(MannequinBody, SameConnectivityForAnyParameters) {
  const BodyMesh a = mannequin::make_body(BodyParams{});
  const BodyMesh b = mannequin::make_body(other_params());
  EXPECT_EQ(a.vertices.rows(), b.vertices.rows());
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  EXPECT_TRUE(a.triangles == b.triangles);
  EXPECT_NO_THROW(check_same_connectivity(a, b));
  EXPECT_GT(a.triangles.size(), 24000u);
  EXPECT_LT(a.triangles.size(), 29000u);
  EXPECT_FALSE((a.vertices - b.vertices).isZero());
  EXPECT_TRUE(a.vertices.allFinite());
  EXPECT_TRUE(b.vertices.allFinite());
}

void expect_closed_and_outward(const BodyMesh& m) {
  // Every directed edge once, and its reverse once: closed, manifold, consistently oriented.
  std::map<std::pair<Index, Index>, int> directed;
  for (const auto& t : m.triangles)
    for (int e = 0; e < 3; ++e) ++directed[{t[static_cast<std::size_t>(e)], t[static_cast<std::size_t>((e + 1) % 3)]}];
  std::size_t bad = 0;
  for (const auto& [edge, n] : directed)
    if (n != 1 || !directed.count({edge.second, edge.first})) ++bad;
  EXPECT_EQ(bad, 0u);
  double volume = 0, min_area = 1e300;
  for (const auto& t : m.triangles) {
    const Vec3 a = row3(m.vertices, t[0]), b = row3(m.vertices, t[1]), c = row3(m.vertices, t[2]);
    volume += a.dot(b.cross(c)) / 6.0;
    min_area = std::min(min_area, 0.5 * (b - a).cross(c - a).norm());
  }
  EXPECT_GT(volume, 30000.0);  // cm^3: a 165 cm body is about 55 litres
  EXPECT_LT(volume, 150000.0);
  EXPECT_GT(min_area, 1e-6);  // no degenerate triangles
  // Soles at y = 0, head at the height.
  EXPECT_NEAR(m.vertices.col(1).minCoeff(), 0.0, 1e-9);
}

TEST(MannequinBody, ClosedConsistentlyOrientedOutward) {
  expect_closed_and_outward(mannequin::make_body(BodyParams{}));
  expect_closed_and_outward(mannequin::make_body(other_params()));
  BodyParams hi;
  hi.resolution = 2;
  const BodyMesh m2 = mannequin::make_body(hi);
  expect_closed_and_outward(m2);
  EXPECT_GT(m2.triangles.size(), 3 * mannequin::make_body(BodyParams{}).triangles.size());
}

TEST(MannequinBody, HeightAndSymmetry) {
  for (const BodyParams& p : {BodyParams{}, other_params()}) {
    const BodyMesh m = mannequin::make_body(p);
    EXPECT_NEAR(m.vertices.col(1).maxCoeff(), p.height, 1e-6);
    EXPECT_NEAR(m.vertices.col(0).maxCoeff(), -m.vertices.col(0).minCoeff(), 1e-6);
  }
}

TEST(MannequinBody, GirthsMatchTheParameters) {
  for (const BodyParams& p : {BodyParams{}, other_params()}) {
    BodyParams flat = p;
    flat.belly = 0;  // a belly adds to the waist girth on purpose
    const BodyMesh m = mannequin::make_body(flat);
    const auto lv = mannequin::landmarks(flat);
    EXPECT_NEAR(hull_perimeter(torso_slice(m, flat, lv.hip)), flat.hip, 0.03 * flat.hip);
    EXPECT_NEAR(hull_perimeter(torso_slice(m, flat, lv.waist)), flat.waist, 0.03 * flat.waist);
    EXPECT_NEAR(hull_perimeter(torso_slice(m, flat, lv.bust)), flat.bust, 0.03 * flat.bust);
    // Shoulder width: the torso's width at the shoulder level.
    const auto sh = torso_slice(m, flat, lv.shoulder);
    double w = 0;
    for (const auto& q : sh) w = std::max(w, 2 * std::abs(q.x()));
    EXPECT_NEAR(w, flat.shoulder, 0.03 * flat.shoulder);
  }
}

TEST(MannequinBody, BellyPushesTheFrontForward) {
  BodyParams flat, round;
  round.belly = 8;
  const double navel = mannequin::landmarks(flat).navel;
  const auto front = [&](const BodyParams& p) {
    double z = -1e300;
    for (const auto& q : torso_slice(mannequin::make_body(p), p, navel))
      if (std::abs(q.x()) < 3) z = std::max(z, q.y());
    return z;
  };
  EXPECT_NEAR(front(round) - front(flat), 8.0, 0.5);
  // The back does not move.
  const auto back = [&](const BodyParams& p) {
    double z = 1e300;
    for (const auto& q : torso_slice(mannequin::make_body(p), p, navel)) z = std::min(z, q.y());
    return z;
  };
  EXPECT_NEAR(back(round), back(flat), 0.05);
}

TEST(MannequinBody, HipWidensTheButtocks) {
  BodyParams p;
  p.hip = 110;
  const double y = mannequin::landmarks(p).hip;
  const auto back = [&](const BodyParams& q) {
    double z = 1e300;
    for (const auto& s : torso_slice(mannequin::make_body(q), q, y)) z = std::min(z, s.y());
    return z;
  };
  EXPECT_LT(back(p), back(BodyParams{}) - 1.0);
}

TEST(MannequinBody, BadParametersThrow) {
  BodyParams p;
  p.height = -1;
  EXPECT_THROW(mannequin::make_body(p), Error);
  p = BodyParams{};
  p.resolution = 0;
  EXPECT_THROW(mannequin::make_body(p), Error);
  p = BodyParams{};
  p.bust = std::nan("");
  EXPECT_THROW(mannequin::make_body(p), Error);
  try {
    p = BodyParams{};
    p.waist = 1000;
    mannequin::make_body(p);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("waist"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace refit
