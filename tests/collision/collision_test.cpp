// The collision step: garment vertices and faces inside body B or too close come
// out, smoothly, locally and for any thread count the same.
#include <refit/collision/collision.hpp>
#include <refit/collision/unfold.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/topology.hpp>
#include <refit/metrics/metrics.hpp>

#include <mannequin/mannequin.hpp>

#include "support/shapes.hpp"
#include "support/test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace refit {
namespace {

BodyMesh sphere_body(int levels, double radius) { return test::icosphere(levels, radius); }

Garment sphere_garment(int levels, double radius) { return test::icosphere_garment(levels, radius); }

// A flat 5 x 5 grid of 4 cm quads at height y, centred over the origin.
Garment coarse_grid(double y) {
  return test::quad_grid(6, 6, 4.0, [y](double, double) { return y; }, -10.0, -10.0);
}

// g and `copies` copies of it, each 100 further along x: far from any body.
Garment with_far_copies(const Garment& g, int copies) {
  Garment out = g;
  for (int k = 1; k <= copies; ++k) {
    Garment far = g;
    far.positions.col(0).array() += 100.0 * k;
    out = test::merge_garments(out, far);
  }
  return out;
}

// -- penetration resolution -----------------------------------------------------

struct Pushed {
  BodyMesh body;
  Garment garment;
  Points pushed;
};

// The mannequin's top, with the front of the torso band between two heights
// pushed 2 cm into the body.
Pushed pushed_top() {
  mannequin::BodyParams bp;
  Pushed p;
  p.body = mannequin::make_body(bp);
  mannequin::GarmentParams gp;
  gp.kind = mannequin::GarmentParams::Kind::Top;
  gp.target_vertices = 6000;
  p.garment = mannequin::make_garment(bp, gp);
  const auto lm = mannequin::landmarks(bp);
  p.pushed = p.garment.positions;
  for (Eigen::Index i = 0; i < p.pushed.rows(); ++i) {
    const double y = p.pushed(i, 1), z = p.pushed(i, 2);
    if (y > lm.waist && y < lm.bust && z > 0.0) {
      const double w = std::sin(M_PI * (y - lm.waist) / (lm.bust - lm.waist));
      const double front = std::clamp(z / 10.0, 0.0, 1.0);
      p.pushed(i, 2) -= 2.5 * w * front * front * (3.0 - 2.0 * front);
    }
  }
  return p;
}

TEST(Collision, PushedTopComesOutSmoothlyAndOnlyLocally) {
  Pushed p = pushed_top();
  const BodySurface body(p.body);
  const PenetrationMetrics before = measure_penetration(p.pushed, body);
  ASSERT_GT(before.inside, 50u) << "the fixture must start inside the body";

  CollisionOptions o;
  Points out = p.pushed;
  const CollisionReport r = resolve_penetrations(p.garment, out, body, o);
  EXPECT_EQ(r.inside_before, before.inside);
  EXPECT_EQ(r.inside_after, 0u);
  EXPECT_EQ(measure_penetration(out, body).inside, 0u);
  EXPECT_GE(r.moved, r.too_close);
  EXPECT_GT(r.max_displacement, 1.0);

  // No face flipped that was not flipped already (relative to the pushed input
  // and to the garment as designed).
  Garment pushed_garment = p.garment;
  pushed_garment.positions = p.pushed;
  EXPECT_EQ(measure_sanity(pushed_garment, out).flipped_faces, 0u);
  EXPECT_LE(measure_sanity(p.garment, out).flipped_faces, measure_sanity(p.garment, p.pushed).flipped_faces);

  // Untouched: vertices more than smoothing_rings edges from any too-close
  // vertex (inside or within the clearance, or a corner of a face whose centre
  // is) keep their exact position; everything that moved is within those rings.
  const Csr adj = vertex_adjacency(p.garment);
  const std::size_t n = p.garment.vertex_count();
  std::vector<int> ring(n, -1);
  std::vector<Index> frontier;
  const auto too_close = [&](const Vec3& q) { return body.inside(q) || body.closest(q).distance < o.clearance; };
  for (Index i = 0; i < n; ++i)
    if (too_close(row3(p.pushed, i))) ring[i] = 0;
  for (std::size_t f = 0; f < p.garment.faces.rows(); ++f) {
    Vec3 centre = Vec3::Zero();
    for (Index v : p.garment.faces.row(f)) centre += row3(p.pushed, v);
    if (too_close(centre / double(p.garment.faces.row_size(f))))
      for (Index v : p.garment.faces.row(f)) ring[v] = 0;
  }
  for (Index i = 0; i < n; ++i)
    if (ring[i] == 0) frontier.push_back(i);
  for (int level = 1; level <= o.smoothing_rings; ++level) {
    std::vector<Index> next;
    for (Index i : frontier)
      for (Index j : adj.row(i))
        if (ring[j] < 0) {
          ring[j] = level;
          next.push_back(j);
        }
    frontier = std::move(next);
  }
  std::size_t far_untouched = 0, moved = 0;
  double max_step_ratio = 0.0;
  for (Index i = 0; i < n; ++i) {
    const bool changed = (out.row(i) - p.pushed.row(i)).squaredNorm() > 0.0;
    moved += changed;
    if (ring[i] < 0) {
      EXPECT_FALSE(changed) << "vertex " << i << " is far from every too-close vertex but moved";
      ++far_untouched;
    }
  }
  EXPECT_GT(far_untouched, n / 2);
  EXPECT_EQ(moved, r.moved);
  // Smooth: along every edge, the displacement difference stays well below the
  // largest displacement (a spike would make one edge carry all of it).
  for (Index i = 0; i < n; ++i)
    for (Index j : adj.row(i)) {
      const double di = (out.row(i) - p.pushed.row(i)).norm(), dj = (out.row(j) - p.pushed.row(j)).norm();
      max_step_ratio = std::max(max_step_ratio, std::abs(di - dj) / r.max_displacement);
    }
  EXPECT_LT(max_step_ratio, 0.6);

  // Nothing to do on the garment as designed (already outside the clearance).
  Points designed = p.garment.positions;
  const CollisionReport none = resolve_penetrations(p.garment, designed, body, o);
  EXPECT_EQ(none.too_close, 0u);
  EXPECT_EQ(none.moved, 0u);
  EXPECT_TRUE(designed == p.garment.positions);
}

// Rounds after the first repair what the last one left, each correction spread
// by its size: they check fewer vertices than rounds that spread every repair over
// smoothing_rings, and the garment comes out as clear of the body, unfolded and
// within a hair of it.
TEST(Collision, SmallRepairsSpreadLessThanTheFirstCorrection) {
  Pushed p = pushed_top();
  const BodySurface body(p.body);
  CollisionOptions by_size, full;
  full.repair_tilt = 0.0;
  Points a = p.pushed, b = p.pushed;
  const CollisionReport ra = resolve_penetrations(p.garment, a, body, by_size);
  const CollisionReport rb = resolve_penetrations(p.garment, b, body, full);
  ASSERT_GE(rb.rounds, 2) << "the fixture must need repair rounds";
  EXPECT_LT(ra.rechecked, rb.rechecked);
  EXPECT_EQ(ra.inside_after, 0u);
  EXPECT_EQ(ra.faces_inside_after, 0u);
  Garment pushed_garment = p.garment;
  pushed_garment.positions = p.pushed;
  EXPECT_EQ(measure_sanity(pushed_garment, a).flipped_faces, 0u);
  double largest_difference = 0.0, closest = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    largest_difference = std::max(largest_difference, (a.row(i) - b.row(i)).norm());
    if ((a.row(i) - p.pushed.row(i)).squaredNorm() > 0.0)
      closest = std::min(closest, body.closest(row3(a, static_cast<Index>(i))).distance);
  }
  EXPECT_LT(largest_difference, 0.05);
  EXPECT_GT(closest, by_size.clearance - 0.01);
}

