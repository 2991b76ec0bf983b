// Surface shape optimisation (paper section 5) on small fixtures of our own:
// a plane patch, a tube, a sphere, a point grid.
#include "support/shapes.hpp"

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/surface/agents.hpp>
#include <refit/surface/surface.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>

namespace refit {
namespace {

template <class H>
Garment patch(int nx, int nz, double s, H&& height, double x0 = 0.0, double z0 = 0.0) {
  return test::quad_grid(nx, nz, s, height, x0, z0);
}
Garment flat_patch(int n, double s, double x0 = 0.0, double z0 = 0.0) {
  return patch(n, n, s, [](double, double) { return 0.0; }, x0, z0);
}

// Points on a sphere (Fibonacci spiral).
Points sphere_points(int n, double radius) {
  Points p(n, 3);
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double y = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - y * y), t = golden * i;
    p.row(i) << radius * r * std::cos(t), radius * y, radius * r * std::sin(t);
  }
  return p;
}

bool same_bytes(const Points& a, const Points& b) {
  return a.rows() == b.rows() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

TEST(SurfaceAgents, OneAgentPerVoxelNearestItsCentre) {
  const Garment g = patch(41, 41, 0.25, [](double x, double z) { return 0.5 * std::sin(x) * std::cos(z); });
  const VoxelGrid grid = make_voxel_grid(g, Points(0, 3), 1.0);
  const GarmentAgents ga = select_agents(g, grid);
  ASSERT_GT(ga.size(), 50u);
  const Points a = ga.positions(g.positions);
  std::vector<std::uint64_t> keys;
  for (std::size_t i = 0; i < ga.size(); ++i) {
    const auto c = grid.cell(row3(a, Index(i)));
    EXPECT_EQ(VoxelGrid::morton(c), ga.voxel[i]);
    keys.push_back(ga.voxel[i]);
    // No garment vertex in the same voxel is nearer the centre (vertices are samples too).
    const double d = (row3(a, Index(i)) - grid.centre(c)).norm();
    for (Index v = 0; v < g.vertex_count(); ++v)
      if (grid.cell(row3(g.positions, v)) == c) {
        EXPECT_LE(d, (row3(g.positions, v) - grid.centre(c)).norm() + 1e-6);
      }
  }
  EXPECT_TRUE(std::is_sorted(keys.begin(), keys.end()));
  EXPECT_EQ(std::adjacent_find(keys.begin(), keys.end()), keys.end());  // one per voxel
}

TEST(SurfaceAgents, SamplesFacesHangingEdgesPointsAndLooseVertices) {
  // A big triangle, a long hanging edge and a loose vertex: all must produce agents.
  Garment g;
  g.positions.resize(6, 3);
  g.positions << 0, 0, 0, 10, 0, 0, 0, 0, 10,  // triangle
      20, 0, 0, 20, 10, 0,                       // `l` segment
      30, 30, 30;                                // unreferenced
  g.faces.push_row(std::array<Index, 3>{0, 1, 2});
  g.lines.push_row(std::array<Index, 2>{3, 4});
  const VoxelGrid grid = make_voxel_grid(g, Points(0, 3), 1.0);
  const GarmentAgents ga = select_agents(g, grid);
  const Points a = ga.positions(g.positions);
  std::size_t in_face = 0, on_line = 0, loose = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    const Vec3 p = a.row(i).transpose();
    if (p.y() == 0.0 && p.x() <= 10 && p.z() <= 10) ++in_face;
    if (p.x() == 20.0 && p.z() == 0.0) ++on_line;
    if (p == Vec3(30, 30, 30)) ++loose;
  }
  EXPECT_GE(in_face, 40u);  // about half of the 10 x 10 voxels under the triangle
  EXPECT_GE(on_line, 9u);   // one per voxel along the 10-long edge
  EXPECT_EQ(loose, 1u);
}

