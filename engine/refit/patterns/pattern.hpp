#pragma once
// A garment's 2D pattern (paper section 6, Fig. 10; issue 16): the garment cut
// into panels (panels.hpp), each flattened as rigidly as possible (flatten.hpp),
// measured against 3D (area, perimeter, per-face stretch, seam lengths), with
// the feature curves drawn in, oriented and laid out on a sheet (layout.hpp).
//
// Two steps, so that one cut serves several states of a garment (its original,
// its warp, its resize: the grading view compares them panel by panel):
// cut_pattern depends on the connectivity, the file's groups and UVs, and the
// original shape (seam and feature curves are placed on it); flatten_pattern
// flattens a state given by its vertex positions. A panel that cannot be
// flattened makes flatten_pattern throw refit::Error "FILE: panel 'NAME' (N
// faces) cannot be flattened: REASON", unless PatternOptions::skip_unflattenable
// (then it is left out with a warning).
#include <refit/features/feature_file.hpp>
#include <refit/patterns/feature_lines.hpp>
#include <refit/patterns/flatten.hpp>
#include <refit/patterns/panels.hpp>
#include <refit/patterns/seam_paths.hpp>

#include <string>
#include <vector>

namespace refit {

/// A dart cut into a panel (darts.hpp): a slit from the panel's edge to its apex.
struct Dart {
  Index panel = 0;
  std::vector<Index> garment_path;  // garment vertices from the edge (the waistline) to the apex
  double length_3d = 0;             // on the garment it was cut on
};

struct PatternCut {
  std::string file;                // the garment file, for messages
  PanelSet panels;
  std::vector<SeamPath> seam_paths;  // the seam curves' edge paths
  std::vector<FeatureLine> lines;    // the shape curves, per panel
  std::vector<Dart> darts;           // automatic darts (darts.hpp); their sides are seams of `panels`
};

/// Cuts `original` (see above): groups, UV seams and the seam curves of `specs`;
/// binds the shape curves of `specs` as feature lines. Throws refit::Error as
/// build_feature_curves and seam_paths do.
PatternCut cut_pattern(const Garment& original, const std::vector<FeatureSpec>& specs, const std::string& file,
                       const std::string& features_file = "");

struct PatternOptions {
  FlattenOptions flatten;
  bool skip_unflattenable = false;
  double margin = 2.0;           // between pieces on the sheet, in garment units
  Vec3 up = Vec3::UnitY();       // the garment's up: each piece is turned so that it points up the sheet (the grain)
  double stretch_warning = 0.05; // warn when a piece's 95th percentile of |log stretch| exceeds this
  // A panel is flattened again with its seams held (FlattenOptions::boundary_weight)
  // only where plain ARAP leaves a seam's two 2D lengths more than this fraction
  // of their mean apart (0: every panel with a seam). 0.1 %: a millimetre a metre.
  double seam_tolerance = 0.001;
  // A seam whose sides are still more than this fraction apart after that is held
  // again, ten times as hard, on both its pieces (issue 16: sewn edges within 0.5 %).
  double seam_agreement = 0.005;
};

struct PieceMeasures {
  double area_3d = 0, area_2d = 0, perimeter_3d = 0, perimeter_2d = 0;
  double stretch_p50 = 0, stretch_p95 = 0, stretch_max = 0;  // over faces: |log singular value| (measures.hpp)
  double triangle_stretch_p95 = 0;                           // the same over the fan triangles
  std::size_t flipped = 0;                                   // faces turned over in 2D
};

struct PatternPiece {
  bool flattened = false;
  Points2 uv;                        // per panel vertex, placed on the sheet
  std::vector<double> face_stretch;  // per panel face: |log s| of the worse singular value (measures.hpp)
  PieceMeasures measures;
  int iterations = 0;
  bool converged = false;
  bool seams_held = false;           // flattened again with its seams held (PatternOptions::seam_tolerance)
  double flatten_ms = 0;             // wall time of its flattenings (factorisations, conformal start, ARAP)
  double rotation = 0;               // radians the flattened piece was turned by to put its grain up
};

struct SeamMeasure {
  double length_3d = 0;
  std::array<double, 2> length_2d{};
  double mismatch = 0;  // |length_2d[0] - length_2d[1]| / their mean
};

struct Pattern {
  std::vector<PatternPiece> pieces;  // per panel
  std::vector<SeamMeasure> seams;    // per seam of the cut (0 where a side was not flattened)
  double width = 0, height = 0;      // of the sheet
  double stretch_p95 = 0;            // over the faces of every flattened piece
  double seam_mismatch_max = 0;
  std::vector<std::string> warnings;
};

/// The warnings for the panels of `cut` that cannot be flattened; throws the
/// first as refit::Error (see above) unless `skip`.
std::vector<std::string> unflattenable_panels(const PatternCut& cut, bool skip);

/// Flattens the garment state `positions` (same vertices as the cut's garment)
/// piece by piece (in parallel), measures it and lays it out.
Pattern flatten_pattern(const Garment& g, const PatternCut& cut, const Points& positions,
                        const PatternOptions& options = {});

/// p-th percentile (0..100) of `values` by linear interpolation; 0 when empty.
double percentile(std::vector<double> values, double p);

}  // namespace refit