// A vertex a round moved to the clearance measures a rounding error short of it
// when checked again; that is no shortfall. Counted as one, it kept the rounds
// going to the last and spread its nothing over a ring each time: a garment the
// step has cleared then never came out as needing nothing.
TEST(Collision, AClearedGarmentNeedsNothingMore) {
  Pushed p = pushed_top();
  const BodySurface body(p.body);
  CollisionOptions o;
  Points once = p.pushed;
  const CollisionReport first = resolve_penetrations(p.garment, once, body, o);
  ASSERT_GE(first.rounds, 2) << "the fixture must need repair rounds";
  EXPECT_LT(first.rounds, o.max_rounds) << "the rounds end when nothing is short, before the last";
  Points twice = once;
  const CollisionReport second = resolve_penetrations(p.garment, twice, body, o);
  EXPECT_EQ(second.too_close, 0u);
  EXPECT_EQ(second.moved, 0u);
  EXPECT_TRUE(twice == once);
}

TEST(Collision, WhatTheSymmetrisationHookLeavesInsideIsPushedOutAgain) {
  // The hook (the pipeline makes both sides of a symmetric pair move alike)
  // puts the vertices the rounds moved on the right half back where they
  // started, inside the body: the extra round pushes them out again.
  Pushed p = pushed_top();
  const BodySurface body(p.body);
  CollisionOptions o;
  int calls = 0;
  std::size_t undone = 0;
  o.after_rounds = [&](const Points& now) {
    ++calls;
    std::vector<std::pair<Index, Vec3>> moves;
    for (Index i = 0; i < now.rows(); ++i)
      if (p.pushed(i, 0) > 0.0 && row3(now, i) != row3(p.pushed, i) && body.inside(row3(p.pushed, i)))
        moves.emplace_back(i, row3(p.pushed, i));
    undone = moves.size();
    return moves;
  };
  Points out = p.pushed;
  const CollisionReport r = resolve_penetrations(p.garment, out, body, o);
  EXPECT_EQ(calls, 1);
  ASSERT_GT(undone, 20u) << "the hook must undo some pushes";
  EXPECT_EQ(r.inside_after, 0u);
  EXPECT_EQ(measure_penetration(out, body).inside, 0u);
  EXPECT_EQ(r.faces_inside_after, count_face_centres_inside(p.garment, out, body));
  Garment pushed_garment = p.garment;
  pushed_garment.positions = p.pushed;
  EXPECT_EQ(measure_sanity(pushed_garment, out).flipped_faces, 0u);
}

