// BodySurface (Embree queries) against analytic answers on a sphere and against
// brute force (every triangle; generalized winding number) on the mannequin and
// on a real MakeHuman body.
#include <refit/body/body_surface.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>

#include "support/shapes.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#if __has_include(<mannequin/mannequin.hpp>)
#include <mannequin/mannequin.hpp>
#define REFIT_HAVE_MANNEQUIN 1
#endif

#include <array>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

namespace refit {
namespace {

// Reference point-triangle distance, written differently from the engine's:
// projection onto the plane when inside, else the nearest of the three edges.
double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double s = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + s * ab - p).norm();
}
double triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const Vec3 q = p - n * ((p - a).dot(n) / n.squaredNorm());
  const double w0 = (b - q).cross(c - q).dot(n), w1 = (c - q).cross(a - q).dot(n), w2 = (a - q).cross(b - q).dot(n);
  if (w0 >= 0 && w1 >= 0 && w2 >= 0) return (p - q).norm();
  return std::min({segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}
double brute_distance(const BodyMesh& m, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles)
    best = std::min(best, triangle_distance(p, row3(m.vertices, t[0]), row3(m.vertices, t[1]), row3(m.vertices, t[2])));
  return best;
}
// Generalized winding number (solid angles, Van Oosterom and Strackee): about 1
// inside a closed outward mesh, 0 outside, whatever self-intersections do to ray parity.
double winding_number(const BodyMesh& m, const Vec3& p) {
  double sum = 0.0;
  for (const auto& t : m.triangles) {
    const Vec3 a = row3(m.vertices, t[0]) - p, b = row3(m.vertices, t[1]) - p, c = row3(m.vertices, t[2]) - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    sum += 2.0 * std::atan2(num, den);
  }
  return sum / (4.0 * M_PI);
}

// Minimal OBJ body reader for the shared data (v and f lines only), so this test
// does not depend on the io module.
BodyMesh load_obj_body(const std::string& path) {
  std::ifstream in(path);
  BodyMesh m;
  std::vector<Vec3> v;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    std::string tag;
    ss >> tag;
    if (tag == "v") {
      Vec3 p;
      ss >> p.x() >> p.y() >> p.z();
      v.push_back(p);
    } else if (tag == "f") {
      std::vector<Index> ids;
      std::string tok;
      while (ss >> tok) ids.push_back(static_cast<Index>(std::stoul(tok.substr(0, tok.find('/'))) - 1));
      for (std::size_t k = 1; k + 1 < ids.size(); ++k) m.triangles.push_back({ids[0], ids[k], ids[k + 1]});
    }
  }
  m.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.vertices.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  m.path = path;
  return m;
}

struct Probe {
  Vec3 p;
  int expect_inside = -1;  // -1: take the reference
};

// Points near the surface (random spots on random triangles, pushed along the
// face normal by tiny to moderate offsets), all over the bounding box, and far away.
std::vector<Probe> probes(const BodyMesh& m, std::size_t count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const Vec3 lo = m.vertices.colwise().minCoeff().transpose(), hi = m.vertices.colwise().maxCoeff().transpose();
  const double diag = (hi - lo).norm();
  const double offsets[] = {1e-7, 1e-5, 1e-3, 1e-2, 0.1};
  std::vector<Probe> out;
  for (std::size_t i = 0; i < count; ++i) {
    const int kind = static_cast<int>(i % 4);
    if (kind <= 1) {
      const auto& t = m.triangles[static_cast<std::size_t>(u01(rng) * static_cast<double>(m.triangles.size())) %
                                  m.triangles.size()];
      const Vec3 a = row3(m.vertices, t[0]), b = row3(m.vertices, t[1]), c = row3(m.vertices, t[2]);
      // Stay away from edges so the offset point's side is the face's side.
      double s = 0.1 + 0.8 * u01(rng), r = 0.1 + 0.8 * u01(rng);
      if (s + r > 0.9) {
        s = 0.9 - s * 0.5;
        r = 0.9 - s - 0.05;
      }
      const Vec3 n = (b - a).cross(c - a).normalized();
      const double off = offsets[i / 4 % 5] * diag * 1e-2;
      const double sign = kind == 0 ? 1.0 : -1.0;
      out.push_back({a + s * (b - a) + r * (c - a) + sign * off * n, -1});
    } else if (kind == 2) {
      out.push_back({lo + (hi - lo).cwiseProduct(Vec3(u01(rng), u01(rng), u01(rng))), -1});
    } else {
      const Vec3 d = Vec3(u01(rng) - 0.5, u01(rng) - 0.5, u01(rng) - 0.5).normalized();
      out.push_back({0.5 * (lo + hi) + d * diag * (1.0 + 5.0 * u01(rng)), 0});
    }
  }
  return out;
}

