#pragma once
// Beyond the paper: the surface step's clearance rounds. Eq. 14 holds only the
// agents the warp put within epsilon of body B. A free region a little farther
// out (a bodice with 1.5 cm of ease over a bigger bust, a skirt over bigger
// hips) returns to its original shape and sinks into body B, and the collision
// step can only push vertices out afterwards. So each free agent the solve
// leaves closer than the clearance (or inside) is held at the nearest point that
// clears the body by it, and the system is solved again from there (an active
// set, usually one round): the rest of the surface bends around the contact by
// eq. 13 instead of by a later smoothing. Measured on the 6k test dress
// (SurfaceDress tests): 92 vertices inside body B before collision -> 15,
// collision moves 179 vertices instead of 470, the held-out slices 4.2x/3.6x ->
// 4.2x/3.2x after collision; on the procedural 4M dress 323k vertices inside ->
// 0. Holding them at their warped positions instead keeps only 1.9x/1.6x (the
// warp's bumps come back around every held agent).
#include <refit/core/types.hpp>

#include <cstdint>
#include <functional>
#include <vector>

namespace refit {

/// The point nearest p at `clearance` from body B (`distance`: signed, negative
/// inside): Newton steps along the distance's gradient (central differences of
/// width `step`); where that fails (an edge of a bounded distance), the point on
/// the way from p back to `fallback` (the warped position) that clears it.
Vec3 clear_point(const std::function<double(const Vec3&)>& distance, double clearance, double step, Vec3 p,
                 const Vec3& fallback);

/// Moves every agent with free[a] whose x lies closer than `clearance` to body B
/// to its clear_point (falling back towards `warped`), marks it fixed[a] = 3 and
/// returns how many it moved. Parallel; the result does not depend on the threads.
std::size_t hold_clear_of_body(const std::function<double(const Vec3&)>& distance, double clearance, double step,
                               const std::vector<std::uint8_t>& free, const Points& warped, Points& x,
                               std::vector<std::uint8_t>& fixed);

/// Beyond the paper's eq. 14 (SurfaceOptions::near_body_band): moves every agent
/// with free[a] whose x lies farther from body B than ceiling[a] to the nearest
/// point at that distance (Newton steps as clear_point; where they fail, the point
/// on the way back to `warped` that is that close), marks it fixed[a] = 4 and
/// returns how many it moved. Parallel; the result does not depend on the threads.
std::size_t hold_near_body(const std::function<double(const Vec3&)>& distance, const std::vector<double>& ceiling,
                           double step, const std::vector<std::uint8_t>& free, const Points& warped, Points& x,
                           std::vector<std::uint8_t>& fixed);

}  // namespace refit