TEST(Collision, TheBodyPokingThroughACoarseFaceIsPushedOutToo) {
  // A flat 5 x 5 grid of 4 cm quads at y = 9.8 over a sphere of radius 10: the
  // corners nearest its top, (+-2, +-2), clear the body by about 0.2 (more than
  // the clearance, 0.1), but the sphere's top pokes through the middle face.
  const BodySurface body(sphere_body(4, 10.0));
  const Garment g = coarse_grid(9.8);
  CollisionOptions o;
  o.clearance = 0.1;
  Points out = g.positions;
  ASSERT_EQ(measure_penetration(out, body).inside, 0u);
  for (Index v = 0; v < 36; ++v) ASSERT_GT(body.closest(row3(out, v)).distance, o.clearance) << v;
  ASSERT_EQ(count_face_centres_inside(g, out, body), 1u);
  const CollisionReport r = resolve_penetrations(g, out, body, o);
  EXPECT_EQ(r.too_close, 0u);  // no vertex of its own
  EXPECT_EQ(r.faces_inside_before, 1u);
  EXPECT_EQ(r.faces_inside_after, 0u);
  EXPECT_EQ(count_face_centres_inside(g, out, body), 0u);
  // The middle face's centre clears the body by the face clearance now.
  Vec3 centre = Vec3::Zero();
  for (Index v : g.faces.row(12)) centre += row3(out, v);
  EXPECT_GE(body.closest(centre / 4.0).distance, o.face_clearance * 0.99);
  EXPECT_GT(r.moved, 4u);
}

