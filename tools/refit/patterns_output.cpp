// Pattern files of a garment state; see patterns_output.hpp.
#include "patterns_output.hpp"

#include "report_file.hpp"

#include <refit/core/error.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/patterns/dxf.hpp>
#include <refit/patterns/grading.hpp>
#include <refit/patterns/report.hpp>
#include <refit/patterns/svg.hpp>

#include <filesystem>

namespace refit::cli {
namespace {

void write_text(const std::string& path, const std::string& text) {
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace

void add_pattern_options(CLI::App& app, PatternsOptions& o, const std::string& advanced, const std::string& group) {
  std::vector<CLI::Option*> main;
  main.push_back(app.add_option("--sheet-units", o.sheet_units, "Units of the SVG: cm or mm (true scale either way)")
                     ->check(CLI::IsMember({"cm", "mm"}))
                     ->capture_default_str());
  main.push_back(app.add_flag("--stretch-map", o.stretch_map, "Colour the SVG's pieces by their stretch against 3D"));
  main.push_back(app.add_flag("--skip-unflattenable", o.skip_unflattenable,
                              "Leave out panels that cannot be flattened (with a warning) instead of failing"));
  main.push_back(app.add_option("--darts", o.darts,
                                "auto: cut darts from the waistline where a piece stretches more than --dart-target "
                                "(95th percentile of its faces); none: no darts")
                     ->check(CLI::IsMember({"auto", "none"}))
                     ->capture_default_str());
  main.push_back(app.add_option("--dart-target", o.dart.max_stretch, "With --darts auto: the stretch p95 each piece is cut down to")
                     ->check(CLI::Range(1e-4, 1.0))
                     ->capture_default_str());
  main.push_back(app.add_option("--max-darts", o.dart.max_per_panel, "With --darts auto: darts per piece, at most")
                     ->check(CLI::Range(0, 100))
                     ->capture_default_str());
  if (!group.empty())
    for (CLI::Option* opt : main) opt->group(group);
  app.add_option("--boundary-weight", o.flatten.boundary_weight,
                 "Weight that keeps the pieces' outlines at their 3D length (0 = plain ARAP; seams then agree less)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str()
      ->group(advanced);
  app.add_option("--seam-tolerance", o.seam_tolerance,
                 "A piece is flattened again with its seams held only where plain ARAP leaves a seam's two sides "
                 "more than this fraction of their length apart (0: every piece with a seam)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str()
      ->group(advanced);
  app.add_option("--conformal-iterations", o.flatten.conformal_iterations,
                 "Conjugate-gradient iterations of the conformal start, at most")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str()
      ->group(advanced);
  app.add_option("--arap-iterations", o.flatten.max_iterations, "ARAP iterations per piece, at most")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str()
      ->group(advanced);
  app.add_option("--arap-tolerance", o.flatten.tolerance,
                 "ARAP stops when an iteration lowers the energy by less than this fraction")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str()
      ->group(advanced);
}

std::vector<std::string> pattern_paths(const std::string& dir, const std::string& name, bool grading) {
  const std::filesystem::path base = std::filesystem::path(dir) / name;
  std::vector<std::string> out = {base.string() + ".svg", base.string() + ".dxf", base.string() + ".json"};
  if (grading) out.push_back(base.string() + "-grading.svg");
  return out;
}

PatternWriter::PatternWriter(std::shared_ptr<const Garment> original, const std::vector<FeatureSpec>& specs,
                             const std::string& garment_file, const std::string& features_file, PatternsOptions options)
    : garment_(std::move(original)), options_(std::move(options)) {
  pattern_options_.skip_unflattenable = options_.skip_unflattenable;
  pattern_options_.flatten = options_.flatten;
  pattern_options_.seam_tolerance = options_.seam_tolerance;
  pattern_options_.margin = 2.0 / (100.0 * metres_per_unit(options_.units));  // 2 cm
  cut_ = cut_pattern(*garment_, specs, garment_file, features_file);
  unflattenable_panels(cut_, options_.skip_unflattenable);  // refused before any work
  if (options_.darts == "auto") original_ = cut_darts(*garment_, cut_, pattern_options_, options_.dart);
}

const Pattern& PatternWriter::original_pattern() const {
  if (!original_) original_ = flatten_pattern(*garment_, cut_, garment_->positions, pattern_options_);
  return *original_;
}

nlohmann::json PatternWriter::write(const std::string& name, const Points& positions, bool grade) const {
  const Pattern pattern = flatten_pattern(*garment_, cut_, positions, pattern_options_);
  const double cm_per_unit = 100.0 * metres_per_unit(options_.units);
  const std::vector<std::string> paths = pattern_paths(options_.dir, name, grade);
  nlohmann::json report = pattern_report(*garment_, cut_, pattern, positions, options_.units);
  OutputBatch batch;  // the files of one state appear together
  write_text(paths[0], sheet_svg(pattern_sheet(*garment_, cut_, pattern, options_.stretch_map), cm_per_unit,
                                 options_.sheet_units));
  write_text(paths[1], sheet_dxf(pattern_sheet(*garment_, cut_, pattern), options_.units));
  if (grade) {
    const Pattern& before = original_pattern();
    const Grading grading = grade_pattern(*garment_, cut_, before, pattern);
    report["grading"] = grading_report(grading);
    report["grading"]["original"] = {{"stretch_p95", before.stretch_p95}, {"seam_mismatch_max", before.seam_mismatch_max}};
    write_text(paths[3], sheet_svg(grading_sheet(*garment_, cut_, before, pattern, grading, pattern_options_.margin),
                                   cm_per_unit, options_.sheet_units));
  }
  write_json_report(paths[2], report);
  batch.commit();
  nlohmann::json summary = {{"svg", paths[0]},
                            {"dxf", paths[1]},
                            {"report", paths[2]},
                            {"panels", cut_.panels.panels.size()},
                            {"darts", report["darts"]},
                            {"stretch_p95", pattern.stretch_p95},
                            {"seam_mismatch_max", pattern.seam_mismatch_max},
                            {"warnings", pattern.warnings}};
  if (grade) {
    summary["grading_svg"] = paths[3];
    summary["straightness_mean"] = report["grading"]["straightness_mean"];
    summary["straightness_max"] = report["grading"]["straightness_max"];
  }
  return summary;
}

}  // namespace refit::cli
