#pragma once
// Feature curves drawn into the pattern as internal lines: each sample bound
// once to the face it lies on (of the original garment), so the same material
// line is found on the pattern of any state of the garment (the original, the
// warp, the resize), which is what the grading view compares.
//
// In: the original garment, its panels, the feature curves sampled on it. Out:
// per curve, its runs of consecutive samples on one panel (a curve that crosses
// a seam becomes one line per panel it runs over; runs of fewer than 2 samples
// are dropped), and their 2D points on a flattened panel.
#include <refit/features/feature_curves.hpp>
#include <refit/patterns/flatten.hpp>
#include <refit/patterns/panels.hpp>

#include <array>
#include <span>
#include <string>
#include <vector>

namespace refit {

/// A sample on a face: fan triangle (corner 0, k, k+1) of `face`, with weights.
struct FaceSample {
  Index face = 0, k = 1;
  std::array<double, 3> weight{};
};

struct FeatureLine {
  std::string name;     // the curve's name, "#2", "#3"... for its later runs
  std::string curve;    // the curve's name
  Index panel = 0;
  bool closed = false;  // the whole closed curve on one panel
  std::vector<FaceSample> samples;
};

/// Binds the curves' samples to the faces of `original` and splits them into
/// runs per panel (see above). Samples that lie on `l` or `p` elements are left out.
std::vector<FeatureLine> bind_feature_lines(const Garment& original, const PanelSet& panels,
                                            std::span<const FeatureCurve> curves);

/// The line's points on its panel flattened to `uv` (panel vertices).
Points2 line_points(const FeatureLine& line, const PanelSet& panels, const Garment& g, const Points2& uv);

/// The line's points on the garment in 3D at `positions`.
Points line_points_3d(const FeatureLine& line, const Garment& g, const Points& positions);

}  // namespace refit