TEST(Collision, TheBodyPokingThroughAFaceAwayFromItsCentreIsPushedOutToo) {
  // The same grid at y = 9.92 shifted by 1 cm: the sphere's top (0, 10, 0) now
  // pokes 0.08 through the face [-1, 3] x [-1, 3] near its corner (-1, -1),
  // while its corners and its centre (1, 1) all clear the body.
  const BodySurface body(sphere_body(4, 10.0));
  Garment g;
  g.positions.resize(36, 3);
  for (int i = 0; i < 6; ++i)
    for (int k = 0; k < 6; ++k) g.positions.row(i * 6 + k) << -9.0 + 4.0 * i, 9.92, -9.0 + 4.0 * k;
  for (int i = 0; i < 5; ++i)
    for (int k = 0; k < 5; ++k) {
      const Index a = Index(i * 6 + k);
      g.faces.push_row(std::array<Index, 4>{a, a + 1, a + 7, a + 6});
    }
  // Dense points of every face (bilinear), inside the body or not, and the faces with one.
  std::size_t faces_with_one = 0;
  auto points_inside = [&](const Points& x) {
    std::size_t inside = 0;
    faces_with_one = 0;
    for (std::size_t f = 0; f < g.faces.rows(); ++f) {
      const auto c = g.faces.row(f);
      const std::size_t before = inside;
      for (int i = 0; i <= 20; ++i)
        for (int k = 0; k <= 20; ++k) {
          const double u = i / 20.0, v = k / 20.0;
          const Vec3 p = (1 - u) * (1 - v) * row3(x, c[0]) + u * (1 - v) * row3(x, c[1]) + u * v * row3(x, c[2]) +
                         (1 - u) * v * row3(x, c[3]);
          inside += body.inside(p);
        }
      faces_with_one += inside > before;
    }
    return inside;
  };
  Points out = g.positions;
  ASSERT_EQ(measure_penetration(out, body).inside, 0u);
  ASSERT_EQ(count_face_centres_inside(g, out, body), 0u);
  ASSERT_GT(points_inside(out), 0u);
  // The cap poking through (radius about 1.26 at the grid) reaches the two faces
  // beside that corner as well: every face with a point inside is counted.
  EXPECT_EQ(faces_with_one, 3u);
  const CollisionReport r = resolve_penetrations(g, out, body);
  EXPECT_EQ(r.faces_inside_before, faces_with_one);
  EXPECT_EQ(r.faces_inside_after, 0u);
  EXPECT_EQ(points_inside(out), 0u);
  EXPECT_EQ(measure_sanity(g, out).flipped_faces, 0u);
}

// A bump of the body smaller than a coarse face's sample spacing: a sphere of
// radius 1 whose top rises 0.1 through one triangle with 10 cm legs, at a point 1.8 cm
// or more from every sample, its corners and its centre far off the body.
struct Bump {
  BodySurface body{test::icosphere(3, 1.0, Vec3(5.5, -0.9, 2.5))};
  Garment g;
  Bump() {
    g.positions.resize(3, 3);
    g.positions << 0.0, 0.0, 0.0, 10.0, 0.0, 0.0, 0.0, 0.0, 10.0;
    g.faces.push_row(std::array<Index, 3>{0, 1, 2});
  }
  // The face's point over the bump's top, (5.5, 2.5) on the plane: barycentric (0.2, 0.55, 0.25).
  Vec3 over_top(const Points& x) const { return 0.2 * row3(x, 0) + 0.55 * row3(x, 1) + 0.25 * row3(x, 2); }
};

