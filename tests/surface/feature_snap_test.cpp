// The snap through the optimised feature curves (surface/feature_snap) on a flat
// quad sheet whose feature samples are the only agents.
#include <refit/attach/attachment.hpp>
#include <refit/surface/feature_snap.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace refit {
namespace {

constexpr int kGridSide = 21;          // vertices per side, spacing 1, on y = 0
constexpr double kReach = 2.5;  // a vertex blends the samples within this distance

struct Sheet {
  Garment garment;
  Points samples;  // along z = 10.3, x = 2 ... 18
  SurfaceAttachment at;
  Csr reach;
  std::vector<float> weight;
  std::vector<std::int32_t> feature_of;  // agent k is sample k
};

Sheet sheet(double reach = kReach) {
  Sheet s;
  Garment& g = s.garment;
  g.positions.resize(kGridSide * kGridSide, 3);
  for (int i = 0; i < kGridSide; ++i)
    for (int k = 0; k < kGridSide; ++k) g.positions.row(i * kGridSide + k) << i, 0.0, k;
  for (int i = 0; i + 1 < kGridSide; ++i)
    for (int k = 0; k + 1 < kGridSide; ++k) {
      const Index a = Index(i * kGridSide + k);
      const std::array<Index, 4> q{a, a + 1, a + 1 + Index(kGridSide), a + Index(kGridSide)};
      g.faces.push_row(q);
    }
  const int m = 33;
  s.samples.resize(m, 3);
  for (int j = 0; j < m; ++j) s.samples.row(j) << 2.0 + 0.5 * j, 0.0, 10.3;
  s.at = attach_points(g, s.samples);
  s.feature_of.resize(m);
  for (int j = 0; j < m; ++j) s.feature_of[j] = j;
  // Smooth compact weights, normalised as if garment agents shared the rest (sum 0.5).
  for (Index v = 0; v < Index(g.vertex_count()); ++v) {
    std::vector<Index> row;
    std::vector<double> w;
    double sum = 0.0;
    for (int j = 0; j < m; ++j) {
      const double d2 = (row3(g.positions, v) - row3(s.samples, Index(j))).squaredNorm();
      if (d2 >= reach * reach) continue;
      const double t = 1.0 - d2 / (reach * reach);
      row.push_back(Index(j));
      w.push_back(t * t);
      sum += t * t;
    }
    s.reach.push_row(row);
    for (double x : w) s.weight.push_back(float(0.5 * x / sum));
  }
  return s;
}

// The sheet's weights as the snap reach gives them: (1 - d^2/r^2)^2, not normalised.
Sheet kernel_sheet(double reach) {
  Sheet s = sheet(reach);
  s.weight.clear();
  for (Index v = 0; v < Index(s.garment.vertex_count()); ++v)
    for (Index j : s.reach.row(v)) {
      const double t = 1.0 - (row3(s.garment.positions, v) - row3(s.samples, j)).squaredNorm() / (reach * reach);
      s.weight.push_back(float(t * t));
    }
  return s;
}

// Targets: the samples lifted by a smooth bump the sheet can follow.
Points lifted(const Points& samples) {
  Points t = samples;
  for (Eigen::Index j = 0; j < t.rows(); ++j) t(j, 1) = 0.4 * std::sin(0.3 * t(j, 0));
  return t;
}

TEST(FeatureSnap, TheCarriedSamplesReachTheirTargetsAndOnlyNearbyVerticesMove) {
  const Sheet s = sheet();
  Points p = s.garment.positions;
  const Points targets = lifted(s.samples);
  const FeatureSnapReport rep = snap_to_features(p, targets, s.at, s.reach, s.weight, s.feature_of, {}, 1e-3);
  std::printf("  gap %.4f -> %.6f, %zu vertices moved\n", rep.gap_before, rep.gap_after, rep.vertices_moved);
  EXPECT_NEAR(rep.gap_before, 0.4, 1e-3);
  EXPECT_LT(rep.gap_after, 0.02 * rep.gap_before);
  EXPECT_EQ(rep.samples_held, 0u);
  const Points carried = carry(s.at, p);
  EXPECT_LT((carried - targets).rowwise().norm().maxCoeff(), rep.gap_after + 1e-12);
  std::size_t moved = 0;
  for (Index v = 0; v < Index(p.rows()); ++v) {
    const double move = (row3(p, v) - row3(s.garment.positions, v)).norm();
    moved += move > 0.0;
    if (s.reach.row_size(v) == 0) {
      EXPECT_EQ(move, 0.0) << v;  // no feature agent in reach: untouched
    }
  }
  EXPECT_EQ(moved, rep.vertices_moved);
  EXPECT_GT(moved, 0u);
  // Smooth and bounded: the correction fades away from the curve (rows z = 10, 11
  // carry the samples) to nothing at z = 14, and overshoots the targets nowhere.
  auto lift = [&](int i, int k) { return std::abs(p(i * kGridSide + k, 1)); };
  EXPECT_GT(lift(10, 12), 0.0);
  EXPECT_LT(lift(10, 13), lift(10, 12));
  EXPECT_EQ(lift(10, 14), 0.0);
  EXPECT_LT(p.col(1).cwiseAbs().maxCoeff(), 1.5 * targets.col(1).cwiseAbs().maxCoeff());
}

TEST(FeatureSnap, HeldVerticesStayAndTheSamplesOnThemStayToo) {
  const Sheet s = sheet();
  std::vector<float> held(s.garment.vertex_count(), 0.0f);
  for (int i = 0; i <= 6; ++i)
    for (int k = 0; k < kGridSide; ++k) held[i * kGridSide + k] = 1.0f;  // x <= 6
  Points p = s.garment.positions;
  const Points targets = lifted(s.samples);
  const FeatureSnapReport rep = snap_to_features(p, targets, s.at, s.reach, s.weight, s.feature_of, held, 1e-3);
  // The samples at x <= 7 sit on a face with a held corner (counted from the attachment:
  // the one at x = 7 lies on an edge shared by a held and a free face).
  std::size_t on_held = 0;
  for (std::size_t j = 0; j < s.at.vertex.size(); ++j) {
    bool h = false;
    for (int c = 0; c < 3; ++c) h |= s.at.weight[j][c] != 0.0 && held[s.at.vertex[j][c]];
    on_held += h;
  }
  EXPECT_EQ(rep.samples_held, on_held);
  EXPECT_GT(on_held, 8u);
  // Over the samples not on a held vertex; next to the held part the sheet
  // cannot bend at once, farther along (x >= 10) the samples reach their targets.
  EXPECT_LT(rep.gap_after, 0.5 * rep.gap_before);
  const Points carried = carry(s.at, p);
  for (Eigen::Index j = 0; j < carried.rows(); ++j)
    if (s.samples(j, 0) >= 10.0) {
      EXPECT_LT((carried.row(j) - targets.row(j)).norm(), 0.02 * rep.gap_before) << j;
    }
  for (Index v = 0; v < Index(p.rows()); ++v)
    if (held[v]) {
      EXPECT_EQ((row3(p, v) - row3(s.garment.positions, v)).norm(), 0.0) << v;
    }
  std::printf("  %zu samples on held vertices, gap over the others %.4f -> %.4f\n", rep.samples_held, rep.gap_before,
              rep.gap_after);
}

TEST(FeatureSnap, SamplesAlreadyOnTheirTargetsChangeNothing) {
  const Sheet s = sheet();
  Points p = s.garment.positions;
  const FeatureSnapReport rep = snap_to_features(p, carry(s.at, p), s.at, s.reach, s.weight, s.feature_of, {}, 1e-3);
  EXPECT_EQ(rep.gap_before, 0.0);
  EXPECT_EQ(rep.vertices_moved, 0u);
  EXPECT_EQ(std::memcmp(p.data(), s.garment.positions.data(), sizeof(double) * p.size()), 0);
}

TEST(FeatureSnap, TheNarrowedKernelIsTheSameKernelOnAShareOfTheRadius) {
  SnapKernel k;
  k.scale = {0.5, 1.0};
  const auto w = [](double d) { return float((1.0 - d * d) * (1.0 - d * d)); };  // d in radii
  EXPECT_NEAR(k.weight(w(0.3), 0), (1.0 - 0.09 / 0.25) * (1.0 - 0.09 / 0.25), 1e-6);
  EXPECT_EQ(k.weight(w(0.6), 0), 0.0f);  // beyond half the radius
  EXPECT_EQ(k.weight(w(0.6), 1), w(0.6));  // a whole kernel keeps its weights
  EXPECT_EQ(k.weight(1.0f, 0), 1.0f);
  EXPECT_EQ(SnapKernel{}.weight(w(0.6), 0), w(0.6));
}

TEST(FeatureSnap, OnlyAKernelWideAgainstItsFacesIsNarrowed) {
  // Faces 1 wide: a sample's farthest corner (of those it has weight on) lies
  // 0.7 to 1.2 from its agent. A kernel of radius 2 is kept whole (three times
  // that corner is beyond it), one of radius 12.5 is narrowed to the share asked.
  for (const double reach : {2.0, 12.5}) {
    const Sheet s = kernel_sheet(reach);
    SnapVertices vs;
    for (const auto& corners : s.at.vertex)
      for (Index v : corners) {
        SnapVertex& sv = vs[v];
        sv.position = row3(s.garment.positions, v);
        const auto r = s.reach.row(v);
        sv.reach.assign(r.begin(), r.end());
        sv.weight.assign(s.weight.begin() + s.reach.offsets[v], s.weight.begin() + s.reach.offsets[v + 1]);
      }
    const SnapKernel k = narrowed_kernel(s.at, vs, s.feature_of, 0.5);
    ASSERT_EQ(k.scale.size(), s.at.vertex.size());
    for (double q : k.scale) {
      if (reach < 5.0) EXPECT_EQ(q, 1.0) << reach;
      else EXPECT_EQ(q, 0.5) << reach;
    }
    EXPECT_TRUE(narrowed_kernel(s.at, vs, s.feature_of, 1.0).scale.empty());
  }
}

TEST(FeatureSnap, NarrowedLaterPassesStillReachTheTargets) {
  // A wide kernel on fine faces (the case the narrowing is for): the passes
  // after the first on half the radius close what the first leaves.
  const Sheet s = kernel_sheet(12.5);
  const Points targets = lifted(s.samples);
  Points p = s.garment.positions;
  const FeatureSnapReport first = snap_to_features(p, targets, s.at, s.reach, s.weight, s.feature_of, {}, 1e-3);
  const FeatureSnapReport second = snap_to_features(p, targets, s.at, s.reach, s.weight, s.feature_of, {}, 1e-3, 0.5);
  std::printf("  gap %.5f -> %.6f (whole kernel) -> %.8f (narrowed)\n", first.gap_before, first.gap_after, second.gap_after);
  EXPECT_LT(second.gap_after, 0.5 * first.gap_after);
  EXPECT_LT((carry(s.at, p) - targets).rowwise().norm().maxCoeff(), second.gap_after + 1e-12);
}

}  // namespace
}  // namespace refit