// Compares the surface against brute force on every probe, queried in parallel.
void check_against_brute_force(const BodyMesh& m, std::size_t count, unsigned seed) {
  const BodySurface s(m);
  const auto pts = probes(m, count, seed);
  std::vector<double> dist(pts.size()), sd(pts.size());
  std::vector<std::uint8_t> in(pts.size());
  parallel_for(0, pts.size(), 16, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      dist[i] = s.closest(pts[i].p).distance;
      in[i] = s.inside(pts[i].p) ? 1 : 0;
      sd[i] = s.signed_distance(pts[i].p);
    }
  });
  std::size_t wrong_inside = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const double ref = brute_distance(m, pts[i].p);
    ASSERT_NEAR(dist[i], ref, 1e-9 * (1.0 + ref)) << "probe " << i;
    const double w = winding_number(m, pts[i].p);
    const bool ref_in = pts[i].expect_inside >= 0 ? pts[i].expect_inside == 1 : w > 0.5;
    if ((in[i] == 1) != ref_in) {
      ++wrong_inside;
      ADD_FAILURE() << "probe " << i << " at distance " << ref << ": inside=" << int(in[i]) << " winding=" << w;
    }
    EXPECT_EQ(sd[i] < 0.0, in[i] == 1);
    EXPECT_NEAR(std::abs(sd[i]), ref, 1e-9 * (1.0 + ref));
  }
  EXPECT_EQ(wrong_inside, 0u);
}

TEST(BodySurface, SphereClosestAndInsideMatchAnalytic) {
  const Vec3 c(1.0, -2.0, 3.0);
  const double r = 10.0;
  const BodyMesh m = test::icosphere(3, r, c);
  // The faces lie between the inradius and r from the centre.
  double inradius = r;
  for (const auto& t : m.triangles) {
    const Vec3 a = row3(m.vertices, t[0]);
    const Vec3 n = (row3(m.vertices, t[1]) - a).cross(row3(m.vertices, t[2]) - a).normalized();
    inradius = std::min(inradius, std::abs((a - c).dot(n)));
  }
  const BodySurface s(m);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 d = Vec3(u(rng), u(rng), u(rng)).normalized();
    const double rho = (i % 2 == 0) ? 3.0 * r * std::abs(u(rng)) : r * (1.0 + 0.02 * u(rng));
    const Vec3 p = c + rho * d;
    const ClosestPoint cp = s.closest(p);
    EXPECT_NEAR(cp.distance, std::abs(rho - r), r - inradius + 1e-12);
    EXPECT_NEAR((cp.point - p).norm(), cp.distance, 1e-12);
    EXPECT_NEAR(cp.normal.norm(), 1.0, 1e-12);
    if (rho < inradius - 1e-9) {
      EXPECT_TRUE(s.inside(p)) << rho;
    }
    if (rho > r + 1e-9) {
      EXPECT_FALSE(s.inside(p)) << rho;
    }
  }
  EXPECT_TRUE(s.inside(c));
  EXPECT_NEAR(s.signed_distance(c), -inradius, 1e-9);
  Index tri = 0;
  const double hit = s.intersect(c, Vec3(1, 0, 0), &tri);
  EXPECT_GT(hit, inradius - 1e-4);
  EXPECT_LT(hit, r + 1e-4);
  EXPECT_TRUE(std::isinf(s.intersect(c + Vec3(0, 0, 3 * r), Vec3(0, 0, 1))));
}

TEST(BodySurface, PointsOnAndNearTheSurface) {
  const BodyMesh m = test::icosphere(3, 1.0, Vec3::Zero());
  const BodySurface s(m);
  for (Eigen::Index v = 0; v < m.vertices.rows(); ++v) {
    const Vec3 p = m.vertices.row(v).transpose();
    // A vertex is on the surface: distance 0, and "on" is not inside.
    EXPECT_EQ(s.closest(p).distance, 0.0);
    EXPECT_FALSE(s.inside(p));
    // Along the vertex normal (the sphere's radius), even a hair off the surface.
    for (double eps : {1e-12, 1e-9, 1e-6, 1e-3}) {
      EXPECT_TRUE(s.inside(p * (1.0 - eps))) << v << " " << eps;
      EXPECT_FALSE(s.inside(p * (1.0 + eps))) << v << " " << eps;
    }
  }
  // Edge midpoints (on an edge, shared by two faces) and just off them.
  for (const auto& t : m.triangles) {
    const Vec3 e = 0.5 * (row3(m.vertices, t[0]) + row3(m.vertices, t[1]));
    EXPECT_NEAR(s.closest(e).distance, 0.0, 1e-15);
    EXPECT_TRUE(s.inside(e * (1.0 - 1e-9)));
    EXPECT_FALSE(s.inside(e * (1.0 + 1e-9)));
  }
}

