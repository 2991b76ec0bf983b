// The closest-element tree against a scan of every element.
#include <refit/attach/attachment.hpp>
#include <refit/attach/element_tree.hpp>
#include <refit/io/obj_garment.hpp>
#include <support/test_support.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
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
  // A bumpy 60 x 60 grid of triangles (1 cm), a third of its cells as one
  // two-triangle element (a quad), a copy of some triangles (a soup's
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
      if ((i + j) % 3 == 1) {
        elements.push_back({{a, c, d, a, d, b}, 6});  // (a, c, d) then (a, d, b)
        continue;
      }
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
  for (int q = 0; q < 1000; ++q) {
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


// Every query of `queries` against the scan, the hint chained from query to
// query (a far previous element as often as a near one) and every third
// query without one.
void expect_tree_finds_the_scans(const std::vector<Element>& elements, const Points& x, const Points& queries) {
  const ElementTree tree(elements, x);
  std::size_t hint = ElementTree::kNoHint;
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    const Vec3 p = queries.row(q).transpose();
    if (q % 3 == 0) hint = ElementTree::kNoHint;
    std::size_t want = 0;
    const ElementPoint a = scan(elements, x, p, want);
    const ElementPoint b = tree.closest(p, hint);
    ASSERT_EQ(a.d2, b.d2) << "query " << q;
    ASSERT_EQ(a.vertex, b.vertex) << "query " << q;
    ASSERT_EQ(a.weight, b.weight) << "query " << q;
    ASSERT_EQ(a.point, b.point) << "query " << q;
    ASSERT_LT(hint, elements.size()) << "query " << q;
  }
}

TEST(ElementTree, FindsWhatAScanFindsInRandomSoups) {
  // Triangles of sizes from 10 um to 1 m anywhere in a 2 m box, a quarter of
  // them degenerate (a repeated corner, three collinear corners, a needle),
  // copies of earlier triangles under their own vertex numbers (equally close,
  // different answers: the first must win) and under the same ones, segments
  // (some of zero length), points and two-triangle elements (bent, and with a
  // repeated corner). One soup sits 10 km from the origin,
  // where float boxes are coarse against the elements.
  for (const double origin : {0.0, 1e6}) {
    std::mt19937 rng(origin == 0.0 ? 11 : 12);
    std::uniform_real_distribution<double> u(-100.0, 100.0), unit(0.0, 1.0);
    std::vector<Vec3> v;
    std::vector<Element> elements;
    const auto vertex = [&](const Vec3& p) {
      v.push_back(p + Vec3::Constant(origin));
      return Index(v.size() - 1);
    };
    for (int i = 0; i < 1500; ++i) {
      const Vec3 c(u(rng), u(rng), u(rng));
      const double size = std::pow(10.0, -3.0 + 5.0 * unit(rng));
      const Vec3 d1 = size * Vec3(u(rng), u(rng), u(rng)) / 100.0, d2 = size * Vec3(u(rng), u(rng), u(rng)) / 100.0;
      const Index a = vertex(c);
      switch (i % 12) {
        case 0: elements.push_back({{a, a, vertex(c + d1)}, 3}); break;                // a repeated corner
        case 1: elements.push_back({{a, vertex(c + d1), vertex(c + 2.5 * d1)}, 3}); break;  // collinear
        case 2: elements.push_back({{a, vertex(c + d1), vertex(c + d1 + 1e-9 * d2)}, 3}); break;  // a needle
        case 3: elements.push_back({{a, vertex(c + d1), vertex(c + d1)}, 2}); break;     // a segment
        case 4: elements.push_back({{a, a, a}, 2}); break;                              // a segment of length 0
        case 5: elements.push_back({{a, a, a}, 1}); break;                              // a point
        case 7: {  // two triangles, bent along their shared edge
          const Index b = vertex(c + d1), cc = vertex(c + d1 + d2 + 0.3 * d1.cross(d2) / (d1.norm() + 1e-30)),
                      d = vertex(c + d2);
          elements.push_back({{a, b, cc, a, cc, d}, 6});
          break;
        }
        case 8: {  // the first one degenerate (a repeated corner)
          const Index b = vertex(c + d1), d = vertex(c + d2);
          elements.push_back({{a, a, b, a, d, b}, 6});
          break;
        }
        case 9: {  // two triangles far apart (an element's triangles need not meet)
          const Index b = vertex(c + d1), cc = vertex(c + d2), far = vertex(-c);
          elements.push_back({{a, b, cc, far, vertex(-c + d1), vertex(-c + d2)}, 6});
          break;
        }
        case 6:
          if (!elements.empty()) {  // an earlier element again: its own vertices, then copies of them
            const Element e = elements[std::size_t(unit(rng) * double(elements.size()))];
            elements.push_back(e);
            Element copy = e;
            for (int k = 0; k < (e.corners == 6 ? 6 : 3); ++k) copy.v[k] = vertex(v[e.v[k]] - Vec3::Constant(origin));
            elements.push_back(copy);
            break;
          }
          [[fallthrough]];
        default: elements.push_back({{a, vertex(c + d1), vertex(c + d2)}, 3});
      }
    }
    Points x(Eigen::Index(v.size()), 3);
    for (std::size_t i = 0; i < v.size(); ++i) x.row(Eigen::Index(i)) = v[i].transpose();
    // Queries anywhere, exactly on corners (ties among all elements there), on
    // edges' midpoints and near elements.
    Points queries(800, 3);
    for (Eigen::Index q = 0; q < queries.rows(); ++q) {
      const Element& e = elements[std::size_t(q * 7919) % elements.size()];
      const Vec3 a = row3(x, e.v[0]), b = row3(x, e.v[1]);
      Vec3 p = Vec3(1.5 * u(rng), 1.5 * u(rng), 1.5 * u(rng)) + Vec3::Constant(origin);
      if (q % 4 == 1) p = a;
      if (q % 4 == 2) p = 0.5 * (a + b);
      if (q % 4 == 3) p = a + Vec3(u(rng), u(rng), u(rng)) * 1e-3;
      queries.row(q) = p.transpose();
    }
    expect_tree_finds_the_scans(elements, x, queries);
  }
}