TEST(SurfaceAgents, SelectionIsThreadCountIndependent) {
  const Garment g = patch(120, 120, 0.1, [](double x, double z) { return std::sin(x + z); });
  const VoxelGrid grid = make_voxel_grid(g, Points(0, 3), 0.37);
  GarmentAgents one, two;
  {
    ThreadLimit limit(1);
    one = select_agents(g, grid);
  }
  {
    ThreadLimit limit(2);
    two = select_agents(g, grid);
  }
  EXPECT_EQ(one.vertex, two.vertex);
  EXPECT_EQ(one.weight, two.weight);
}

TEST(SurfaceOneRing, SquareGridGivesTheFourAxisNeighbours) {
  Points p(25, 3);
  for (int i = 0; i < 5; ++i)
    for (int k = 0; k < 5; ++k) p.row(i * 5 + k) << i, 0, k;
  const Csr ring = build_one_rings(p, 3.0);
  std::vector<Index> centre(ring.row(12).begin(), ring.row(12).end());
  std::sort(centre.begin(), centre.end());
  EXPECT_EQ(centre, (std::vector<Index>{7, 11, 13, 17}));
  // A corner: its two axis neighbours; the diagonal (p - a_c).(a_c - a) = 0 is excluded.
  std::vector<Index> corner(ring.row(0).begin(), ring.row(0).end());
  std::sort(corner.begin(), corner.end());
  EXPECT_EQ(corner, (std::vector<Index>{1, 5}));
}

TEST(SurfaceOneRing, NoCandidateInsideTheHull) {
  // Section 5.1: the planes define a convex hull around a that holds no other agent.
  const Points p = sphere_points(600, 10.0);
  const Csr ring = build_one_rings(p, 6.0);
  for (std::size_t a = 0; a < ring.rows(); ++a) {
    ASSERT_GE(ring.row_size(a), 3u);
    const Vec3 pa = row3(p, Index(a));
    for (Index q = 0; q < p.rows(); ++q) {
      if (q == a || (row3(p, q) - pa).norm() >= 6.0) continue;
      bool cut = false;
      for (Index c : ring.row(a)) cut |= (row3(p, q) - row3(p, c)).dot(row3(p, c) - pa) >= 0.0;
      EXPECT_TRUE(cut) << "agent " << q << " lies inside the one-ring hull of " << a;
    }
  }
}

TEST(SurfaceEncoding, ExactAtRestAndWeaklyDiagonallyDominant) {
  for (const Points& p : {sphere_points(800, 5.0), ([] {
                            const Garment g = patch(30, 30, 0.3, [](double x, double z) { return 0.3 * x * z; });
                            return g.positions;
                          })()}) {
    const AgentRows rows = encode_agents(p, build_one_rings(p, 3.0));
    ASSERT_EQ(rows.size(), std::size_t(p.rows()));
    EXPECT_LT(max_residual(rows, p), 1e-12);
    for (std::size_t a = 0; a < rows.size(); ++a) {
      double off = 0.0;
      for (Index k = rows.ring.offsets[a]; k < rows.ring.offsets[a + 1]; ++k) {
        EXPECT_GE(rows.weight[k], 0.0);
        off += std::abs(rows.weight[k]);
      }
      ASSERT_GT(rows.diag[a], 0.0);
      EXPECT_GE(std::abs(rows.diag[a]), off * (1 - 1e-12));  // |a_jj| >= sum |a_ji|
    }
  }
}

TEST(SurfaceFrames, MinimalSpanningTreeOrientsASphereConsistently) {
  const Points p = sphere_points(700, 4.0);
  Csr ring = build_one_rings(p, 2.0);
  std::vector<std::uint8_t> open;
  order_rings(p, ring, open);
  const Points n = fan_normals(p, ring, open);
  const auto flip = orient_normals(n, ring);
  std::size_t outward = 0, flipped_raw = 0;
  for (Index a = 0; a < p.rows(); ++a) {
    const double d = flip[a] * row3(n, a).dot(row3(p, a).normalized());
    EXPECT_GT(std::abs(d), 0.9);
    outward += d > 0;
    flipped_raw += flip[a] < 0;
  }
  // All one way (in or out), whatever the raw fan orientation was.
  EXPECT_TRUE(outward == 0 || outward == std::size_t(p.rows())) << outward;
  (void)flipped_raw;
}