TEST(Collision, ABumpBetweenTheSamplesOfACoarseFaceIsPushedOut) {
  const Bump b;
  CollisionOptions o;
  o.clearance = 0.1;
  ASSERT_TRUE(b.body.inside(b.over_top(b.g.positions)));
  // Without probing (probe_radius above the face's size) the samples miss it.
  CollisionOptions blind = o;
  blind.probe_radius = 100.0;
  Points missed = b.g.positions;
  const CollisionReport r0 = resolve_penetrations(b.g, missed, b.body, blind);
  EXPECT_EQ(r0.faces_inside_before, 0u);
  EXPECT_TRUE(b.body.inside(b.over_top(missed)));
  // Probing the points over the body's vertices (and where its edges cross the
  // face's sides) finds it, counts it and pushes the face out of the body.
  Points out = b.g.positions;
  const CollisionReport r = resolve_penetrations(b.g, out, b.body, o);
  EXPECT_EQ(r.faces_inside_before, 1u);
  EXPECT_EQ(r.faces_inside_after, 0u);
  EXPECT_FALSE(b.body.inside(b.over_top(out)));
  EXPECT_GE(b.body.signed_distance(b.over_top(out)), 0.0);
  // ... by what that needs, not a lift of the whole face: its corners move by well under 1 cm.
  for (Index v = 0; v < 3; ++v) EXPECT_LT((row3(out, v) - row3(b.g.positions, v)).norm(), 1.0) << v;
}

TEST(Collision, AFaceOnlyItsCornersClearIsStillAsked) {
  // A small triangle 0.09 above the tip of a narrow pyramid, its corners 0.06
  // from the axis: each corner clears the tip by 0.108 (over the clearance,
  // 0.1), and every corner lies within 0.108 of every other (edge 0.104), but
  // the centre is 0.09 off the tip. A corner's clear ball covers the face only
  // once the clearance is taken off its radius, so the face is asked and pushed.
  BodyMesh pyramid;
  pyramid.vertices.resize(4, 3);
  pyramid.vertices.row(0) << 0.0, 0.0, 0.0;
  for (int k = 0; k < 3; ++k) {
    const double a = 2.0 * M_PI * k / 3.0;
    pyramid.vertices.row(k + 1) << 0.3 * std::cos(a), -1.0, 0.3 * std::sin(a);
  }
  pyramid.triangles = {{0, 2, 1}, {0, 3, 2}, {0, 1, 3}, {1, 2, 3}};
  const BodySurface body(pyramid);
  Garment g;
  g.positions.resize(3, 3);
  for (int k = 0; k < 3; ++k) {
    const double a = 2.0 * M_PI * k / 3.0 + 0.3;
    g.positions.row(k) << 0.06 * std::cos(a), 0.09, 0.06 * std::sin(a);
  }
  g.faces.push_row(std::array<Index, 3>{0, 1, 2});
  CollisionOptions o;
  o.clearance = 0.1;
  o.face_clearance = 0.1;
  Points out = g.positions;
  for (Index v = 0; v < 3; ++v) ASSERT_NEAR(body.closest(row3(out, v)).distance, 0.108, 1e-3) << v;
  const Vec3 centre_before = (row3(out, 0) + row3(out, 1) + row3(out, 2)) / 3.0;
  ASSERT_NEAR(body.closest(centre_before).distance, 0.09, 1e-9);
  const CollisionReport r = resolve_penetrations(g, out, body, o);
  EXPECT_EQ(r.too_close, 0u);  // no vertex of its own
  const Vec3 centre = (row3(out, 0) + row3(out, 1) + row3(out, 2)) / 3.0;
  EXPECT_GE(body.closest(centre).distance, 0.099);
  EXPECT_EQ(r.moved, 3u);
}

TEST(Collision, SphereShellPartlyInsideComesOutBitIdenticalForAnyThreadCount) {
  const BodySurface body(sphere_body(3, 10.0));
  const Garment g = sphere_garment(3, 10.4);
  Points shifted = g.positions.rowwise() + Eigen::RowVector3d(1.5, 0, 0);
  Points one = shifted, two = shifted;
  CollisionReport r1, r2;
  {
    ThreadLimit limit(1);
    r1 = resolve_penetrations(g, one, body);
  }
  r2 = resolve_penetrations(g, two, body);
  EXPECT_GT(r1.inside_before, 10u);
  EXPECT_EQ(r1.inside_after, 0u);
  EXPECT_TRUE(one == two);
  EXPECT_EQ(r1.moved, r2.moved);
  EXPECT_EQ(measure_penetration(one, body).inside, 0u);
  EXPECT_EQ(measure_sanity(g, one).flipped_faces, 0u);
  for (Eigen::Index i = 0; i < one.rows(); ++i) EXPECT_GT(body.closest(row3(one, static_cast<Index>(i))).distance, 0.2 - 1e-9);
  CollisionOptions negative;
  negative.clearance = -1.0;
  EXPECT_THROW(resolve_penetrations(g, shifted, body, negative), Error);
}

