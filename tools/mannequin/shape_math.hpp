#pragma once
// Small shape helpers shared by the body and the garment generators.
#include <algorithm>
#include <numbers>

namespace refit::mannequin {

inline constexpr double kPi = std::numbers::pi;

/// 0 below 0, 1 above 1, smooth (C1) in between.
inline double smoothstep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

}  // namespace refit::mannequin
