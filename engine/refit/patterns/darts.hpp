#pragma once
// Automatic darts (issue 16): a pattern piece over a doubly curved part of the
// body (waist to hip, the seat) cannot lie flat without stretch; a pattern maker
// cuts darts there. Where a piece's 95th percentile of per-face stretch is above
// the target, a dart is cut: a slit along garment edges from the piece's free
// top edge (the waistline: boundary edges of the garment itself, not seams, in
// the top fifth of the piece along the garment's up) downwards into the region
// of high stretch, ending at a point (the apex). Then the pattern is flattened
// again, until every piece is within the target or has its most darts.
//
// Placement: per vertex the area-weighted stretch of its faces; the dart is the
// path from the waistline, over interior vertices away from the piece's other
// edges, that gains most stretch above the target per unit length (a
// shortest-path tree whose edges cost their length plus 4 times their sideways
// part, never climbing: vertical-ish darts), ending where the gain is largest
// (where the stretch falls under the target), a tenth to a third of the
// piece's height long. The dart's two sides are a seam
// like any other (pattern.cpp holds them at one length).
#include <refit/patterns/pattern.hpp>

#include <vector>

namespace refit {

struct DartOptions {
  double max_stretch = 0.0;  // target of each piece's stretch p95; 0 = no darts
  int max_per_panel = 6;     // darts per piece, at most
};

/// Cuts darts into `cut` (made on `original`) until each piece's stretch p95,
/// flattened at the original's positions with `options`, is at most
/// `darts.max_stretch` or it has `darts.max_per_panel` darts. Returns the
/// pattern of the original with the final cut. Fills cut.darts.
Pattern cut_darts(const Garment& original, PatternCut& cut, const PatternOptions& options, const DartOptions& darts);

/// The seam of `cut.panels` that is the dart (its two sides), or -1.
long dart_seam(const PatternCut& cut, const Dart& dart);

}  // namespace refit
