#pragma once
// The faces the collision step's last rounds turn over (issue 13, item 4). The
// step smooths the warp's folds out before its pushes and after each pass of
// them, but its last rounds (over what a pass moved, then over what is left
// inside body B) push with no smoothing after them: on the 1M dress they turned
// 3 slivers against their corners on F_thinner, and the outfit's 4 on F_thinner
// were all such (bench/README.md, "Faces the last rounds turn over").
#include <refit/body/body_surface.hpp>
#include <refit/surface/folds.hpp>

#include <cstdint>
#include <vector>

namespace refit {

struct LastFoldsReport {
  FoldReport folds;      // smooth_out_folds' figures
  std::size_t held = 0;  // vertices the smoothing moved that kept their place (too close to body B there)
};

/// The faces of `positions` turned against their corners smoothed out as
/// smooth_out_folds does, by its rounds only (with its reshaping of the faces
/// that only lean, the 1M dress on a thinner and taller body came out with 4
/// faces turned over instead of 2).
/// A vertex the smoothing moves takes its new place only where that is clear of
/// body B by `clearance` (less a thousandth of it, the pushes' own rounding);
/// else it keeps the place the pushes gave it.
LastFoldsReport smooth_out_last_folds(const Garment& g, const FoldBinding& binding, Points& positions,
                                      const Csr& adjacency, const std::vector<std::uint8_t>* pinned,
                                      const BodySurface& body_b, double clearance);

}  // namespace refit
