// The closest-element tree against a scan of every element.
#include <refit/attach/element_tree.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace refit::detail {
namespace {

// The scan: the closest element, the first of equally close ones.
ElementPoint scan(const std::vector<Element>& elements, const Points& x, const Vec3& p, std::size_t& id) {
  ElementPoint best;
  for (std::size_t i = 0; i < elements.size(); ++i) {
    const ElementPoint c = closest_on_element(p, x, elements[i]);
    if (c.d2 < best.d2) best = c, id = i;
  }
  return best;
}

TEST(ElementTree, FindsWhatAScanFinds) {
  // A bumpy 60 x 60 grid of triangles (1 cm), a copy of some of them (a soup's
  // duplicates: ties), hanging segments, loose points and a degenerate triangle.
  const int n = 60;
  Points x((n + 1) * (n + 1) + 3, 3);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) x.row(i * (n + 1) + j) << i, j, 0.3 * std::sin(0.7 * i) * std::cos(0.5 * j);
  const Index extra = Index((n + 1) * (n + 1));
  x.row(extra) << 10, 10, 5;
  x.row(extra + 1) << 30, 12, -4;
  x.row(extra + 2) << 70, 70, 0;
  std::vector<Element> elements;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const Index a = Index(i * (n + 1) + j), b = a + 1, c = a + Index(n + 1), d = c + 1;
      elements.push_back({{a, c, d}, 3});
      elements.push_back({{a, d, b}, 3});
      if ((i + j) % 7 == 0) elements.push_back({{a, d, b}, 3});  // duplicate: the first must win
    }
  elements.push_back({{extra, extra + 1, extra + 1}, 2});
  elements.push_back({{extra + 2, extra + 2, extra + 2}, 1});
  elements.push_back({{0, 1, 2}, 3});  // collinear: a degenerate triangle
  const ElementTree tree(elements, x);

  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5.0, 75.0), h(-3.0, 3.0);
  std::size_t hint = ElementTree::kNoHint;
  for (int q = 0; q < 3000; ++q) {
    // On the surface (at grid vertices and edges: many equally close elements), near it, and far away.
    Vec3 p(u(rng), u(rng), q % 3 == 0 ? 0.0 : h(rng));
    if (q % 5 == 0) p = row3(x, Index(q % ((n + 1) * (n + 1))));
    if (q % 11 == 0) p *= 30.0;
    if (q % 2 == 0) hint = ElementTree::kNoHint;
    std::size_t want = 0;
    const ElementPoint a = scan(elements, x, p, want);
    const ElementPoint b = tree.closest(p, hint);
    ASSERT_EQ(a.d2, b.d2) << q;
    ASSERT_EQ(a.vertex, b.vertex) << q;
    ASSERT_EQ(a.weight, b.weight) << q;
    ASSERT_EQ(a.point, b.point) << q;
  }
}

}  // namespace
}  // namespace refit::detail
