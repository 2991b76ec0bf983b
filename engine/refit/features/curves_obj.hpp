#pragma once
// Feature curves as OBJ polylines for inspection (`--curves-out`, `refit features`), in the garment's units.
#include <refit/features/feature_curves.hpp>
#include <refit/features/shape_matching.hpp>

#include <string>
#include <vector>

namespace refit {

/// Writes each curve's samples as one OBJ `l` polyline in group `<name>_original`
/// (closed curves repeat their first vertex at the end). Atomic: the file appears
/// whole or not at all. Throws refit::Error when it cannot be written.
void write_curves_obj(const std::string& path, const std::vector<FeatureCurve>& curves);

/// Writes, per curve, groups `<name>_original`, `<name>_warped` and
/// `<name>_optimised` with the respective sample polylines. Atomic.
void write_curves_obj(const std::string& path, const FeatureResult& result);

}  // namespace refit