TEST(BodySurface, ClosestWithinHonoursTheRadius) {
  const BodyMesh m = test::icosphere(2, 1.0, Vec3::Zero());
  const BodySurface s(m);
  const Vec3 p(0.0, 0.0, 1.5);
  EXPECT_TRUE(std::isinf(s.closest_within(p, 0.4).distance));
  const ClosestPoint cp = s.closest_within(p, 0.6);
  EXPECT_NEAR(cp.distance, s.closest(p).distance, 0.0);
  EXPECT_LT(cp.distance, 0.6);
  // Far points.
  const Vec3 far(1e4, -3e3, 2e3);
  EXPECT_NEAR(s.closest(far).distance, brute_distance(m, far), 1e-9);
  EXPECT_FALSE(s.inside(far));
}

TEST(BodySurface, CloserThanAnswersAsClosestWithin) {
  // Points from on the surface to beyond the radius, radii from small to the
  // sphere's size, and points exactly at the radius off a vertex (along its
  // normal: the distance is the radius, so "closer than" is no): the early-ending
  // search answers as the closest point's distance does, exactly.
  const BodyMesh m = test::icosphere(3, 5.0, Vec3(1, 2, 3));
  const BodySurface s(m);
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::size_t> pick(0, m.vertices.rows() - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::size_t yes = 0, no = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 dir3 = Vec3(unit(rng), unit(rng), unit(rng)).normalized();
    const double offset = std::array<double, 5>{0.0, 0.05, 0.4, 1.0, 6.0}[std::size_t(i) % 5];
    const Vec3 p = row3(m.vertices, Index(pick(rng))) + offset * dir3;
    for (double radius : {0.05, 0.5, 1.0, 4.0}) {
      const bool expected = s.closest_within(p, radius).distance < radius;
      ASSERT_EQ(s.closer_than(p, radius), expected) << i << " radius " << radius;
      (expected ? yes : no) += 1;
    }
  }
  for (Index v = 0; v < 40; ++v) {
    const Vec3 q = row3(m.vertices, v) + 0.3 * (row3(m.vertices, v) - Vec3(1, 2, 3)).normalized();
    const double d = s.closest(q).distance;
    EXPECT_EQ(s.closer_than(q, d), s.closest_within(q, d).distance < d);
    EXPECT_FALSE(s.closer_than(q, d));  // at the radius exactly: not closer
    EXPECT_TRUE(s.closer_than(q, std::nextafter(d, 1.0)));
  }
  EXPECT_GT(yes, 1000u);
  EXPECT_GT(no, 1000u);
  EXPECT_FALSE(s.closer_than(Vec3(std::nan(""), 0, 0), 1.0));
  EXPECT_FALSE(s.closer_than(row3(m.vertices, 0), 0.0));
}

TEST(BodySurface, BadBodyThrowsNamingTheFile) {
  BodyMesh m = test::icosphere(1, 1.0, Vec3::Zero());
  m.path = "bodies/bad.obj";
  m.triangles[3][1] = 100000;
  try {
    BodySurface s(m);
    FAIL() << "expected refit::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("bodies/bad.obj"), std::string::npos) << e.what();
  }
  BodyMesh empty;
  empty.name = "empty";
  EXPECT_THROW(BodySurface{empty}, Error);
}

TEST(BodySurface, SphereAgainstBruteForce) { check_against_brute_force(test::icosphere(3, 5.0, Vec3(1, 2, 3)), 2000, 11); }

#ifdef REFIT_HAVE_MANNEQUIN
TEST(BodySurface, MannequinAgainstBruteForce) {
  const BodyMesh m = mannequin::make_body(mannequin::BodyParams{});
  check_against_brute_force(m, 1500, 3);
}
#endif

