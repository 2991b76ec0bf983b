// Procedural garments: vertex counts, topology (manifold, soup, layers), staying
// outside the body, the dress's straight profiles and its feature file.
#include <mannequin/mannequin.hpp>
#include <refit/body/body_surface.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/topology.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

namespace refit {
namespace {

using mannequin::BodyParams;
using mannequin::GarmentParams;
using Kind = GarmentParams::Kind;

BodyParams body_b() {
  BodyParams p;
  p.height = 172;
  p.bust = 100;
  p.waist = 84;
  p.hip = 108;
  p.belly = 8;
  p.shoulder = 41;
  return p;
}

GarmentParams params(Kind kind, std::size_t target, bool soup = false, bool two = false) {
  GarmentParams g;
  g.kind = kind;
  g.target_vertices = target;
  g.soup = soup;
  g.two_layers = two;
  return g;
}

double face_area(const Garment& g, std::size_t f) {
  const auto r = g.faces.row(f);
  const Vec3 a = row3(g.positions, r[0]);
  double area = 0;
  for (std::size_t k = 1; k + 1 < r.size(); ++k)
    area += 0.5 * (row3(g.positions, r[k]) - a).cross(row3(g.positions, r[k + 1]) - a).norm();
  return area;
}

/// Brute-force inside test and depth: ray parity along a skew direction over
/// every triangle, then the distance to the nearest triangle for points inside.
class BruteBody {
 public:
  explicit BruteBody(const BodyMesh& m) : m_(m) {}

  /// Depth of p inside the body (0 when outside). Inside is the majority of
  /// three ray parities, so a ray grazing an edge cannot flip the answer.
  double depth(const Vec3& p) const {
    int inside = 0;
    for (const Vec3& dir : {Vec3(0.3179, 0.1213, 0.9403).normalized(), Vec3(-0.7713, 0.2291, 0.5937).normalized(),
                            Vec3(0.1117, -0.9236, -0.3668).normalized()})
      inside += parity(p, dir);
    if (inside < 2) return 0.0;
    double best = 1e300;
    for (const auto& t : m_.triangles)
      best = std::min(best, point_triangle(p, row3(m_.vertices, t[0]), row3(m_.vertices, t[1]), row3(m_.vertices, t[2])));
    return best;
  }

