// Step 1 (primary resizing) invariants: identity, rigid motion, uniform scaling,
// thread-count independence, degenerate triangles.
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/warp/warp.hpp>

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <random>

namespace refit {
namespace {

// A closed UV sphere (radius r) as a small stand-in body.
BodyMesh sphere(double r, int rings = 24, int segments = 48) {
  BodyMesh b;
  b.name = "sphere";
  std::vector<Vec3> v;
  v.emplace_back(0, r, 0);
  for (int i = 1; i < rings; ++i) {
    const double th = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double ph = 2 * M_PI * j / segments;
      v.emplace_back(r * std::sin(th) * std::cos(ph), r * std::cos(th), r * std::sin(th) * std::sin(ph));
    }
  }
  v.emplace_back(0, -r, 0);
  b.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) b.vertices.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  auto id = [&](int ring, int seg) { return static_cast<Index>(1 + (ring - 1) * segments + (seg % segments)); };
  const Index south = static_cast<Index>(v.size() - 1);
  for (int j = 0; j < segments; ++j) b.triangles.push_back({0, id(1, j + 1), id(1, j)});
  for (int i = 1; i < rings - 1; ++i)
    for (int j = 0; j < segments; ++j) {
      b.triangles.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      b.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
  for (int j = 0; j < segments; ++j) b.triangles.push_back({south, id(rings - 1, j), id(rings - 1, j + 1)});
  return b;
}

// Points scattered in a shell around the sphere, at 0.1 to 8 units from its surface.
Points shell_points(double r, std::size_t n, unsigned seed = 7) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0.1, 8.0);
  Points p(static_cast<Eigen::Index>(n), 3);
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 d(g(rng), g(rng), g(rng));
    p.row(static_cast<Eigen::Index>(i)) = (d.normalized() * (r + u(rng))).transpose();
  }
  return p;
}

BodyMesh transformed(const BodyMesh& a, const Eigen::Matrix3d& m, const Vec3& t) {
  BodyMesh b = a;
  for (Eigen::Index i = 0; i < b.vertices.rows(); ++i)
    b.vertices.row(i) = (m * a.vertices.row(i).transpose() + t).transpose();
  return b;
}

double max_abs(const Points& p) { return p.cwiseAbs().maxCoeff(); }

TEST(Warp, IdentityBodyLeavesPointsAlone) {
  const BodyMesh a = sphere(20.0);
  ReferenceBody ref(a);
  const Points p = shell_points(20.0, 3000);
  const WarpBinding bind = ref.bind(p);
  const Points out = bind.apply(compute_frames(a));
  EXPECT_LE(max_abs(out - p), 1e-9 * max_abs(p));
}

TEST(Warp, RigidMotionMovesPointsRigidly) {
  const BodyMesh a = sphere(20.0);
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 t(5, -3, 11);
  ReferenceBody ref(a);
  const Points p = shell_points(20.0, 3000);
  const Points out = ref.bind(p).apply(compute_frames(transformed(a, rot, t)));
  Points expected = (p * rot.transpose()).rowwise() + t.transpose();
  EXPECT_LE(max_abs(out - expected), 1e-6 * max_abs(expected));
}

TEST(Warp, UniformScalingScalesPointsNearTheBody) {
  const BodyMesh a = sphere(20.0, 48, 96);
  const double s = 1.1;
  const Vec3 centre(2, 1, -1);
  const Eigen::Matrix3d m = s * Eigen::Matrix3d::Identity();
  ReferenceBody ref(a);
  // Points 0.05 from the surface: the frames are orthonormal, so only the part
  // of p that the body carries scales; the 0.05 offset stays 0.05.
  Points p = shell_points(20.0, 2000);
  for (Eigen::Index i = 0; i < p.rows(); ++i) p.row(i) = p.row(i).normalized() * 20.05;
  const Points out = ref.bind(p).apply(compute_frames(transformed(a, m, (1 - s) * centre)));
  const Points expected = (p * s).rowwise() + ((1 - s) * centre).transpose();
  // p' - s p = (1 - s)(p - c) with c the blended triangle centre, which lies
  // within about one edge length (2 pi 20 / 96 = 1.31) of p: that part of p
  // does not scale.
  const double edge = 2 * M_PI * 20.0 / 96;
  EXPECT_LE(max_abs(out - expected), (s - 1) * (0.05 + edge));
  // Far points do not scale: that is eq. 4 with orthonormal frames (DESIGN.md).
  EXPECT_LE(max_abs(out - expected), 0.5);
}