TEST(ElementTree, FindsWhatAScanFindsOnFineTubes) {
  // Real-like without the shared data: a garment's fine tube (5 mm triangles,
  // the outer one as quads) around a body's, both a few mm apart, queried at mirror images of its
  // vertices (the symmetry binding's queries), at the vertices themselves and
  // just off the surface.
  const int around = 120, along = 40;
  Points x(2 * around * along, 3);
  std::vector<Element> elements;
  for (int layer = 0; layer < 2; ++layer)
    for (int j = 0; j < along; ++j)
      for (int i = 0; i < around; ++i) {
        const double angle = 2.0 * std::numbers::pi * i / around + 0.01 * j, r = 12.0 + 0.3 * layer + 0.2 * std::sin(3.0 * angle);
        x.row((layer * along + j) * around + i) << 3.0 + r * std::cos(angle), r * std::sin(angle), 0.5 * j;
      }
  for (int layer = 0; layer < 2; ++layer)
    for (int j = 0; j + 1 < along; ++j)
      for (int i = 0; i < around; ++i) {
        const auto id = [&](int jj, int ii) { return Index((layer * along + jj) * around + (ii % around)); };
        if (layer == 1) {
          elements.push_back({{id(j, i), id(j + 1, i), id(j + 1, i + 1), id(j, i), id(j + 1, i + 1), id(j, i + 1)}, 6});
          continue;
        }
        elements.push_back({{id(j, i), id(j + 1, i), id(j + 1, i + 1)}, 3});
        elements.push_back({{id(j, i), id(j + 1, i + 1), id(j, i + 1)}, 3});
      }
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  Points queries(400, 3);
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    Vec3 p = row3(x, Index(q * 13 % x.rows()));
    if (q % 3 == 0) p.x() = 6.0 - p.x();  // the mirror image about x = 3
    if (q % 3 == 1) p += Vec3(u(rng), u(rng), u(rng));
    queries.row(q) = p.transpose();
  }
  expect_tree_finds_the_scans(elements, x, queries);
}

