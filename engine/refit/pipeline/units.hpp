#pragma once
// Physical constants of the method are in cm (epsilon = 1 cm, clearance 0.2 cm);
// --units says what one garment unit is, and this converts.
#include <string>

namespace refit {

/// Garment units per centimetre for "cm", "mm", "m" or "in". Throws refit::Error otherwise.
double units_per_cm(const std::string& units);

}  // namespace refit