// A caller resolving one garment on many bodies keeps its vertex adjacency: the
// same result as the step making it itself, and one of another garment is refused.
TEST(Collision, AGivenVertexAdjacencyGivesTheSameResult) {
  const BodySurface body(sphere_body(3, 10.0));
  const Garment g = sphere_garment(3, 10.4);
  const Points shifted = g.positions.rowwise() + Eigen::RowVector3d(1.5, 0, 0);
  Points own = shifted, given = shifted;
  const CollisionReport r_own = resolve_penetrations(g, own, body);
  const Csr adjacency = vertex_adjacency(g);
  CollisionOptions with;
  with.adjacency = &adjacency;
  const CollisionReport r_given = resolve_penetrations(g, given, body, with);
  EXPECT_GT(r_own.moved, 10u);
  EXPECT_TRUE(own == given);
  EXPECT_EQ(r_own.to_json(), r_given.to_json());
  const Csr other = vertex_adjacency(sphere_garment(2, 10.4));
  with.adjacency = &other;
  EXPECT_THROW(resolve_penetrations(g, given, body, with), Error);
  // Its vertex faces too.
  const Csr faces_of_vertex = vertex_faces(g);
  with.adjacency = &adjacency;
  with.faces_of_vertex = &faces_of_vertex;
  Points given_faces = shifted;
  const CollisionReport r_faces = resolve_penetrations(g, given_faces, body, with);
  EXPECT_TRUE(own == given_faces);
  EXPECT_EQ(r_own.to_json(), r_faces.to_json());
  const Csr other_faces = vertex_faces(sphere_garment(2, 10.4));
  with.faces_of_vertex = &other_faces;
  EXPECT_THROW(resolve_penetrations(g, given_faces, body, with), Error);
}

// The rounds after the first ask only the faces of the vertices they check when
// those are few against the garment (collision.cpp), else every face. Far
// copies that never move make the same rounds few: the part on the body comes
// out the same, and the copies as they were.
TEST(Collision, FarPiecesThatNeverMoveLeaveTheResultAsItIs) {
  // A 5 x 5 grid of 4 cm quads at y = 9.65 over a sphere of radius 10: the
  // corners nearest its top are too close (0.055 off it, clearance 0.1), so the
  // middle face waits for round 2, where the body pokes through its middle.
  const BodySurface body(sphere_body(4, 10.0));
  const Garment g = coarse_grid(9.65);
  const Garment padded = with_far_copies(g, 40);
  CollisionOptions o;
  o.clearance = 0.1;
  const Eigen::Index n = g.positions.rows();
  Points alone = g.positions, with = padded.positions;
  const CollisionReport r_alone = resolve_penetrations(g, alone, body, o);
  const CollisionReport r_with = resolve_penetrations(padded, with, body, o);
  EXPECT_GT(r_alone.rounds, 1u);
  EXPECT_GT(r_alone.too_close, 0u);
  EXPECT_EQ(r_alone.faces_inside_after, 0u);
  EXPECT_TRUE(with.topRows(n) == alone);
  EXPECT_TRUE(with.bottomRows(with.rows() - n) == padded.positions.bottomRows(with.rows() - n));
  EXPECT_EQ(r_alone.moved, r_with.moved);
  EXPECT_EQ(r_alone.rounds, r_with.rounds);
}