TEST(ElementTree, FindsWhatAScanFindsWhenBuiltInParallel) {
  // Over 2^16 elements the top levels of the tree are built in parallel: a
  // fine bumpy sheet of 160k triangles, queried at its vertices, mirror images
  // and points off it (including far away) against the scan.
  const int n = 283;
  Points x(n * n, 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) x.row(j * n + i) << 0.1 * i, 0.1 * j, 0.3 * std::sin(0.05 * i) * std::cos(0.07 * j);
  std::vector<Element> elements;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const Index a = Index(j * n + i);
      elements.push_back({{a, a + 1, a + Index(n) + 1}, 3});
      elements.push_back({{a, a + Index(n) + 1, a + Index(n)}, 3});
    }
  ASSERT_GT(elements.size(), std::size_t(1) << 17);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  Points queries(90, 3);
  for (Eigen::Index q = 0; q < queries.rows(); ++q) {
    Vec3 p = row3(x, Index(q * 797 % x.rows()));
    if (q % 3 == 0) p.x() = 20.0 - p.x();
    if (q % 3 == 1) p += Vec3(u(rng), u(rng), q % 2 ? u(rng) : 40.0 * u(rng));
    queries.row(q) = p.transpose();
  }
  expect_tree_finds_the_scans(elements, x, queries);
}

TEST(ElementTree, FindsWhatAScanFindsOnTheSharedGarments) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "the shared data (../shared/data) is absent";
  for (const char* name : {"dress_on_A_female", "dress_soup_on_A_female", "jeans_on_A_female", "male_suit_on_M_ref",
                           "outfit_dress_jeans_on_A_female", "skirt_on_A_female"}) {
    SCOPED_TRACE(name);
    const Garment g = read_garment_obj(data + "/garments/" + name + ".obj");
    std::vector<Element> elements;
    for (std::size_t f = 0; f < g.faces.rows(); ++f) {
      const auto face = g.faces.row(f);
      for (std::size_t k = 1; k + 1 < face.size(); ++k) elements.push_back({{face[0], face[k], face[k + 1]}, 3});
    }
    for (std::size_t l = 0; l < g.lines.rows(); ++l) {
      const auto line = g.lines.row(l);
      for (std::size_t k = 0; k + 1 < line.size(); ++k) elements.push_back({{line[k], line[k + 1], line[k + 1]}, 2});
    }
    for (Index v : g.points.indices) elements.push_back({{v, v, v}, 1});
    // Mirror images about the garment's middle, vertices (the soup's are
    // doubled: ties between faces that do not share vertex numbers) and
    // points just off them, about 100 of each.
    const Points& x = g.positions;
    const double mid = 0.5 * (x.col(0).minCoeff() + x.col(0).maxCoeff());
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    const Eigen::Index step = std::max<Eigen::Index>(1, x.rows() / 100);
    Points queries(3 * ((x.rows() + step - 1) / step), 3);
    Eigen::Index q = 0;
    for (Eigen::Index i = 0; i < x.rows(); i += step) {
      const Vec3 p = x.row(i).transpose();
      queries.row(q++) << 2.0 * mid - p.x(), p.y(), p.z();
      queries.row(q++) = p.transpose();
      queries.row(q++) = (p + Vec3(u(rng), u(rng), u(rng))).transpose();
    }
    expect_tree_finds_the_scans(elements, x, queries);
    // Through the public entry point too (queries in curve order, in parallel).
    const SurfaceAttachment at = attach_points(g, queries);
    for (Eigen::Index k = 0; k < queries.rows(); ++k) {
      std::size_t id = 0;
      const ElementPoint want = scan(elements, x, queries.row(k).transpose(), id);
      ASSERT_EQ(at.vertex[std::size_t(k)], want.vertex) << k;
      ASSERT_EQ(at.weight[std::size_t(k)], want.weight) << k;
    }
  }
}

}  // namespace
}  // namespace refit::detail
