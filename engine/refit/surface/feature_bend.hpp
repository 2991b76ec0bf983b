#pragma once
// Beyond the paper: the surface leaves the feature curves smoothly.
//
// Eq. 13 is of Laplace type: every free agent is its ring's weighted mean plus
// its offset h. Such a system holds the feature agents exactly but bends across
// them within one agent spacing: where an optimised curve stands off the rest
// of the solution (the straight front profile of `refit demo`, 1 cm outside a
// surface that returns to the original's flatter front and rests on the belly
// of body B), the garment shows a crease along the curve, whatever the agent
// count. Around the features the surface is solved again in least squares over
// the rows of eq. 13 of the zone and of the feature agents themselves (a system
// of biharmonic type): the feature agents' own rows then count too, so the
// surface meets the held curve with the curve's slope instead of a kink. The
// zone's border keeps the first solution, and its rows count too. Measured in
// bench/README.md ("The pinch at the centre-front waist").
#include <refit/core/types.hpp>
#include <refit/surface/agent_system.hpp>

#include <cstdint>
#include <functional>
#include <vector>

namespace refit {

struct FeatureBendReport {
  std::size_t agents = 0;  // agents solved again
  int rounds = 0;          // least-squares solves (one more per clearance round)
  bool solved = false;     // false: nothing to solve, or the factorisation failed (x kept)
};

/// Per agent, the one-ring steps (over `ring`) to the nearest feature agent
/// (fixed[a] == 2), up to `rings`; -1 farther, or with no feature agent.
std::vector<int> feature_depth(const Csr& ring, const std::vector<std::uint8_t>& fixed, int rings);

/// Solves the agents within `rings` one-ring steps of a feature agent (fixed[a]
/// == 2) again: the unknowns are the zone's agents short of its border that are
/// free or held by a clearance round (fixed[a] == 3; free[a] or that), the rows
/// those of eq. 13 (`rows`, right-hand side `h`) of every zone agent, feature
/// agents and the border's agents included (so the surface also leaves the zone
/// with the first solution's slope); everything else keeps its x. With `hold_clear`
/// (it moves the agents a solve left too close to body B among those it is given,
/// marks them fixed[a] = 3 and returns their count), up to `clearance_rounds` such
/// agents are held and the zone solved again. Sparse Cholesky of the normal
/// equations (Eigen); deterministic.
FeatureBendReport bend_around_features(
    const AgentRows& rows, const Points& h, int rings, const std::vector<std::uint8_t>& free,
    std::vector<std::uint8_t>& fixed, Points& x, int clearance_rounds,
    const std::function<std::size_t(const std::vector<std::uint8_t>&)>& hold_clear);

}  // namespace refit