// Distance to a "body": the half-space y < floor.
std::function<double(const Vec3&)> floor_at(double floor) {
  return [floor](const Vec3& p) { return std::max(0.0, p.y() - floor); };
}
const std::function<double(const Vec3&)> no_body = [](const Vec3&) { return 1e30; };

TEST(SurfaceBindingTest, IdentityWithoutFeaturesReturnsTheInput) {
  // A = B and no features: the warped garment equals the original, and the encoding is exact there.
  const Garment g = patch(40, 40, 0.5, [](double x, double z) { return 2.0 * std::sin(0.3 * x) * std::cos(0.2 * z); });
  SurfaceOptions o;
  o.voxel = 1.0;
  const SurfaceBinding b = SurfaceBinding::bind(g, Points(0, 3), o);
  const SurfaceResult r = b.apply(g.positions, Points(0, 3), floor_at(0.0));
  EXPECT_GT(r.stats.fixed_body, 0u);
  EXPECT_LT(r.stats.fixed_body, r.stats.agents);
  EXPECT_EQ(r.stats.anchored, 0u);
  EXPECT_TRUE(r.stats.converged);
  const double scale = g.positions.cwiseAbs().maxCoeff();
  EXPECT_LT((r.positions - g.positions).cwiseAbs().maxCoeff(), 1e-6 * scale);
}

TEST(SurfaceBindingTest, EncodeOnOriginalRestoresTheOriginalShapeEncodeOnWarpedKeepsTheWarp) {
  // Flat original; the warp puts a bump in the middle; the border touches the
  // body (fixed at its warped place). Encoded on the original the surface goes
  // back to flat; encoded on the warped state it keeps the bump exactly.
  const int n = 21;
  const double s = 0.5, c = (n - 1) * s / 2;
  const Garment g = flat_patch(n, s);
  Points warped = g.positions;
  for (Eigen::Index i = 0; i < warped.rows(); ++i) {
    const double dx = warped(i, 0) - c, dz = warped(i, 2) - c;
    warped(i, 1) = 2.0 * std::exp(-(dx * dx + dz * dz) / 4.0);
  }
  auto border = [c](const Vec3& p) { return std::max(std::abs(p.x() - c), std::abs(p.z() - c)) > c - 1.2 ? 0.0 : 1e9; };
  SurfaceOptions o;
  o.voxel = 0.5;
  o.max_iterations = 5000;
  o.tolerance = 1e-9;
  const SurfaceResult orig = SurfaceBinding::bind(g, Points(0, 3), o).apply(warped, Points(0, 3), border);
  o.encode_on_warped = true;
  const SurfaceResult warp = SurfaceBinding::bind(g, Points(0, 3), o).apply(warped, Points(0, 3), border);
  EXPECT_TRUE(orig.stats.converged);
  EXPECT_TRUE(warp.stats.converged);
  EXPECT_LT((warp.positions - warped).cwiseAbs().maxCoeff(), 1e-6);
  const double bump_warp = warped.col(1).maxCoeff();
  const double bump_orig = orig.positions.col(1).cwiseAbs().maxCoeff();
  EXPECT_LT(bump_orig, 0.2 * bump_warp) << "encode on original should flatten the bump";
  EXPECT_GT((orig.positions - warp.positions).cwiseAbs().maxCoeff(), 1.0);
  EXPECT_TRUE(orig.positions.allFinite());
}

