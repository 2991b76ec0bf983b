#pragma once
// The pattern's JSON report: per panel its size in 3D and 2D, its stretch and
// its feature lines; per seam the lengths of its two sides; the cuts made and
// the warnings. Every length in the garment's units, changes as fractions
// (0.01 = 1 %). Documented in docs/patterns.md.
#include <refit/patterns/pattern.hpp>

#include <nlohmann/json.hpp>

#include <string>

namespace refit {

/// The report of `pattern`, flattened from the garment state `positions`.
nlohmann::json pattern_report(const Garment& g, const PatternCut& cut, const Pattern& pattern, const Points& positions,
                              const std::string& units);

/// One line per panel for `refit inspect`: name, faces, vertices, boundary
/// loops, and why it cannot be flattened when it cannot.
std::vector<std::string> panel_lines(const PatternCut& cut);

}  // namespace refit
