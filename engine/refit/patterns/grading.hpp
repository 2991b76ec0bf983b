#pragma once
// The grading view (issue 16 item 4): a garment's pattern before and after a
// resize (or a warp), piece by piece, from one cut (pattern.hpp), so every piece
// and feature line is the same material in both. Per piece: its size change
// (area, perimeter, width and height along the grain); per feature line: its 2D
// straightness, the paper's S-shape distortion (section 6, Fig. 10): how far the
// line is from its own shape on the original pattern after the best similarity
// (rotation, uniform scale, translation), as RMS distance over the original
// line's length. The sheet puts each original piece (grey) beside its resized
// self (black, turned to match it), labelled with the size change.
#include <refit/patterns/sheet.hpp>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace refit {

struct LineGrading {
  std::string name;
  double length_original = 0, length = 0;  // in 2D, garment units
  double deviation = 0;                    // RMS after the best similarity / original length
};

struct PieceGrading {
  std::string panel;
  bool graded = false;  // flattened in both patterns
  double area_change = 0, perimeter_change = 0, width_change = 0, height_change = 0;  // resized / original - 1
  std::vector<LineGrading> lines;
};

struct Grading {
  std::vector<PieceGrading> pieces;  // per panel
  std::size_t lines = 0;
  double deviation_mean = 0, deviation_max = 0;  // over every feature line of every graded piece
};

/// RMS distance of `line` from `original` (row i to row i) after the best 2D
/// similarity of the original onto it (closed form; no reflection), over the
/// original's polyline length. Throws refit::Error when the rows differ, there
/// are fewer than 2, or the original has zero length.
double shape_deviation_2d(const Points2& line, const Points2& original, bool closed);

/// Compares two patterns of the same cut (see above).
Grading grade_pattern(const Garment& g, const PatternCut& cut, const Pattern& original, const Pattern& resized);

/// The side-by-side sheet of `grading`.
Sheet grading_sheet(const Garment& g, const PatternCut& cut, const Pattern& original, const Pattern& resized,
                    const Grading& grading, double margin);

/// The grading as JSON: per piece its changes and lines, and the summary.
nlohmann::json grading_report(const Grading& grading);

}  // namespace refit