TEST(Warp, SameBitsForOneAndTwoThreads) {
  const BodyMesh a = sphere(20.0);
  const Eigen::Matrix3d m = Eigen::Vector3d(1.1, 0.9, 1.3).asDiagonal();
  const BodyMesh b = transformed(a, m, Vec3(1, 2, 3));
  const Points p = shell_points(20.0, 20000);
  Points one, two;
  {
    ThreadLimit limit(1);
    one = ReferenceBody(a).bind(p).apply(compute_frames(b));
  }
  {
    ThreadLimit limit(2);
    two = ReferenceBody(a).bind(p).apply(compute_frames(b));
  }
  ASSERT_EQ(one.rows(), two.rows());
  EXPECT_EQ(0, std::memcmp(one.data(), two.data(), sizeof(double) * static_cast<std::size_t>(one.size())));
}

// The garment, each feature curve and each chunk are warped with one change to
// body B made once: the same bits as each apply making its own, and a change
// from another body A is refused.
TEST(Warp, OneChangeServesEveryPointSet) {
  const BodyMesh a = sphere(20.0);
  const BodyMesh b = transformed(a, Eigen::Vector3d(1.1, 0.9, 1.3).asDiagonal(), Vec3(1, 2, 3));
  const ReferenceBody ref(a), other(a);
  const TriangleFrames frames_b = compute_frames(b);
  const TriangleChange change = triangle_change(ref.frames(), frames_b);
  for (unsigned seed : {1u, 2u, 3u}) {
    const WarpBinding bind = ref.bind(shell_points(20.0, 500, seed));
    const Points own = bind.apply(frames_b), shared = bind.apply(change);
    ASSERT_EQ(own.rows(), shared.rows());
    EXPECT_EQ(0, std::memcmp(own.data(), shared.data(), sizeof(double) * static_cast<std::size_t>(own.size())));
  }
  EXPECT_THROW(other.bind(shell_points(20.0, 10)).apply(change), Error);
  EXPECT_THROW(triangle_change(ref.frames(), compute_frames(sphere(20.0, 12, 24))), Error);
}

TEST(Warp, DegenerateTrianglesAreSkippedAndCounted) {
  BodyMesh a = sphere(20.0);
  // Collapse one triangle of A (two corners at the same place) and another on B only.
  a.vertices.row(a.triangles[100][1]) = a.vertices.row(a.triangles[100][0]);
  BodyMesh b = transformed(a, 1.2 * Eigen::Matrix3d::Identity(), Vec3::Zero());
  b.vertices.row(b.triangles[500][2]) = b.vertices.row(b.triangles[500][0]);
  const TriangleFrames fa = compute_frames(a), fb = compute_frames(b);
  EXPECT_GE(fa.degenerate, 1u);
  EXPECT_GE(fb.degenerate, fa.degenerate + 1);
  ReferenceBody ref(a);
  const Points p = shell_points(20.0, 5000);
  const Points out = ref.bind(p).apply(fb);
  EXPECT_TRUE(out.allFinite());
}

TEST(Warp, TriangleSetFollowsEq2AndTheCap) {
  const BodyMesh a = sphere(20.0, 48, 96);
  WarpOptions opt;
  opt.max_triangles = 8;
  ReferenceBody ref(a, opt);
  Points p(2, 3);
  p.row(0) << 0, 0, 20.01;  // near: few centres within 1.2 |pq|
  p.row(1) << 0, 0, 60;     // far: many centres inside the radius, capped
  const WarpBinding bind = ref.bind(p);
  EXPECT_LT(bind.triangles.row_size(0), 8u);
  EXPECT_EQ(bind.triangles.row_size(1), 8u);
  EXPECT_EQ(bind.capped, 1u);
  // The set is exactly the centres within (1 + alpha) |pq| for the near point.
  const TriangleFrames& f = ref.frames();
  const Vec3 q = p.row(0).transpose();
  double dmin = 1e300;
  for (Eigen::Index t = 0; t < f.centre.rows(); ++t) dmin = std::min(dmin, (f.centre.row(t).transpose() - q).norm());
  std::size_t inside = 0;
  for (Eigen::Index t = 0; t < f.centre.rows(); ++t)
    inside += (f.centre.row(t).transpose() - q).norm() < 1.2 * dmin ? 1 : 0;
  EXPECT_EQ(bind.triangles.row_size(0), inside);
}

}  // namespace
}  // namespace refit
