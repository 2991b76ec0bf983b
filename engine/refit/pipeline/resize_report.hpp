#pragma once
// The parts of a resize report that the in-memory pipeline (resize.cpp) and the
// chunked one (refit/chunked) share, so both give the same report. Lengths in
// the garment's units, times in ms; plain functions of their arguments.
#include <refit/features/shape_matching.hpp>
#include <refit/features/symmetry.hpp>
#include <refit/surface/surface.hpp>

#include <nlohmann/json.hpp>

#include <vector>

namespace refit {

/// The rows of `parts`, one after another.
Points concat_rows(const std::vector<const Points*>& parts);

/// The report's "symmetry" object as the binding finds it (body B's figures
/// and the mirrored curves' names are added later).
nlohmann::json symmetry_report(const SymmetryCheck& sym);

/// The report's "surface" object.
nlohmann::json surface_report(const SurfaceStats& s);

/// The report's "features" list: per curve its fixed samples and shape figures.
nlohmann::json features_report(const FeatureResult& curves);

/// Every feature figure of the report measured on the written garment (after
/// the collision step, issue 13), the surface step's own beside it: the curves'
/// samples carried on the written garment, on the warp, and before the collision.
void report_written_features(const FeatureResult& curves, const Points& on_result, const Points& on_warp,
                             const Points& before_collision, nlohmann::json& report);

}  // namespace refit