// A correction that would turn faces over is evened out over their corners
// (unfold.hpp). A small region's faces are listed from its vertices, a larger
// one's from a scan: the same faces either way, so the same correction on a
// 4 x 4 grid alone (the scan) and with far copies (the list).
TEST(Collision, UnfoldEvensOutACorrectionThatTurnsFacesOverTheSameForFewOrManyVertices) {
  const Garment g = test::quad_grid(4, 4, 1.0, [](double, double) { return 0.0; });
  const Garment padded = with_far_copies(g, 20);
  // Vertex 5 (1, 0, 1) pushed past its neighbours at x = 2, vertex 6 (1, 0, 2) a little.
  const std::vector<Index> region = {5, 6};
  const auto run = [&](const Garment& garment) {
    std::vector<long> slot(garment.vertex_count(), -1);
    slot[5] = 0, slot[6] = 1;
    std::vector<Vec3> disp = {Vec3(2.5, 0, 0), Vec3(0.5, 0, 0)};
    const Csr faces_of_vertex = vertex_faces(garment);
    unfold(garment, garment.positions, region, [&]() -> const Csr& { return faces_of_vertex; },
           [&](Index v) { return slot[v]; }, 10, disp);
    return disp;
  };
  const std::vector<Vec3> scanned = run(g), listed = run(padded);
  EXPECT_LT(scanned[0].x(), 1.0);  // evened out, not left at 2.5
  EXPECT_TRUE(scanned == listed);
  Points moved = g.positions;
  moved.row(5) += scanned[0].transpose();
  moved.row(6) += scanned[1].transpose();
  for (std::size_t f = 0; f < g.faces.rows(); ++f)
    EXPECT_GT(face_normal(moved, g.faces.row(f)).dot(face_normal(g.positions, g.faces.row(f))), 0.0) << f;
}

// Layers: a fine shell too close to the body under a coarse one clear of it.
// The collision step pushes the inner shell out past the middle of the outer
// shell's faces; with the layers' order bound on the input, the outer faces
// go up with it (the shared suit on M_heavier: the trousers through the jacket).
// The check is a ray from the sphere's centre through each inner vertex, cut
// with the outer shell's triangles.
// Two icosphere shells about a sphere body of radius 10: the inner one (layer 1)
// and the outer one over it (layer 2), with their layer covers (gap 0.03).
// Subdivision levels 3 and 2 unless given.
struct Shells {
  BodyMesh sphere = sphere_body(4, 10.0);
  Garment g;
  Garment outer;
  Index first_outer = 0;
  std::vector<LayerCover> covers;

  Shells(double inner_radius, double outer_radius, int inner_level = 3, int outer_level = 2) {
    const BodySurface body(sphere);
    const Garment inner = sphere_garment(inner_level, inner_radius);
    outer = sphere_garment(outer_level, outer_radius);
    g.positions.resize(inner.positions.rows() + outer.positions.rows(), 3);
    g.positions << inner.positions, outer.positions;
    for (std::size_t f = 0; f < inner.faces.rows(); ++f) g.faces.push_row(inner.faces.row(f));
    first_outer = Index(inner.positions.rows());
    for (std::size_t f = 0; f < outer.faces.rows(); ++f) {
      std::array<Index, 3> t;
      for (int k = 0; k < 3; ++k) t[std::size_t(k)] = outer.faces.row(f)[std::size_t(k)] + first_outer;
      g.faces.push_row(t);
    }
    std::vector<std::uint32_t> layer(g.vertex_count(), 1);
    std::fill(layer.begin() + first_outer, layer.end(), 2u);
    covers = bind_layer_order(g, layer, body, 2.0, 0.03);
  }

  // Where each inner vertex lies under the outer shell: how far out along its
  // ray the outer shell is, less the vertex's own distance from the centre
  // (the least over the inner vertices).
  double below_outer(const Points& x) const {
    double least = std::numeric_limits<double>::infinity();
    for (Index i = 0; i < first_outer; ++i) {
      const Vec3 d = row3(x, i).normalized();
      for (std::size_t f = 0; f < outer.faces.rows(); ++f) {
        const auto t = outer.faces.row(f);
        const Vec3 a = row3(x, t[0] + first_outer), e1 = row3(x, t[1] + first_outer) - a, e2 = row3(x, t[2] + first_outer) - a;
        const Vec3 h = d.cross(e2);
        const double det = e1.dot(h);
        if (std::abs(det) < 1e-12) continue;
        const double u = -a.dot(h) / det;
        const Vec3 q = (-a).cross(e1);
        const double v = d.dot(q) / det, along = e2.dot(q) / det;
        if (u < 0.0 || v < 0.0 || u + v > 1.0 || along <= 0.0) continue;
        least = std::min(least, along - row3(x, i).norm());
      }
    }
    return least;
  }
};

