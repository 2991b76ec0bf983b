// PointTree's k-nearest search with a hint (the previous query's answer bounds
// the search from the start): the same answer as without, ties included.
#include <refit/body/centre_tree.hpp>

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace refit {
namespace {

TEST(PointTree, AHintOnlyPrunesTheKNearest) {
  // A 20^3 grid (many equally distant points: ties) and random points; queries
  // on grid points, between them and anywhere, each hinted with the previous
  // query's answer (near or far) or with points of the tree at random.
  std::vector<Vec3> v;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j)
      for (int k = 0; k < 20; ++k) v.push_back({double(i), double(j), double(k)});
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2.0, 22.0);
  for (int i = 0; i < 2000; ++i) v.push_back({u(rng), u(rng), u(rng)});
  Points x(Eigen::Index(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) x.row(Eigen::Index(i)) = v[i].transpose();
  const PointTree tree(x);
  std::vector<Index> want_idx, got_idx, prev;
  std::vector<double> want_d2, got_d2;
  std::size_t bounded = 0;
  for (int q = 0; q < 3000; ++q) {
    Vec3 p(u(rng), u(rng), u(rng));
    if (q % 3 == 0) p = v[std::size_t(q * 37) % 8000];                  // on a grid point
    if (q % 3 == 1) p = v[std::size_t(q * 37) % 8000] + Vec3(0.5, 0.5, 0);  // between four
    const std::size_t k = 1 + std::size_t(q % 12);
    std::vector<Vec3> hint;
    if (q % 4 == 3) {
      for (std::size_t j = 0; j < k + 2; ++j) hint.push_back(v[std::size_t(rng() % v.size())]);
    } else if (q % 5 == 0) {  // the answer itself: the bound is the k-th distance, ties at it stay in
      std::vector<Index> own;
      std::vector<double> d2;
      tree.knn(p, k, own, d2);
      for (Index i : own) hint.push_back(v[i]);
    } else {
      for (Index i : prev) hint.push_back(v[i]);
    }
    bounded += hint.size() >= k;
    tree.knn(p, k, want_idx, want_d2);
    tree.knn(p, k, got_idx, got_d2, hint);
    ASSERT_EQ(got_idx, want_idx) << "query " << q;
    ASSERT_EQ(got_d2, want_d2) << "query " << q;
    std::vector<double> d2;
    tree.knn(p, 12, prev, d2);  // the next query's hint: at least its k points
  }
  EXPECT_GT(bounded, 2500u);
}

}  // namespace
}  // namespace refit
