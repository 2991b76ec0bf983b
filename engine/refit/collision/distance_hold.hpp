#pragma once
// The distance hold (issue 13, beyond the paper; runs before penetration
// resolution): garment vertices that sat on body A or close to it keep their
// distance to body B. The surface step restores the garment's original local
// shape, so where body B is thinner a fitted skirt stays where body A's hips were
// (measured on the real skirt: vertices 0.7 cm off body A ended 2.7 cm off the
// thinner body B), and where it is fuller the garment sinks towards it. Each held
// vertex whose distance to body B differs from its distance to body A by more
// than `tolerance` moves along body B's normal by the excess; the move spreads
// smoothly over up to `smoothing_rings` edges (vertices there that are not held
// take a falloff, held ones keep exactly their own move), and no face is turned
// over. Penetration resolution afterwards lifts what still needs clearance.
#include <refit/body/body_surface.hpp>
#include <refit/core/garment.hpp>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <vector>

namespace refit {

struct DistanceHoldOptions {
  double tolerance = 0.1;    // garment units (0.1 cm): a change of distance this small is left alone
  double reach = 4.0;        // garment units: a held vertex farther than its distance plus this from body B is left alone
  int smoothing_rings = 6;   // how far (in edges) a move spreads
  int smoothing_passes = 12; // Jacobi passes of the displacement field
  int unfold_passes = 20;    // passes that undo a move turning a face over (unfold.hpp)
  /// Per vertex (or null): vertices that must not move (the corners of the faces
  /// the feature curves sit on).
  const std::vector<std::uint8_t>* pinned = nullptr;
};

struct DistanceHoldReport {
  std::size_t held = 0;          // vertices with a distance to keep
  std::size_t corrected = 0;     // ... that were off it by more than the tolerance
  double largest_change = 0.0;   // before the hold: largest |distance to B - distance to A| over the held vertices
  std::size_t moved = 0;         // vertices moved (corrected + spread)
  double max_displacement = 0.0;

  nlohmann::json to_json() const;
};

/// Per garment vertex, its signed distance to `body_a` when that is in [0, band]
/// (outside the body and near it), else NaN: the distances the hold keeps.
/// Parallel; the same for any thread count.
std::vector<double> near_body_distances(const Points& positions, const BodySurface& body_a, double band);

/// Moves the held vertices (finite `distance_a[v]`) to their distance on
/// `body_b`, in place (see above). Throws refit::Error when the sizes differ.
/// Parallel; bit-identical for any thread count.
DistanceHoldReport hold_body_distance(const Garment& g, Points& positions, const BodySurface& body_b,
                                      const std::vector<double>& distance_a, const DistanceHoldOptions& options = {});

}  // namespace refit
