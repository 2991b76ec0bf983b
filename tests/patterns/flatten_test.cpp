// Flattening one piece (patterns/flatten.hpp): a developable piece comes out
// isometric, a flat one rigidly, orientation is kept, the result does not depend
// on the thread count, a closed piece is refused.
#include "patterns/pattern_fixtures.hpp"

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/patterns/flatten.hpp>
#include <refit/patterns/measures.hpp>

#include <gtest/gtest.h>

#include <cmath>

namespace refit {
namespace {

// The worst |log s| over the triangles.
double worst_stretch(const test::Piece& p, const Points2& uv) {
  double worst = 0;
  for (const Triangle& t : p.triangles) {
    Points x(3, 3);
    Points2 u(3, 2);
    for (int i = 0; i < 3; ++i) {
      x.row(i) = p.xyz.row(t[i]);
      u.row(i) = uv.row(t[i]);
    }
    worst = std::max(worst, log_stretch(face_singular_values(x, u)));
  }
  return worst;
}

TEST(Flatten, DevelopablePieceComesOutIsometric) {
  const test::Piece p = test::cylinder_piece(30, 20, 10.0, 20.0, 1.5 * M_PI, 0.0);
  const Flattening f = flatten_piece(p.xyz, p.triangles);
  EXPECT_TRUE(f.converged);
  EXPECT_LT(worst_stretch(p, f.uv), 1e-6);
}

TEST(Flatten, FlatPieceComesBackRigidly) {
  const test::Piece p = test::flat_piece(12, 9);
  const Flattening f = flatten_piece(p.xyz, p.triangles);
  // Distances between all pairs of vertices are kept.
  double worst = 0;
  for (Eigen::Index i = 0; i < p.xyz.rows(); i += 7)
    for (Eigen::Index j = 0; j < p.xyz.rows(); j += 5)
      worst = std::max(worst, std::abs((p.xyz.row(i) - p.xyz.row(j)).norm() - (f.uv.row(i) - f.uv.row(j)).norm()));
  EXPECT_LT(worst, 1e-6);
}

TEST(Flatten, KeepsTheTrianglesOrientation) {
  const test::Piece p = test::cylinder_piece(24, 16, 10.0, 20.0, M_PI, 1.0);  // bumpy: not developable
  const Flattening f = flatten_piece(p.xyz, p.triangles);
  for (const Triangle& t : p.triangles) {
    const Eigen::Vector2d a = f.uv.row(t[1]) - f.uv.row(t[0]), b = f.uv.row(t[2]) - f.uv.row(t[0]);
    ASSERT_GT(a.x() * b.y() - a.y() * b.x(), 0.0);
  }
  // Not developable: some stretch is left, and it is reported as such.
  EXPECT_GT(worst_stretch(p, f.uv), 1e-3);
}

TEST(Flatten, ResultDoesNotDependOnTheThreadCount) {
  const test::Piece p = test::cylinder_piece(80, 60, 10.0, 20.0, M_PI, 1.0);
  Points2 one, two;
  {
    const ThreadLimit limit(1);
    one = flatten_piece(p.xyz, p.triangles).uv;
  }
  {
    const ThreadLimit limit(2);
    two = flatten_piece(p.xyz, p.triangles).uv;
  }
  EXPECT_EQ(one, two);  // bit for bit
}

TEST(Flatten, HeldEdgesKeepTheirLength) {
  const test::Piece p = test::cylinder_piece(24, 16, 10.0, 20.0, M_PI, 1.0);
  // Hold the outline at 1.02 times its 3D length.
  std::vector<HeldEdge> held;
  for (const auto& [a, b] : test::border_edges(p)) held.push_back({a, b, 1.02 * (p.xyz.row(a) - p.xyz.row(b)).norm()});
  const auto outline = [&](const Points2& uv) {
    double l2 = 0, l3 = 0;
    for (const HeldEdge& h : held) {
      l2 += (uv.row(h.a) - uv.row(h.b)).norm();
      l3 += h.length;
    }
    return l2 / l3 - 1;
  };
  const Flattening plain = flatten_piece(p.xyz, p.triangles);
  const Flattening f = flatten_piece(p.xyz, p.triangles, {}, held);
  EXPECT_LT(std::abs(outline(f.uv)), 0.002);
  EXPECT_GT(std::abs(outline(plain.uv)), 5 * std::abs(outline(f.uv)));
  // From a start: the same minimum.
  const Flattening again = flatten_piece(p.xyz, p.triangles, {}, held, &plain.uv);
  EXPECT_EQ(again.conformal_iterations, 0);
  EXPECT_LT(std::abs(outline(again.uv) - outline(f.uv)), 1e-4);
  const std::vector<HeldEdge> bad = {{0, 100000, 1.0}};
  EXPECT_THROW(flatten_piece(p.xyz, p.triangles, {}, bad), Error);
}

TEST(Flatten, RefusesAClosedPiece) {
  // A tetrahedron: no boundary.
  Points xyz(4, 3);
  xyz << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  const std::vector<Triangle> tris = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  EXPECT_THROW(flatten_piece(xyz, tris), Error);
  const std::vector<Triangle> bad = {{0, 1, 7}};
  EXPECT_THROW(flatten_piece(xyz, bad), Error);
}

}  // namespace
}  // namespace refit
