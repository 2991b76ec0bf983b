// The least-squares solve around the features (feature_bend.hpp) on a flat
// grid of agents with a held line raised out of it: eq. 13 alone gives a tent
// with a crease along the line; the bend must round it and touch nothing else.
#include <refit/surface/agent_system.hpp>
#include <refit/surface/agents.hpp>
#include <refit/surface/feature_bend.hpp>

#include <gtest/gtest.h>

#include <cmath>

namespace refit {
namespace {

constexpr int kN = 21, kLine = kN / 2;
Index at(int i, int k) { return Index(i * kN + k); }

struct Tent {
  AgentRows rows;
  std::vector<std::uint8_t> fixed, free;
  Points x;
};

// Flat grid in the xz plane; border held (1) at y = 0, the middle line i = kLine
// held as a feature (2) at y = 1; the rest solved by eq. 13 (Gauss-Seidel to rest).
Tent tent() {
  Tent t;
  Points p(kN * kN, 3);
  for (int i = 0; i < kN; ++i)
    for (int k = 0; k < kN; ++k) p.row(at(i, k)) << i, 0.0, k;
  t.rows = encode_agents(p, build_one_rings(p, 3.0));
  t.fixed.assign(kN * kN, 0);
  t.x = p;
  for (int i = 0; i < kN; ++i)
    for (int k = 0; k < kN; ++k) {
      if (i == 0 || k == 0 || i == kN - 1 || k == kN - 1) t.fixed[at(i, k)] = 1;
      if (i == kLine && k > 0 && k < kN - 1) {
        t.fixed[at(i, k)] = 2;
        t.x(at(i, k), 1) = 1.0;
      }
    }
  for (std::size_t a = 0; a < t.fixed.size(); ++a) t.free.push_back(t.fixed[a] == 0);
  for (int sweep = 0; sweep < 5000; ++sweep)
    for (std::size_t a = 0; a < t.free.size(); ++a) {
      if (!t.free[a]) continue;
      Vec3 s = row3(t.rows.h, Index(a));
      auto r = t.rows.ring.row(a);
      for (std::size_t j = 0; j < r.size(); ++j) s += t.rows.weight[t.rows.ring.offsets[a] + j] * row3(t.x, r[j]);
      t.x.row(Eigen::Index(a)) = (s / t.rows.diag[a]).transpose();
    }
  return t;
}

// Second difference of the height across the line at its middle: the crease.
double crease(const Points& x) {
  const int k = kN / 2;
  return std::abs(x(at(kLine - 1, k), 1) - 2.0 * x(at(kLine, k), 1) + x(at(kLine + 1, k), 1));
}

TEST(FeatureBend, RoundsTheCreaseAlongAHeldLineAndKeepsTheRest) {
  Tent t = tent();
  const Points laplace = t.x;
  const double before = crease(t.x);
  ASSERT_GT(before, 0.1);  // the tent's crease is there to remove
  const FeatureBendReport r = bend_around_features(t.rows, t.rows.h, 4, t.free, t.fixed, t.x, 0, nullptr);
  ASSERT_TRUE(r.solved);
  EXPECT_GT(r.agents, 0u);
  EXPECT_LT(crease(t.x), 0.5 * before);  // measured: 0.236 -> 0.083
  for (int i = 0; i < kN; ++i)
    for (int k = 0; k < kN; ++k) {
      const Index a = at(i, k);
      // Held agents and the zone's border (4 steps from the line) and beyond keep the first solution.
      if (t.fixed[a] != 0 || std::abs(i - kLine) >= 4) {
        EXPECT_EQ(t.x.row(a), laplace.row(a)) << i << " " << k;
      }
      EXPECT_TRUE(t.x.row(a).allFinite());
      EXPECT_LE(t.x(a, 1), 1.0 + 1e-9);  // no overshoot above the held line
    }
}

TEST(FeatureBend, NoZoneWithoutFeaturesOrWithLessThanTwoRings) {
  Tent t = tent();
  const Points laplace = t.x;
  EXPECT_FALSE(bend_around_features(t.rows, t.rows.h, 1, t.free, t.fixed, t.x, 0, nullptr).solved);
  for (auto& f : t.fixed)
    if (f == 2) f = 1;
  EXPECT_FALSE(bend_around_features(t.rows, t.rows.h, 4, t.free, t.fixed, t.x, 0, nullptr).solved);
  EXPECT_EQ(t.x, laplace);
}

TEST(FeatureBend, AgentsTheBendSinksAreHeldAndSolvedAround) {
  Tent t = tent();
  // A "body" the rounded tent must stay above: y >= 0.99 one step from the line. The hold
  // lifts what the solve left below it and marks it held, as the clearance rounds do.
  int calls = 0;
  const auto hold = [&](const std::vector<std::uint8_t>& solved) {
    ++calls;
    std::size_t moved = 0;
    for (std::size_t a = 0; a < solved.size(); ++a) {
      const int i = int(a) / kN;
      if (solved[a] && std::abs(i - kLine) == 1 && t.x(Eigen::Index(a), 1) < 0.99) {
        t.x(Eigen::Index(a), 1) = 0.99;
        t.fixed[a] = 3;
        ++moved;
      }
    }
    return moved;
  };
  const FeatureBendReport r = bend_around_features(t.rows, t.rows.h, 4, t.free, t.fixed, t.x, 3, hold);
  ASSERT_TRUE(r.solved);
  EXPECT_EQ(r.rounds, 2);  // one solve, one hold, one solve around the held agents
  EXPECT_EQ(calls, 2);
  for (int k = 1; k < kN - 1; ++k) {
    EXPECT_EQ(t.fixed[at(kLine - 1, k)], 3);
    EXPECT_DOUBLE_EQ(t.x(at(kLine - 1, k), 1), 0.99);
  }
}

}  // namespace
}  // namespace refit
