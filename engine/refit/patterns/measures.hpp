#pragma once
// How far a flattened piece is from its 3D shape: area and perimeter in 3D and
// 2D, and per face its stretch, the singular values s1 >= s2 of the linear map
// that best takes the face's corners from 3D (in the face's best-fit plane) to
// 2D, in the least-squares sense (exact for a triangle; a quad's four corners
// average the sawtooth that its two triangles show on a bumpy surface). A face
// turned over in 2D has s2 < 0.
#include <refit/patterns/panels.hpp>

#include <array>
#include <span>
#include <vector>

namespace refit {

/// Singular values of the best linear map of the corners `xyz` (n x 3, n >= 3)
/// to `uv` (n x 2), s1 >= |s2|, s2 negative when the map turns the face over
/// (with respect to the corners' order). {0, 0} for a face of no area.
std::array<double, 2> face_singular_values(const Points& xyz, const Points2& uv);

/// |log |s|| of the worse singular value: 0 for an isometry (and for a face of
/// no area); a collapsed face counts as s = 1e-12 (27.6), a turned-over one by
/// the size of its singular values (the turn is counted apart).
double log_stretch(const std::array<double, 2>& s);

struct PieceStretch {
  std::vector<double> face;      // per panel face (Panel::faces order): log_stretch of its singular values
  std::vector<double> triangle;  // per panel triangle: the same for the triangle alone
  double area_3d = 0, area_2d = 0, perimeter_3d = 0, perimeter_2d = 0;
  std::size_t flipped = 0;       // faces turned over
};

/// The measures of a panel flattened from `xyz` (panel vertices) to `uv`.
PieceStretch measure_piece(const Garment& g, const PanelSet& set, std::size_t panel, const Points& xyz,
                           const Points2& uv);

}  // namespace refit
