#pragma once
// Writing a garment's 2D patterns (engine/refit/patterns), shared by `refit
// flatten` and `refit resize --patterns-out`: the original garment is cut and
// flattened once; each state written gives DIR/NAME.svg, DIR/NAME.dxf,
// DIR/NAME.json and, when graded against the original, DIR/NAME-grading.svg.
#include <refit/features/feature_file.hpp>
#include <refit/patterns/darts.hpp>
#include <refit/patterns/pattern.hpp>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace refit::cli {

struct PatternsOptions {
  std::string dir;
  std::string sheet_units = "cm";  // of the SVG: cm or mm
  std::string units = "cm";        // of the garment (and the DXF)
  bool stretch_map = false;
  bool skip_unflattenable = false;
  std::string darts = "none";  // auto: cut darts where a piece stretches more than dart.max_stretch
  DartOptions dart{0.02, 6};
  FlattenOptions flatten;
  double seam_tolerance = PatternOptions{}.seam_tolerance;
};

/// Adds the pattern options shared by `flatten` and `resize --patterns-out`
/// (sheet units, stretch map, skipping, darts, and the flattening's advanced
/// knobs in `advanced_group`); all in `group` when it is not empty.
void add_pattern_options(CLI::App& app, PatternsOptions& o, const std::string& advanced_group,
                         const std::string& group = "");

inline PatternsOptions with_units(PatternsOptions o, const std::string& units) {
  o.units = units;
  return o;
}

/// The files write() makes for `name` (checked before any work by the callers).
std::vector<std::string> pattern_paths(const std::string& dir, const std::string& name, bool grading);

class PatternWriter {
 public:
  /// Cuts `original` along its groups, UV seams and the seam curves of `specs`,
  /// and with darts "auto" cuts darts too (flattening the original once).
  PatternWriter(std::shared_ptr<const Garment> original, const std::vector<FeatureSpec>& specs,
                const std::string& garment_file, const std::string& features_file, PatternsOptions options);

  /// Flattens the garment at `positions` and writes its files; with `grade`,
  /// compares it with the original's pattern. Returns the report's summary.
  nlohmann::json write(const std::string& name, const Points& positions, bool grade) const;

  const PatternCut& cut() const { return cut_; }

 private:
  const Pattern& original_pattern() const;

  std::shared_ptr<const Garment> garment_;
  PatternsOptions options_;
  PatternOptions pattern_options_;
  PatternCut cut_;
  mutable std::optional<Pattern> original_;
};

}  // namespace refit::cli