TEST(SurfaceBindingTest, FeaturesPullTheSurfaceAndRebuildIsDeterministic) {
  // A tube (the agents of a cylinder around y); feature: a straight profile line on
  // the tube; warp: a bulge in the middle; the profile targets are the straight
  // original line moved sideways by the bulge's end offsets (here zero).
  const int around = 48, along = 60;
  const double radius = 5.0, dy = 0.5;
  Garment g;
  g.positions.resize(around * along, 3);
  for (int j = 0; j < along; ++j)
    for (int i = 0; i < around; ++i) {
      const double t = 2 * std::numbers::pi * i / around;
      g.positions.row(j * around + i) << radius * std::cos(t), j * dy, radius * std::sin(t);
    }
  for (int j = 0; j + 1 < along; ++j)
    for (int i = 0; i < around; ++i) {
      const Index a = Index(j * around + i), b = Index(j * around + (i + 1) % around);
      g.faces.push_row(std::array<Index, 4>{a, b, b + Index(around), a + Index(around)});
    }
  const double top = (along - 1) * dy;
  auto bulge = [&](double y) { return 1.0 + 0.3 * std::exp(-std::pow((y - top / 2) / (top / 6), 2)); };
  Points warped = g.positions;
  for (Eigen::Index v = 0; v < warped.rows(); ++v) {
    const double f = bulge(warped(v, 1));
    warped(v, 0) *= f;
    warped(v, 2) *= f;
  }
  const int m = 40;
  Points feature(m, 3), target(m, 3), feature_warped(m, 3);
  for (int k = 0; k < m; ++k) {
    const double y = top * k / (m - 1);
    feature.row(k) << radius, y, 0;
    feature_warped.row(k) << radius * bulge(y), y, 0;
    target.row(k) << radius, y, 0;  // straight again
  }
  SurfaceOptions o;
  o.voxel = 1.0;
  o.max_iterations = 300;
  const SurfaceBinding b = SurfaceBinding::bind(g, feature, o);
  EXPECT_EQ(b.feature_count(), std::size_t(m));
  // The colour check: no one-ring edge joins two agents swept at the same time.
  const BlockSchedule& sch = b.schedule();
  std::size_t edges = 0;
  for (std::size_t a = 0; a < b.agent_count(); ++a)
    for (Index q : b.ring().row(a)) {
      ++edges;
      EXPECT_FALSE(sch.concurrent(Index(a), q)) << a << " - " << q;
    }
  EXPECT_GT(edges, 0u);
  EXPECT_GT(sch.blocks(), 8u);

  // Bottom ring of the tube sits on the body (y < 0.6).
  auto body = [](const Vec3& p) { return p.y() < 0.6 ? 0.0 : 1e9; };
  SurfaceResult one, two;
  {
    ThreadLimit limit(1);
    one = b.apply(warped, target, body, &feature_warped);
  }
  {
    ThreadLimit limit(2);
    two = b.apply(warped, target, body, &feature_warped);
  }
  EXPECT_TRUE(same_bytes(one.positions, two.positions));
  EXPECT_TRUE(same_bytes(one.agents, two.agents));
  EXPECT_EQ(one.stats.iterations, two.stats.iterations);
  EXPECT_EQ(one.stats.fixed_feature, std::size_t(m));
  // The bottom ring touches the body: eq. 14 holds it, or (the tube hangs and
  // has a feature) the band frees it.
  EXPECT_GT(one.stats.fixed_body + one.stats.banded, 0u);
  EXPECT_EQ(one.stats.fixed_band, two.stats.fixed_band);
  ASSERT_TRUE(one.positions.allFinite());
  // Vertices next to the profile follow it back in: x near radius, not radius * 1.3.
  double worst_warp = 0.0, worst_result = 0.0;
  for (Eigen::Index v = 0; v < warped.rows(); ++v) {
    const double y = g.positions(v, 1);
    if (std::abs(g.positions(v, 2)) > 0.01 || g.positions(v, 0) < 0 || y < 2 || y > top - 2) continue;
    worst_warp = std::max(worst_warp, std::abs(warped(v, 0) - radius));
    worst_result = std::max(worst_result, std::abs(one.positions(v, 0) - radius));
  }
  EXPECT_GT(worst_warp, 1.0);
  EXPECT_LT(worst_result, 0.25 * worst_warp);
}

