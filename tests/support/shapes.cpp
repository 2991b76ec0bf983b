#include "support/shapes.hpp"

#include <algorithm>
#include <map>

namespace refit::test {

Garment icosphere_garment(int levels, double radius) {
  const BodyMesh m = icosphere(levels, radius);
  Garment g;
  g.positions = m.vertices;
  for (const auto& t : m.triangles) g.faces.push_row(t);
  return g;
}

BodyMesh icosphere(int levels, double radius, const Vec3& centre) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<Index, 3>> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                         {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                         {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                         {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<Index, Index>, Index> mid;
    auto midpoint = [&](Index a, Index b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<Index>(v.size() - 1);
    };
    std::vector<std::array<Index, 3>> g;
    for (auto& tri : f) {
      const Index a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f = std::move(g);
  }
  BodyMesh m;
  m.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) m.vertices.row(static_cast<Eigen::Index>(i)) = (centre + radius * v[i]).transpose();
  m.triangles = std::move(f);
  m.name = "sphere";
  return m;
}

Garment quad_grid(int nx, int nz, double s, const std::function<double(double, double)>& height, double x0, double z0) {
  Garment g;
  g.positions.resize(nx * nz, 3);
  for (int i = 0; i < nx; ++i)
    for (int k = 0; k < nz; ++k) {
      const double x = x0 + i * s, z = z0 + k * s;
      g.positions.row(i * nz + k) << x, height(x, z), z;
    }
  for (int i = 0; i + 1 < nx; ++i)
    for (int k = 0; k + 1 < nz; ++k) {
      const Index a = Index(i * nz + k);
      const std::array<Index, 4> q{a, a + 1, a + 1 + Index(nz), a + Index(nz)};
      g.faces.push_row(q);
    }
  return g;
}

Garment merge_garments(const Garment& a, const Garment& b) {
  Garment g;
  g.positions.resize(a.positions.rows() + b.positions.rows(), 3);
  g.positions << a.positions, b.positions;
  const Index base = Index(a.vertex_count());
  const auto append = [&](const Csr& from_a, const Csr& from_b, Csr& out) {
    out = from_a;
    for (std::size_t e = 0; e < from_b.rows(); ++e) {
      std::vector<Index> r(from_b.row(e).begin(), from_b.row(e).end());
      for (Index& v : r) v += base;
      out.push_row(r);
    }
  };
  append(a.faces, b.faces, g.faces);
  append(a.lines, b.lines, g.lines);
  append(a.points, b.points, g.points);
  return g;
}

}  // namespace refit::test