TEST(BodySurface, MakeHumanBodyAgainstBruteForce) {
  const std::string dir = test::shared_data_dir();
  if (dir.empty()) GTEST_SKIP() << "shared data (../shared/data) not found";
  const BodyMesh m = load_obj_body(dir + "/bodies/A_female.obj");
  ASSERT_EQ(m.triangles.size(), 26756u);
  const auto t0 = std::chrono::steady_clock::now();
  const BodySurface s(m);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("BodySurface of %zu triangles built in %.1f ms\n", m.triangles.size(), ms);
  check_against_brute_force(m, 1500, 5);
}

// 4000 points from deep inside to far outside a body (its inside grid's
// inside, outside and boundary cells): off random vertices in random directions.
std::vector<Vec3> points_around(const BodyMesh& m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, m.vertices.rows() - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 dir3 = Vec3(unit(rng), unit(rng), unit(rng)).normalized();
    const double offset = std::array<double, 6>{0.01, 0.1, 0.3, 1.0, 3.0, 8.0}[std::size_t(i) % 6];
    points.push_back(row3(m.vertices, Index(pick(rng))) + offset * dir3);
  }
  return points;
}

TEST(BodySurface, ClosestAndInsideAnswersAsInsideThenClosest) {
  // Points from deep inside to far outside a real body: the one-query answer is
  // the two-query one, exactly.
  const std::string dir = test::shared_data_dir();
  if (dir.empty()) GTEST_SKIP() << "shared data (../shared/data) not found";
  const BodyMesh m = load_obj_body(dir + "/bodies/F_heavier.obj");
  const BodySurface s(m);
  std::size_t inside = 0, outside_near = 0, outside_none = 0;
  const std::vector<Vec3> points = points_around(m, 7);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    for (double radius : {0.2, 1.0}) {
      const SignedClosestPoint both = s.closest_and_inside(p, radius);
      const bool in = s.inside(p);
      const ClosestPoint cp = in ? s.closest(p) : s.closest_within(p, radius);
      ASSERT_EQ(both.inside, in) << i;
      ASSERT_EQ(both.distance, cp.distance) << i;
      if (std::isfinite(cp.distance)) {
        ASSERT_EQ(both.triangle, cp.triangle) << i;
        ASSERT_TRUE(both.point == cp.point) << i;
      }
      inside += in;
      outside_near += !in && std::isfinite(cp.distance);
      outside_none += !in && !std::isfinite(cp.distance);
    }
  }
  EXPECT_GT(inside, 500u);
  EXPECT_GT(outside_near, 500u);
  EXPECT_GT(outside_none, 500u);
}

// Every hint (a triangle that says yes, a far one, none, one out of range)
// gives the unhinted answer; a yes sets the hint to a triangle that says yes.
void expect_hints_change_nothing(const BodyMesh& m, const std::vector<Vec3>& points) {
  const BodySurface s(m);
  const Index nt = Index(m.triangles.size());
  std::size_t yes = 0, no = 0, from_the_hint = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    const Index closest = s.closest(p).triangle;
    for (double radius : {0.05, 0.3, 1.0}) {
      const bool expected = s.closer_than(p, radius);
      (expected ? yes : no) += 1;
      for (Index hint : {BodySurface::kNoHint, nt + 5, closest, Index((i * 7919) % std::size_t(nt))}) {
        Index h = hint;
        ASSERT_EQ(s.closer_than(p, radius, h), expected) << i << " radius " << radius << " hint " << hint;
        if (!expected) continue;
        ASSERT_LT(h, nt);
        ASSERT_LT(s.closest_within(p, radius).distance, radius);
        Index again = h;  // the triangle it names says yes by itself
        ASSERT_TRUE(s.closer_than(p, radius, again) && again == h) << i;
        from_the_hint += h == hint;
      }
    }
  }
  EXPECT_GT(yes, points.size() / 2);
  EXPECT_GT(no, points.size() / 2);
  EXPECT_GT(from_the_hint, points.size() / 2) << "yes answers taken from the hint";
}

TEST(BodySurface, AHintNeverChangesWhetherAPointIsCloserThan) {
  const BodyMesh m = test::icosphere(3, 5.0, Vec3(1, 2, 3));
  std::mt19937 rng(3);
  std::uniform_int_distribution<std::size_t> pick(0, m.vertices.rows() - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < 1500; ++i) {
    const Vec3 dir3 = Vec3(unit(rng), unit(rng), unit(rng)).normalized();
    const double offset = std::array<double, 6>{-0.3, -0.02, 0.0, 0.04, 0.5, 3.0}[std::size_t(i) % 6];
    points.push_back(row3(m.vertices, Index(pick(rng))) + offset * dir3);
  }
  expect_hints_change_nothing(m, points);
}

