#include <refit/core/error.hpp>
#include <refit/pipeline/units.hpp>

namespace refit {

double units_per_cm(const std::string& units) {
  if (units == "cm") return 1.0;
  if (units == "mm") return 10.0;
  if (units == "m") return 0.01;
  if (units == "in") return 1.0 / 2.54;
  throw Error("--units: unknown unit '" + units + "' (use cm, mm, m or in)");
}

}  // namespace refit
