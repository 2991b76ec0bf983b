#pragma once
// Laying flattened pieces out on a sheet: each piece turned so that the
// garment's up direction runs up the sheet (the grain line of a paper pattern),
// then packed in shelves without overlap.
//
// In: a flattened piece (3D and 2D positions, triangles), or the pieces' bounding
// boxes. Out: a rotation angle; the lower-left corner of every box on the sheet
// (y up) and the sheet's size. Boxes never overlap and keep `margin` apart.
#include <refit/patterns/flatten.hpp>

#include <span>
#include <vector>

namespace refit {

/// Radians to turn `uv` by (counter-clockwise) so that `up` points along +y: the
/// area-weighted mean of the 2D images of up's projection on each triangle.
/// 0 when up is normal to the whole piece.
double grain_rotation(const Points& xyz, const Points2& uv, std::span<const Triangle> triangles, const Vec3& up);

/// `uv` turned by `angle` radians about the origin.
Points2 rotated(const Points2& uv, double angle);

struct Box {
  double width = 0, height = 0;
};

struct Packing {
  std::vector<Eigen::Vector2d> corner;  // lower-left corner of each box
  double width = 0, height = 0;         // the sheet
};

/// Shelf packing: boxes by decreasing height (then index) fill rows left to
/// right, rows stacked downwards from the top of the sheet; the row width is
/// about 1.5 x sqrt(total area), at least the widest box.
Packing pack_boxes(std::span<const Box> boxes, double margin);

}  // namespace refit