TEST(Collision, AnInnerLayerPushedOffTheBodyStaysUnderTheOuterOne) {
  const Shells s(10.1, 10.28);
  const BodySurface body(s.sphere);
  const Garment& g = s.g;
  const std::vector<LayerCover>& covers = s.covers;
  const Index first_outer = s.first_outer;
  ASSERT_GT(covers.size(), std::size_t(first_outer) / 2) << "the outer shell covers the inner one";
  for (const LayerCover& c : covers) {
    EXPECT_LT(c.inner, first_outer) << "only the inner shell is covered";
    EXPECT_GT(cover_height(c, g.positions).first, 0.0);
  }
  const auto below_outer = [&](const Points& x) { return s.below_outer(x); };
  ASSERT_GT(below_outer(g.positions), 0.0) << "the input has the outer shell over the inner one";

  Points without = g.positions, with = g.positions;
  const CollisionReport r_without = resolve_penetrations(g, without, body);
  ASSERT_LT(below_outer(without), 0.0) << "the fixture must push the inner shell through the outer one";
  CollisionOptions o;
  o.layers = &covers;
  const CollisionReport r = resolve_penetrations(g, with, body, o);
  EXPECT_EQ(r.layer_covers, covers.size());
  EXPECT_EQ(r.layers_crossed_before, 0u);  // the step's own pushes cross them
  EXPECT_EQ(r.layers_crossed_after, 0u);
  EXPECT_GT(below_outer(with), 0.0);
  EXPECT_EQ(r.inside_after, 0u);
  EXPECT_EQ(measure_sanity(g, with).flipped_faces, 0u);
  // The clearance, but for the step's rounding (an inner vertex taken down to it).
  for (Index i = 0; i < g.vertex_count(); ++i) EXPECT_GT(body.closest(row3(with, i)).distance, 0.2 - 1e-7);
  EXPECT_EQ(r_without.layer_covers, 0u);
  // Threads do not change it.
  Points one = g.positions;
  {
    ThreadLimit limit(1);
    resolve_penetrations(g, one, body, o);
  }
  EXPECT_TRUE(one == with);
}

// An inner layer its faces push out, round after round, takes the layer over it
// along: a coarse inner shell whose corners clear the body and whose faces'
// middles do not. Taken down under the outer shell by its cover, it was pushed
// out again by its faces in the next round, and ended through the outer shell
// (the real outfit's jeans through the dress at the back waist).
TEST(Collision, AnInnerLayerItsFacesPushOutTakesTheLayerOverAlong) {
  const Shells s(10.5, 10.75, 1, 3);
  const BodySurface body(s.sphere);
  ASSERT_GT(s.covers.size(), std::size_t(s.first_outer) / 2);
  ASSERT_GT(s.below_outer(s.g.positions), 0.0) << "the input has the outer shell over the inner one";
  for (Index i = 0; i < s.first_outer; ++i) ASSERT_GT(body.closest(row3(s.g.positions, i)).distance, 0.4);
  CollisionOptions o;
  o.layers = &s.covers;
  Points x = s.g.positions;
  const CollisionReport r = resolve_penetrations(s.g, x, body, o);
  EXPECT_GT(r.faces_inside_before, 0u) << "the inner shell's faces must dip into the body";
  EXPECT_EQ(r.inside_after, 0u);
  EXPECT_EQ(r.faces_inside_after, 0u);
  EXPECT_EQ(r.layers_crossed_after, 0u);
  EXPECT_GT(s.below_outer(x), 0.0);
  EXPECT_EQ(measure_sanity(s.g, x).flipped_faces, 0u);
}

}  // namespace
}  // namespace refit
