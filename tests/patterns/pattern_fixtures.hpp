#pragma once
// Small pieces and garments for the pattern tests: grids bent onto cylinders
// (developable, or bumpy when `bump` > 0) and OBJ text of grid garments.
#include <refit/patterns/flatten.hpp>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace refit::test {

struct Piece {
  Points xyz;
  std::vector<Triangle> triangles;
  int nu = 0, nv = 0;  // cells around and up
};

inline Index grid_index(int i, int j, int nu) { return static_cast<Index>(j * (nu + 1) + i); }

/// nu x nv cells on a cylinder of `radius` (`angle` radians around, `height`
/// tall), each cell two triangles; `bump` cm of sinusoidal bumps make it non-developable.
inline Piece cylinder_piece(int nu, int nv, double radius, double height, double angle, double bump) {
  Piece p;
  p.nu = nu, p.nv = nv;
  p.xyz.resize((nu + 1) * (nv + 1), 3);
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const double a = angle * i / nu, y = height * j / nv;
      const double r = radius + bump * std::sin(2 * M_PI * 3 * i / nu) * std::sin(2 * M_PI * 2 * j / nv);
      p.xyz.row(grid_index(i, j, nu)) << r * std::cos(a), y, r * std::sin(a);
    }
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const Index a = grid_index(i, j, nu), b = grid_index(i + 1, j, nu), c = grid_index(i + 1, j + 1, nu),
                  d = grid_index(i, j + 1, nu);
      p.triangles.push_back({a, c, b});
      p.triangles.push_back({a, d, c});
    }
  return p;
}

/// A flat grid in z = 0 with irregular spacing.
inline Piece flat_piece(int nu, int nv) {
  Piece p = cylinder_piece(nu, nv, 10.0, 10.0, 1.0, 0.0);
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const double x = i + 0.3 * std::sin(1.7 * i + 0.9 * j), y = j + 0.3 * std::cos(0.8 * i - 1.3 * j);
      p.xyz.row(grid_index(i, j, nu)) << (i == 0 || i == nu ? i : x), (j == 0 || j == nv ? j : y), 0.0;
    }
  return p;
}

/// The border edges of a grid piece.
inline std::vector<std::pair<Index, Index>> border_edges(const Piece& p) {
  std::vector<std::pair<Index, Index>> e;
  for (int i = 0; i < p.nu; ++i) {
    e.emplace_back(grid_index(i, 0, p.nu), grid_index(i + 1, 0, p.nu));
    e.emplace_back(grid_index(i, p.nv, p.nu), grid_index(i + 1, p.nv, p.nu));
  }
  for (int j = 0; j < p.nv; ++j) {
    e.emplace_back(grid_index(0, j, p.nu), grid_index(0, j + 1, p.nu));
    e.emplace_back(grid_index(p.nu, j, p.nu), grid_index(p.nu, j + 1, p.nu));
  }
  return e;
}

/// OBJ text of a grid of nu x nv quads in the plane z = 0 (cell size 1, +y up),
/// with `before_face(i, j)` text written before the face of cell (i, j) (group
/// lines), and `vt` per corner when `uv` is set (u split at column `uv_cut`:
/// cells right of it get their own texture coordinates, a UV seam).
template <class Before>
std::string grid_obj(int nu, int nv, Before before_face, int uv_cut = -1) {
  std::string s;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) s += "v " + std::to_string(i) + " " + std::to_string(j) + " 0\n";
  if (uv_cut >= 0) {
    for (int side = 0; side < 2; ++side)
      for (int j = 0; j <= nv; ++j)
        for (int i = 0; i <= nu; ++i)
          s += "vt " + std::to_string(0.01 * i + side) + " " + std::to_string(0.01 * j) + "\n";
  }
  const auto corner = [&](int i, int j, int side) {
    const std::string v = std::to_string(grid_index(i, j, nu) + 1);
    if (uv_cut < 0) return v;
    return v + "/" + std::to_string(grid_index(i, j, nu) + 1 + side * (nu + 1) * (nv + 1));
  };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      s += before_face(i, j);
      const int side = uv_cut >= 0 && i >= uv_cut ? 1 : 0;
      s += "f " + corner(i, j, side) + " " + corner(i + 1, j, side) + " " + corner(i + 1, j + 1, side) + " " +
           corner(i, j + 1, side) + "\n";
    }
  return s;
}

inline std::string grid_obj(int nu, int nv) {
  return grid_obj(nu, nv, [](int, int) { return std::string(); });
}

}  // namespace refit::test
