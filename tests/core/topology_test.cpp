// Topology statistics and boundary loops on small hand-made garments, including
// the non-manifold cases CAD files contain.
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/topology.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <map>
#include <set>
#include <utility>

namespace refit {
namespace {

Garment make(std::size_t vertices, std::initializer_list<std::initializer_list<Index>> faces,
             std::initializer_list<std::initializer_list<Index>> lines = {},
             std::initializer_list<std::initializer_list<Index>> points = {}) {
  Garment g;
  g.positions = Points::Zero(static_cast<Eigen::Index>(vertices), 3);
  for (std::size_t i = 0; i < vertices; ++i) g.positions(static_cast<Eigen::Index>(i), 0) = double(i);
  for (auto f : faces) g.faces.push_row(std::vector<Index>(f));
  for (auto l : lines) g.lines.push_row(std::vector<Index>(l));
  for (auto p : points) g.points.push_row(std::vector<Index>(p));
  return g;
}

// Each loop is a closed cycle of boundary edges; no boundary edge is used twice.
void expect_valid_loops(const Garment& g, const std::vector<std::vector<Index>>& loops) {
  std::multiset<std::pair<Index, Index>> face_edges;
  for (std::size_t f = 0; f < g.faces.rows(); ++f) {
    const auto r = g.faces.row(f);
    for (std::size_t k = 0; k < r.size(); ++k)
      face_edges.insert(std::minmax(r[k], r[(k + 1) % r.size()]));
  }
  std::set<std::pair<Index, Index>> used;
  for (const auto& loop : loops) {
    ASSERT_GE(loop.size(), 2u);
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const auto e = std::minmax(loop[k], loop[(k + 1) % loop.size()]);
      EXPECT_EQ(face_edges.count(e), 1u) << "loop edge " << e.first << "-" << e.second << " is not a boundary edge";
      EXPECT_TRUE(used.insert(e).second) << "boundary edge used twice";
    }
  }
}

TEST(Topology, ThreeFacesOnOneEdgeIsNonManifold) {
  const Garment g = make(5, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  const TopologyStats s = topology_stats(g);
  EXPECT_EQ(s.faces, 3u);
  EXPECT_EQ(s.edges, 7u);
  EXPECT_EQ(s.non_manifold_edges, 1u);
  EXPECT_EQ(s.boundary_edges, 6u);
  EXPECT_EQ(s.components, 1u);
  EXPECT_EQ(s.unreferenced_vertices, 0u);
  // Vertices 0 and 1 have three boundary edges each, so the six cannot all be
  // chained into closed loops: one closed 4-cycle, the open rest (0-4-1) skipped.
  const auto loops = boundary_loops(g);
  expect_valid_loops(g, loops);
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_EQ(loops[0], (std::vector<Index>{0, 3, 1, 2}));
  EXPECT_EQ(s.boundary_loops, 1u);
}

TEST(Topology, HangingLineLoosePointAndUnreferencedVertex) {
  // Triangle 0-1-2, a hanging line 2-3-4, a loose point 5 and an unreferenced vertex 6.
  const Garment g = make(7, {{0, 1, 2}}, {{2, 3, 4}}, {{5}});
  const TopologyStats s = topology_stats(g);
  EXPECT_EQ(s.vertices, 7u);
  EXPECT_EQ(s.faces, 1u);
  EXPECT_EQ(s.lines, 1u);
  EXPECT_EQ(s.points, 1u);
  EXPECT_EQ(s.unreferenced_vertices, 1u);
  EXPECT_EQ(s.edges, 3u);  // line edges are not face edges
  EXPECT_EQ(s.boundary_edges, 3u);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  EXPECT_EQ(s.boundary_loops, 1u);
  EXPECT_EQ(s.components, 2u);  // triangle + line, and the point
}

TEST(Topology, EachVertexOfAPointStatementIsItsOwnComponent) {
  // `p 4 5 6` lists three separate points (OBJ spec); vertex 3 is unreferenced.
  const Garment g = make(7, {{0, 1, 2}}, {}, {{4, 5, 6}, {2}});
  const TopologyStats s = topology_stats(g);
  EXPECT_EQ(s.points, 2u);
  EXPECT_EQ(s.unreferenced_vertices, 1u);
  EXPECT_EQ(s.components, 4u);
}

TEST(Topology, TwoComponents) {
  const Garment g = make(6, {{0, 1, 2}, {3, 4, 5}});
  const TopologyStats s = topology_stats(g);
  EXPECT_EQ(s.components, 2u);
  EXPECT_EQ(s.boundary_loops, 2u);
  const auto loops = boundary_loops(g);
  ASSERT_EQ(loops.size(), 2u);
  EXPECT_EQ(loops[0], (std::vector<Index>{0, 1, 2}));
  EXPECT_EQ(loops[1], (std::vector<Index>{3, 4, 5}));
}

TEST(Topology, QuadStripHasOneLoopInFaceOrder) {
  // 0 1 2 3 along the bottom, 4 5 6 7 along the top.
  const Garment g = make(8, {{0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}});
  const TopologyStats s = topology_stats(g);
  EXPECT_EQ(s.edges, 10u);
  EXPECT_EQ(s.boundary_edges, 8u);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  EXPECT_EQ(s.components, 1u);
  const auto loops = boundary_loops(g);
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_EQ(loops[0], (std::vector<Index>{0, 1, 2, 3, 7, 6, 5, 4}));
  EXPECT_EQ(s.boundary_loops, 1u);
}

TEST(Topology, OpenCylinderHasTwoLoops) {
  constexpr Index n = 6;  // bottom ring 0..5, top ring 6..11
  Garment g = make(2 * n, {});
  for (Index i = 0; i < n; ++i) {
    const Index j = (i + 1) % n;
    g.faces.push_row(std::vector<Index>{i, j, j + n, i + n});
  }
  const TopologyStats s = topology_stats(g);
  EXPECT_EQ(s.edges, 3u * n);
  EXPECT_EQ(s.boundary_edges, 2u * n);
  EXPECT_EQ(s.boundary_loops, 2u);
  EXPECT_EQ(s.components, 1u);
  const auto loops = boundary_loops(g);
  ASSERT_EQ(loops.size(), 2u);
  expect_valid_loops(g, loops);
  EXPECT_EQ(loops[0], (std::vector<Index>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(loops[1], (std::vector<Index>{6, 11, 10, 9, 8, 7}));
}

TEST(Topology, ClosedCubeHasNoBoundary) {
  const Garment g = make(8, {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}});
  const TopologyStats s = topology_stats(g);
  EXPECT_EQ(s.edges, 12u);
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.boundary_loops, 0u);
  EXPECT_EQ(s.components, 1u);
}

TEST(Topology, BowTieSplitsIntoTwoSimpleLoops) {
  // Two triangles sharing only vertex 0: four boundary edges meet there.
  const Garment g = make(5, {{0, 1, 2}, {0, 3, 4}});
  const auto loops = boundary_loops(g);
  expect_valid_loops(g, loops);
  ASSERT_EQ(loops.size(), 2u);
  EXPECT_EQ(loops[0].size(), 3u);
  EXPECT_EQ(loops[1].size(), 3u);
  EXPECT_EQ(topology_stats(g).components, 1u);
}

TEST(Topology, DegenerateFaceWithRepeatedVertexIsKept) {
  // Face 0-1-1-2 has a repeated vertex: its zero-length side is no edge.
  const Garment g = make(3, {{0, 1, 1, 2}});
  const TopologyStats s = topology_stats(g);
  EXPECT_EQ(s.faces, 1u);
  EXPECT_EQ(s.edges, 3u);
  EXPECT_EQ(s.boundary_loops, 1u);
  EXPECT_EQ(boundary_loops(g)[0], (std::vector<Index>{0, 1, 2}));
}

TEST(Topology, BoundaryVerticesOfWeldedSoupAreTheOuterRing) {
  // Two triangles of a square, as a soup (six vertices): apart, all six
  // vertices are on the boundary; welded (3 -> 0, 4 -> 2), the shared diagonal
  // 0-2 is used twice and the outer ring 0, 1, 2, 5 is left.
  const Garment g = make(6, {{0, 1, 2}, {3, 4, 5}});
  std::vector<Index> apart = {0, 1, 2, 3, 4, 5};
  EXPECT_EQ(boundary_vertices(g, apart), apart);
  const std::vector<Index> welded = {0, 1, 2, 0, 2, 5};
  EXPECT_EQ(boundary_vertices(g, welded), (std::vector<Index>{0, 1, 2, 5}));
  // A triangle welded onto one edge: its side 0-0 is no edge, 0-2 is used twice.
  EXPECT_TRUE(boundary_vertices(make(3, {{0, 1, 2}}), {0, 0, 2}).empty());
  // A closed cube has no boundary.
  const Garment cube = make(8, {{0, 1, 2, 3}, {4, 7, 6, 5}, {0, 4, 5, 1}, {1, 5, 6, 2}, {2, 6, 7, 3}, {3, 7, 4, 0}});
  EXPECT_TRUE(boundary_vertices(cube, {0, 1, 2, 3, 4, 5, 6, 7}).empty());
  EXPECT_THROW(boundary_vertices(g, {0, 1}), Error);
}

TEST(Topology, IndexOutOfRangeThrows) {
  const Garment g = make(3, {{0, 1, 7}});
  EXPECT_THROW(topology_stats(g), Error);
  EXPECT_THROW(boundary_loops(g), Error);
}

// A grid of W x H quads, large enough for many parallel chunks, with a hole of
// quads left out, a triangulated band, a repeated-corner face and a fin (a third
// face on one edge): the edge counts match a plain count, every loop is valid,
// and one and two threads give the same loops.
TEST(Topology, LargeGridSameForOneAndTwoThreadsAndMatchesAPlainCount) {
  const Index W = 240, H = 120;
  Garment g;
  g.positions = Points::Zero((W + 1) * (H + 1) + 1, 3);
  const auto id = [&](Index x, Index y) { return y * (W + 1) + x; };
  for (Index y = 0; y <= H; ++y)
    for (Index x = 0; x <= W; ++x) g.positions.row(id(x, y)) << double(x), double(y), 0.0;
  for (Index y = 0; y < H; ++y)
    for (Index x = 0; x < W; ++x) {
      if (x >= 100 && x < 110 && y >= 50 && y < 55) continue;  // the hole
      if (y == 7) {
        g.faces.push_row(std::vector<Index>{id(x, y), id(x + 1, y), id(x + 1, y + 1)});
        g.faces.push_row(std::vector<Index>{id(x, y), id(x + 1, y + 1), id(x, y + 1)});
      } else if (x == 3 && y == 90) {
        g.faces.push_row(std::vector<Index>{id(x, y), id(x + 1, y), id(x + 1, y), id(x + 1, y + 1), id(x, y + 1)});
      } else {
        g.faces.push_row(std::vector<Index>{id(x, y), id(x + 1, y), id(x + 1, y + 1), id(x, y + 1)});
      }
    }
  g.faces.push_row(std::vector<Index>{id(20, 20), id(21, 20), Index((W + 1) * (H + 1))});  // fin
  std::map<std::pair<Index, Index>, int> uses;
  for (std::size_t f = 0; f < g.faces.rows(); ++f) {
    const auto r = g.faces.row(f);
    for (std::size_t k = 0; k < r.size(); ++k)
      if (r[k] != r[(k + 1) % r.size()]) ++uses[std::minmax(r[k], r[(k + 1) % r.size()])];
  }
  std::size_t boundary = 0, non_manifold = 0;
  for (const auto& [e, k] : uses) boundary += k == 1, non_manifold += k >= 3;

  TopologyStats one, two;
  std::vector<std::vector<Index>> loops_one, loops_two;
  {
    const ThreadLimit limit(1);
    one = topology_stats(g);
    loops_one = boundary_loops(g);
  }
  {
    const ThreadLimit limit(2);
    two = topology_stats(g);
    loops_two = boundary_loops(g);
  }
  EXPECT_EQ(one.edges, uses.size());
  EXPECT_EQ(one.boundary_edges, boundary);
  EXPECT_EQ(one.non_manifold_edges, 1u);
  EXPECT_EQ(non_manifold, 1u);
  EXPECT_EQ(one.edges, two.edges);
  EXPECT_EQ(one.boundary_edges, two.boundary_edges);
  EXPECT_EQ(one.boundary_loops, two.boundary_loops);
  EXPECT_EQ(loops_one, loops_two);
  ASSERT_EQ(loops_one.size(), 2u);  // the rim and the hole (the fin's two edges end without closing)
  EXPECT_EQ(loops_one[0].size(), 2u * (W + H));
  EXPECT_EQ(loops_one[1].size(), 2u * (10 + 5));
  expect_valid_loops(g, loops_one);
}

TEST(Topology, VertexFacesListEachCornersFacesOnceInOrder) {
  // Two triangles and a quad with a repeated corner; vertex 5 is only on a line.
  const Garment g = make(6, {{0, 1, 2}, {2, 1, 3}, {3, 4, 4, 1}}, {{4, 5}});
  const Csr vf = vertex_faces(g);
  ASSERT_EQ(vf.rows(), 6u);
  const std::vector<std::vector<Index>> expected = {{0}, {0, 1, 2}, {0, 1}, {1, 2}, {2}, {}};
  for (std::size_t v = 0; v < 6; ++v)
    EXPECT_EQ(std::vector<Index>(vf.row(v).begin(), vf.row(v).end()), expected[v]) << v;
}

}  // namespace
}  // namespace refit