 private:
  int parity(const Vec3& p, const Vec3& dir) const {
    int hits = 0;
    for (const auto& t : m_.triangles) {
      const Vec3 a = row3(m_.vertices, t[0]), b = row3(m_.vertices, t[1]), c = row3(m_.vertices, t[2]);
      const Vec3 e1 = b - a, e2 = c - a, q = dir.cross(e2);
      const double det = e1.dot(q);
      if (std::abs(det) < 1e-14) continue;
      const Vec3 s = p - a;
      const double u = s.dot(q) / det;
      if (u < 0 || u > 1) continue;
      const Vec3 r = s.cross(e1);
      const double v = dir.dot(r) / det;
      if (v < 0 || u + v > 1) continue;
      if (e2.dot(r) / det > 0) ++hits;
    }
    return hits % 2;
  }
  static double point_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    // Ericson, Real-Time Collision Detection 5.1.5.
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return ap.norm();
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return bp.norm();
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return cp.norm();
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
      return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
    const double denom = 1.0 / (va + vb + vc);
    return (p - (a + ab * vb * denom + ac * vc * denom)).norm();
  }
  const BodyMesh& m_;
};

/// Largest depth inside the body over about `samples` vertices (every vertex of
/// the lowest and highest rows, plus an even stride).
double max_depth(const BodyMesh& body, const Garment& g, std::size_t samples) {
  const BruteBody b(body);
  const std::size_t n = g.vertex_count(), stride = std::max<std::size_t>(1, n / samples);
  std::vector<Index> pick;
  for (std::size_t i = 0; i < n; i += stride) pick.push_back(static_cast<Index>(i));
  std::vector<double> depth(pick.size());
  parallel_for(0, pick.size(), 16, [&](std::size_t i0, std::size_t i1) {
    for (std::size_t i = i0; i < i1; ++i) depth[i] = b.depth(row3(g.positions, pick[i]));
  });
  return *std::max_element(depth.begin(), depth.end());
}

TEST(MannequinGarment, VertexCountsNearTarget) {
  for (Kind kind : {Kind::Dress, Kind::Top, Kind::Trousers})
    for (std::size_t target : {1000u, 2000u, 200000u})
      for (bool two : {false, true}) {
        const Garment g = mannequin::make_garment(BodyParams{}, params(kind, target, false, two));
        EXPECT_NEAR(static_cast<double>(g.vertex_count()), static_cast<double>(target), 0.1 * static_cast<double>(target))
            << "kind " << static_cast<int>(kind) << " two layers " << two;
      }
}

TEST(MannequinGarment, ManifoldQuadGrids) {
  struct Case {
    Kind kind;
    std::size_t loops;
  };
  for (const Case c : {Case{Kind::Dress, 2}, Case{Kind::Top, 2}, Case{Kind::Trousers, 3}}) {
    const Garment g = mannequin::make_garment(BodyParams{}, params(c.kind, 5000));
    const TopologyStats s = topology_stats(g);
    EXPECT_EQ(s.non_manifold_edges, 0u);
    EXPECT_EQ(s.unreferenced_vertices, 0u);
    EXPECT_EQ(s.components, 1u);
    EXPECT_EQ(s.boundary_loops, c.loops);
    EXPECT_EQ(s.lines, 0u);
    EXPECT_EQ(s.points, 0u);
    for (std::size_t f = 0; f < g.faces.rows(); ++f) ASSERT_EQ(g.faces.row_size(f), 4u);
    // Consistent orientation: every interior edge is walked once each way.
    std::set<std::pair<Index, Index>> directed;
    for (std::size_t f = 0; f < g.faces.rows(); ++f) {
      const auto r = g.faces.row(f);
      for (std::size_t k = 0; k < 4; ++k) EXPECT_TRUE(directed.insert({r[k], r[(k + 1) % 4]}).second);
    }
    // Outward: face normals point away from the body's vertical axis (the
    // trousers' legs away from their own leg, checked by the sign of the sum).
    double outward = 0;
    for (std::size_t f = 0; f < g.faces.rows(); ++f) {
      const auto r = g.faces.row(f);
      const Vec3 a = row3(g.positions, r[0]), b = row3(g.positions, r[1]), cc = row3(g.positions, r[2]);
      const Vec3 n = (b - a).cross(cc - a);
      const Vec3 centre = (a + cc) / 2;
      outward += n.dot(Vec3(centre.x(), 0, centre.z()));
    }
    EXPECT_GT(outward, 0.0);
  }
}

TEST(MannequinGarment, SoupHasTheMessButTheSameSurface) {
  for (Kind kind : {Kind::Dress, Kind::Top, Kind::Trousers}) {
    const Garment clean = mannequin::make_garment(BodyParams{}, params(kind, 4000));
    const Garment soup = mannequin::make_garment(BodyParams{}, params(kind, 4000, true));
    const TopologyStats s = topology_stats(soup);
    EXPECT_GE(s.non_manifold_edges, 1u);
    EXPECT_EQ(s.lines, 2u);
    EXPECT_EQ(s.points, 5u);
    EXPECT_EQ(s.unreferenced_vertices, 1u);
    EXPECT_GT(s.components, 10u);  // patches plus independent triangles
    std::size_t triangles = 0;
    for (std::size_t f = 0; f < soup.faces.rows(); ++f) triangles += soup.faces.row_size(f) == 3;
    EXPECT_GT(triangles, 10u);
    // Every face corner is a point of the clean garment except the flap's tip,
    // and the area only grows by the flap.
    std::set<std::tuple<double, double, double>> clean_points;
    for (Index i = 0; i < clean.vertex_count(); ++i)
      clean_points.insert({clean.positions(i, 0), clean.positions(i, 1), clean.positions(i, 2)});
    std::size_t foreign = 0;
    double area_clean = 0, area_soup = 0, area_foreign = 0;
    for (std::size_t f = 0; f < clean.faces.rows(); ++f) area_clean += face_area(clean, f);
    for (std::size_t f = 0; f < soup.faces.rows(); ++f) {
      bool ok = true;
      for (Index i : soup.faces.row(f))
        ok = ok && clean_points.count({soup.positions(i, 0), soup.positions(i, 1), soup.positions(i, 2)});
      area_soup += face_area(soup, f);
      if (!ok) ++foreign, area_foreign += face_area(soup, f);
    }
    EXPECT_EQ(foreign, 1u);
    EXPECT_NEAR(area_soup - area_foreign, area_clean, 1e-9 * area_clean);
    // Drawstrings start on the garment and hang below it.
    for (std::size_t l = 0; l < soup.lines.rows(); ++l) {
      const auto r = soup.lines.row(l);
      EXPECT_TRUE(clean_points.count({soup.positions(r[0], 0), soup.positions(r[0], 1), soup.positions(r[0], 2)}));
      EXPECT_LT(soup.positions(r.back(), 1), soup.positions(r[0], 1) - 5.0);
    }
  }
}

TEST(MannequinGarment, TwoLayers) {
  const Garment one = mannequin::make_garment(BodyParams{}, params(Kind::Dress, 10000));
  const Garment two = mannequin::make_garment(BodyParams{}, params(Kind::Dress, 10000, false, true));
  const TopologyStats s = topology_stats(two);
  EXPECT_EQ(s.components, 2u);
  EXPECT_EQ(s.boundary_loops, 4u);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  // The slip (first layer) is about 1 cm inside the dress (second layer): compare
  // the radii of the two layers' front-centre vertices at the waist.
  const auto lv = mannequin::landmarks(BodyParams{});
  const std::size_t half = two.vertex_count() / 2;
  const auto front_at_waist = [&](std::size_t begin, std::size_t end) {
    double z = 0;
    for (std::size_t i = begin; i < end; ++i)
      if (std::abs(two.positions(static_cast<Eigen::Index>(i), 1) - lv.waist) < 1e-9 &&
          two.positions(static_cast<Eigen::Index>(i), 0) == 0 && two.positions(static_cast<Eigen::Index>(i), 2) > 0)
        z = two.positions(static_cast<Eigen::Index>(i), 2);
    return z;
  };
  ASSERT_EQ(two.vertex_count(), 2 * half);
  const double inner = front_at_waist(0, half), outer = front_at_waist(half, 2 * half);
  EXPECT_NEAR(outer - inner, 1.0, 1e-6);
  EXPECT_GT(one.vertex_count(), 9000u);
}

TEST(MannequinGarment, OutsideTheBody) {
  struct Case {
    BodyParams body;
    GarmentParams g;
  };
  std::vector<Case> cases;
  for (const BodyParams& b : {BodyParams{}, body_b()})
    for (Kind kind : {Kind::Dress, Kind::Top, Kind::Trousers}) cases.push_back({b, params(kind, 20000)});
  cases.push_back({BodyParams{}, params(Kind::Dress, 20000, true, true)});
  cases.push_back({body_b(), params(Kind::Trousers, 20000, true, true)});
  for (const Case& c : cases) {
    const BodyMesh body = mannequin::make_body(c.body);
    const Garment g = mannequin::make_garment(c.body, c.g);
    EXPECT_LT(max_depth(body, g, 400), 0.5) << "kind " << static_cast<int>(c.g.kind) << " belly " << c.body.belly;
    // Every vertex, through the Embree queries.
    const BodySurface surface(body);
    std::vector<double> sd(g.vertex_count());
    parallel_for(0, sd.size(), 256, [&](std::size_t i0, std::size_t i1) {
      for (std::size_t i = i0; i < i1; ++i) sd[i] = surface.signed_distance(row3(g.positions, static_cast<Index>(i)));
    });
    const auto worst = std::min_element(sd.begin(), sd.end());
    EXPECT_GT(*worst, -0.5) << "kind " << static_cast<int>(c.g.kind) << " soup " << c.g.soup << " vertex "
                            << worst - sd.begin() << " of " << sd.size() << " at "
                            << row3(g.positions, static_cast<Index>(worst - sd.begin())).transpose();
  }
}

TEST(MannequinGarment, DressProfilesAreStraightAndFeaturesMatch) {
  for (const BodyParams& b : {BodyParams{}, body_b()}) {
    const GarmentParams gp = params(Kind::Dress, 20000);
    const Garment g = mannequin::make_garment(b, gp);
    const auto j = nlohmann::json::parse(mannequin::dress_features_json(b, gp));
    EXPECT_EQ(j.at("units"), "cm");
    const auto& f = j.at("features");
    ASSERT_EQ(f.size(), 5u);
    const auto vec = [](const nlohmann::json& a) { return Vec3(a[0].get<double>(), a[1].get<double>(), a[2].get<double>()); };
    const auto nearest = [&](const Vec3& p) {
      double d = 1e300;
      for (Index i = 0; i < g.vertex_count(); ++i) d = std::min(d, (row3(g.positions, i) - p).norm());
      return d;
    };
    // The hem first (so it holds the profiles' lower ends), then the profiles.
    const char* names[] = {"hem", "left-profile", "right-profile", "front-profile", "back-profile"};
    for (int k = 0; k < 5; ++k) EXPECT_EQ(f[static_cast<std::size_t>(k)].at("name"), names[k]);
    for (int k = 1; k < 5; ++k) {
      const auto& c = f[static_cast<std::size_t>(k)].at("curve");
      EXPECT_EQ(c.at("kind"), "slice");
      const Vec3 from = vec(c.at("from")), to = vec(c.at("to")), near = vec(c.at("near"));
      const Vec3 n = vec(f[static_cast<std::size_t>(k)].at("plane").at("normal"));
      const Vec3 o = vec(f[static_cast<std::size_t>(k)].at("plane").at("point"));
      // from and to are dress vertices (waist and hem), all three on the plane.
      EXPECT_LT(nearest(from), 1e-6);
      EXPECT_LT(nearest(to), 1e-6);
      EXPECT_LT(nearest(near), 2.0);
      for (const Vec3& p : {from, to, near}) EXPECT_NEAR((p - o).dot(n), 0.0, 1e-9);
      EXPECT_GT(from.y(), to.y());
      // Straight profile: every dress vertex on this half-plane between the waist
      // and the hem lies on the segment from -> to.
      const Vec3 side = Vec3(from.x(), 0, from.z()).normalized();
      std::size_t on = 0;
      for (Index i = 0; i < g.vertex_count(); ++i) {
        const Vec3 p = row3(g.positions, i);
        if (std::abs((p - o).dot(n)) > 1e-9 || p.dot(side) <= 0 || p.y() > from.y() + 1e-9 || p.y() < to.y() - 1e-9) continue;
        ++on;
        const Vec3 d = (to - from).normalized();
        EXPECT_LT(((p - from) - (p - from).dot(d) * d).norm(), 1e-7);
      }
      EXPECT_GT(on, 10u);
    }
    const auto& hem = f[0].at("curve");
    EXPECT_EQ(hem.at("kind"), "boundary");
    const Vec3 hem_near = vec(hem.at("near"));
    EXPECT_LT(nearest(hem_near), 1e-6);
    EXPECT_NEAR(hem_near.y(), g.positions.col(1).minCoeff(), 1e-9);
  }
  EXPECT_THROW(mannequin::dress_features_json(BodyParams{}, params(Kind::Top, 2000)), Error);
}

TEST(MannequinGarment, DeterministicForAnyThreadCount) {
  const GarmentParams gp = params(Kind::Trousers, 50000, true, true);
  Garment a;
  {
    ThreadLimit one(1);
    a = mannequin::make_garment(body_b(), gp);
  }
  const Garment b = mannequin::make_garment(body_b(), gp);
  EXPECT_TRUE(a.positions == b.positions);
  EXPECT_EQ(a.faces.indices, b.faces.indices);
  EXPECT_EQ(a.faces.offsets, b.faces.offsets);
  EXPECT_EQ(a.lines.indices, b.lines.indices);
  EXPECT_EQ(a.points.indices, b.points.indices);
}

TEST(MannequinGarment, BadParametersThrow) {
  EXPECT_THROW(mannequin::make_garment(BodyParams{}, params(Kind::Dress, 10)), Error);
  GarmentParams g = params(Kind::Top, 2000);
  g.ease = std::nan("");
  EXPECT_THROW(mannequin::make_garment(BodyParams{}, g), Error);
  BodyParams b;
  b.hip = 0;
  EXPECT_THROW(mannequin::make_garment(b, params(Kind::Top, 2000)), Error);
}

}  // namespace
}  // namespace refit