TEST(SurfaceBindingTest, KrylovSolveHandlesACoordinateThatIsAlreadySolved) {
  // A flat patch stretched in its plane: the y coordinate is solved from the
  // start (zero residual), x and z are not. BiCGSTAB must leave y exactly flat
  // and converge on the rest without restarting over the solved coordinate.
  const Garment g = flat_patch(60, 0.5);
  Points warped = g.positions;
  warped.col(0) *= 1.2;
  SurfaceOptions o;
  o.voxel = 0.5;
  const SurfaceBinding b = SurfaceBinding::bind(g, Points(0, 3), o);
  auto body = [](const Vec3& p) { return p.x() < 1.0 ? 0.0 : 1e9; };  // the x < 1 edge is held
  SurfaceSystem sys;
  const SurfaceResult r = b.apply(warped, Points(0, 3), body, nullptr, &sys);
  ASSERT_GT(r.stats.levels, 1);
  EXPECT_TRUE(r.stats.converged);
  Points x = sys.start;
  int krylov = 0;
  const SolveReport rep = b.solve(sys.h, sys.free, x, {500, 1e-5, 1.0}, FineSolver::krylov, &krylov);
  std::printf("  %zu agents: %d BiCGSTAB iterations, %d sweeps, update %.2e\n", b.agent_count(), krylov, rep.iterations,
              rep.final_update);
  EXPECT_TRUE(rep.converged);
  EXPECT_GT(krylov, 0);
  EXPECT_LT(krylov, 40);
  EXPECT_EQ(x.col(1).cwiseAbs().maxCoeff(), 0.0);
}