TEST(BodySurface, AHintNeverChangesWhetherAPointIsCloserThanOnARealBody) {
  const std::string dir = test::shared_data_dir();
  if (dir.empty()) GTEST_SKIP() << "shared data (../shared/data) not found";
  const BodyMesh m = load_obj_body(dir + "/bodies/F_heavier.obj");
  std::vector<Vec3> points = points_around(m, 11);
  points.resize(1500);
  expect_hints_change_nothing(m, points);
}

TEST(BodySurface, ClearBallsHoldNoBodyPoint) {
  // The collision step skips a face's points inside the balls earlier queries
  // left clear: each `clear` must be no more than the point's true distance to
  // the body (0 inside), and as much as it where the query found the closest;
  // inside_or_clear answers inside() as it does.
  const std::string dir = test::shared_data_dir();
  if (dir.empty()) GTEST_SKIP() << "shared data (../shared/data) not found";
  const BodyMesh m = load_obj_body(dir + "/bodies/F_heavier.obj");
  const BodySurface s(m);
  std::size_t cleared = 0, exact = 0;
  const std::vector<Vec3> points = points_around(m, 11);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3& p = points[i];
    const bool in = s.inside(p);
    const double distance = s.closest(p).distance;
    const SignedClosestPoint o = s.inside_or_clear(p);
    ASSERT_EQ(o.inside, in) << i;
    ASSERT_LE(o.clear, distance) << i;
    if (in) {
      ASSERT_EQ(o.clear, 0.0) << i;
    }
    for (double radius : {0.01, 0.2, 1.0}) {
      const SignedClosestPoint c = s.closest_and_inside(p, radius);
      ASSERT_LE(c.clear, distance) << i << " radius " << radius;
      if (in) {
        ASSERT_EQ(c.clear, 0.0) << i;
      } else if (std::isfinite(c.distance)) {
        ASSERT_EQ(c.clear, c.distance) << i;
      }
      cleared += c.clear > radius;
      exact += !in && c.clear == distance;
    }
  }
  EXPECT_GT(cleared, 1000u);  // the balls reach beyond the radius asked: what the skipping gains
  EXPECT_GT(exact, 1000u);
}

}  // namespace
}  // namespace refit

namespace refit {
namespace {

// Bodies B share body A's triangles, so a batch makes their topology once
// (BodyTopology): a surface given another body's answers as one made alone, and
// a topology of other triangles is not taken.
TEST(BodySurface, ATopologyServesBodiesOfTheSameTriangles) {
  const BodyMesh a = test::icosphere(3, 10.0, Vec3(1.0, -2.0, 3.0));
  BodyMesh b = a;  // another shape, the same triangles
  for (Eigen::Index v = 0; v < b.vertices.rows(); ++v) {
    Vec3 p = row3(b.vertices, Index(v));
    p = Vec3(1.3 * p.x(), p.y() + 0.05 * p.x() * p.x(), 0.8 * p.z());
    b.vertices.row(v) = p.transpose();
  }
  BodyMesh flipped = b;  // one triangle turned over: not oriented, its own topology
  std::swap(flipped.triangles[5][1], flipped.triangles[5][2]);
  const BodySurface sa(a);
  for (const BodyMesh* m : {&b, &flipped}) {
    const BodySurface own(*m), shared(*m, sa.topology());
    EXPECT_EQ(shared.topology() == sa.topology(), m == &b);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-16.0, 16.0);
    for (int i = 0; i < 500; ++i) {
      const Vec3 p = Vec3(1.0, -2.0, 3.0) + Vec3(u(rng), u(rng), u(rng));
      const SignedClosestPoint x = own.closest_and_inside(p, 2.0), y = shared.closest_and_inside(p, 2.0);
      EXPECT_EQ(x.distance, y.distance);
      EXPECT_EQ(x.inside, y.inside);
      EXPECT_EQ(own.inside(p), shared.inside(p));
      EXPECT_EQ(own.signed_distance(p), shared.signed_distance(p));
      BodySurface::Near n1, n2;
      own.near(p, 3.0, n1);
      shared.near(p, 3.0, n2);
      EXPECT_TRUE(n1.points == n2.points);
      EXPECT_EQ(n1.edges, n2.edges);
    }
  }
}

}  // namespace
}  // namespace refit
