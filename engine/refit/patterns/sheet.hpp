#pragma once
// A drawing of pattern pieces, independent of the file format (svg.hpp and
// dxf.hpp write it): polylines on named layers, texts and filled triangles, in
// the garment's units, y up, the sheet from (0, 0) to (width, height).
//
// Layers: CUT (piece outlines: closed polylines, one per boundary loop), FEATURES
// (the feature curves as internal lines), GRAIN (the grain line: the garment's up
// direction), TEXT (piece names and figures), STRETCH (optional colour map).
#include <refit/patterns/pattern.hpp>

#include <array>
#include <string>
#include <vector>

namespace refit {

inline constexpr const char* kCutLayer = "CUT";
inline constexpr const char* kFeatureLayer = "FEATURES";
inline constexpr const char* kGrainLayer = "GRAIN";
inline constexpr const char* kTextLayer = "TEXT";

struct SheetPath {
  Points2 points;
  bool closed = false;
  std::string layer;
  std::string colour = "#000000";
  bool dashed = false;
};

struct SheetText {
  Eigen::Vector2d at = Eigen::Vector2d::Zero();  // centre of the text's baseline
  std::string text;
  double height = 1.0;                           // garment units
  std::string layer = kTextLayer;
};

struct SheetFill {
  std::array<Eigen::Vector2d, 3> corners;
  std::string colour;
};

struct Sheet {
  double width = 0, height = 0;
  std::vector<SheetPath> paths;
  std::vector<SheetText> texts;
  std::vector<SheetFill> fills;  // drawn first, under the lines
};

/// The laid-out pattern as a sheet: per flattened piece its outlines, feature
/// lines, grain line and name; with `stretch_map`, each triangle filled by its
/// stretch (white 0, yellow 2.5 %, red 5 % and more) and a legend.
Sheet pattern_sheet(const Garment& g, const PatternCut& cut, const Pattern& pattern, bool stretch_map = false,
                    const std::string& colour = "#000000");

/// Where text of `height` fits a piece: its area-weighted centroid, and a
/// height of at most a tenth of the piece's box height.
SheetText piece_label(const Panel& panel, const Points2& uv, const std::string& text, double height);

/// The piece's outlines and feature lines (layers CUT and FEATURES) in `colour`.
void add_piece(Sheet& sheet, const Garment& g, const PatternCut& cut, std::size_t panel, const Points2& uv,
               const std::string& colour, bool dashed = false);

}  // namespace refit