TEST(SurfaceBindingTest, IsolatedPieceIsAnchoredAndDoesNotDrift) {
  // Piece 1 touches the body; piece 2 floats far from body and features.
  const Garment near = flat_patch(15, 0.5);
  const Garment far = flat_patch(6, 0.5, 100.0, 100.0);
  Garment g = test::merge_garments(near, far);
  Points warped = g.positions;
  for (Eigen::Index v = 0; v < warped.rows(); ++v) warped(v, 1) += 0.1 * std::sin(warped(v, 0));
  SurfaceOptions o;
  o.voxel = 0.5;
  const SurfaceBinding b = SurfaceBinding::bind(g, Points(0, 3), o);
  auto body = [](const Vec3& p) { return p.x() < 1.0 ? 0.0 : 1e9; };
  const SurfaceResult r = b.apply(warped, Points(0, 3), body);
  ASSERT_TRUE(r.positions.allFinite());
  EXPECT_GE(r.stats.anchored_groups, 1u);
  EXPECT_GE(r.stats.anchored, 36u);  // every agent of the far piece (6 x 6 vertices at least)
  const Eigen::Index n0 = Eigen::Index(near.vertex_count());
  const auto moved = (r.positions.bottomRows(warped.rows() - n0) - warped.bottomRows(warped.rows() - n0)).cwiseAbs();
  EXPECT_LT(moved.maxCoeff(), 1e-9);

  // Nothing fixed at all: everything anchored, output = warped.
  const SurfaceResult all = b.apply(warped, Points(0, 3), no_body);
  EXPECT_EQ(all.stats.anchored, all.stats.agents);
  EXPECT_LT((all.positions - warped).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(SurfaceBindingTest, BadInputThrowsOneClearLine) {
  const Garment g = flat_patch(5, 1.0);
  SurfaceOptions o;
  o.voxel = -1;
  EXPECT_THROW(SurfaceBinding::bind(g, Points(0, 3), o), Error);
  o.voxel = 1.0;
  for (const int zone : {-1, 17}) {
    SurfaceOptions z = o;
    z.feature_zone_rings = zone;
    EXPECT_THROW(SurfaceBinding::bind(g, Points(0, 3), z), Error) << zone;
  }
  SurfaceOptions reg = o;
  reg.snap_regularisation = 0.0;
  EXPECT_THROW(SurfaceBinding::bind(g, Points(0, 3), reg), Error);
  Points bad(1, 3);
  bad << 0, std::nan(""), 0;
  EXPECT_THROW(SurfaceBinding::bind(g, bad, o), Error);
  const SurfaceBinding b = SurfaceBinding::bind(g, Points::Zero(2, 3), o);
  EXPECT_THROW(b.apply(g.positions, Points::Zero(3, 3), no_body), Error);  // 3 targets for 2 samples
  EXPECT_THROW(b.apply(g.positions.topRows(3), Points::Zero(2, 3), no_body), Error);
  Points nan_warp = g.positions;
  nan_warp(4, 2) = std::numeric_limits<double>::infinity();
  try {
    b.apply(nan_warp, Points::Zero(2, 3), no_body);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("warped vertex row 5"), std::string::npos) << e.what();
  }
}

TEST(SurfaceBindingTest, AutoVoxelLandsNearTheBudget) {
  const Garment g = patch(200, 200, 0.1, [](double x, double z) { return std::sin(x) * std::cos(z); });
  SurfaceOptions o;
  o.agent_budget = 3000;
  const SurfaceBinding b = SurfaceBinding::bind(g, Points(0, 3), o);
  EXPECT_TRUE(b.bind_stats().voxel_was_auto);
  EXPECT_GT(b.bind_stats().agents, 1500u);
  EXPECT_LT(b.bind_stats().agents, 4500u);
  EXPECT_GT(b.bind_stats().ring_degree_mean, 3.5);
}

// The snap's reach (feature_snap.hpp): every vertex within snap_radius voxels of
// a feature sample is moved by that sample's agent, with weight (1 - d^2/r^2)^2,
// whatever agents its blend picked; none farther, and none with radius 0.
TEST(SurfaceSnapReach, EveryVertexWithinTheRadiusOfASampleAndNoOther) {
  const Garment g = flat_patch(41, 0.25);  // 10 x 10 in the x-z plane
  Points samples(5, 3);
  for (int k = 0; k < 5; ++k) samples.row(k) << 3.0 + 1.0 * k, 0.0, 5.1;
  SurfaceOptions o;
  o.voxel = 0.5;
  o.snap_radius = 2.0;  // 1.0 in garment units
  const SurfaceBinding b = SurfaceBinding::bind(g, samples, o);
  const SnapReach reach = b.snap_reach(g.positions, {});
  ASSERT_EQ(reach.reach.rows(), g.vertex_count());
  std::size_t reached = 0;
  for (Index v = 0; v < Index(g.vertex_count()); ++v) {
    const Vec3 p = row3(g.positions, v);
    std::vector<int> want;
    for (int k = 0; k < 5; ++k)
      if ((p - row3(samples, k)).squaredNorm() < 1.0 - 1e-9) want.push_back(k);
    std::vector<int> got;
    const auto r = reach.reach.row(v);
    for (std::size_t q = 0; q < r.size(); ++q) {
      const int k = b.feature_of()[r[q]];
      ASSERT_GE(k, 0) << "only feature agents move a vertex in the snap";
      got.push_back(k);
      const double d2 = (p - row3(samples, k)).squaredNorm();
      EXPECT_NEAR(reach.weight[reach.reach.offsets[v] + q], std::pow(1.0 - d2, 2), 1e-6);
    }
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, want) << "vertex " << v;
    reached += !got.empty();
  }
  EXPECT_GT(reached, 100u);
  o.snap_radius = 0.0;
  const SurfaceBinding through_blends = SurfaceBinding::bind(g, samples, o);
  EXPECT_TRUE(through_blends.snap_reach(g.positions, {}).reach.indices.empty());
}

}  // namespace
}  // namespace refit
