#pragma once
// The feature file (JSON): which curves of a garment must keep their shape
// (paper section 4.2 without a GUI). Format (documented in the README):
//
//   { "units": "cm",                       optional; default: the garment's units
//     "features": [ {
//        "name": "left-profile",             required, unique, non-empty
//        "plane": { "point": [x,y,z], "normal": [x,y,z] }      or
//                 { "segment": [[x,y,z],[x,y,z]], "view": [x,y,z] },
//                                            required for bspline and slice
//        "curve": { "kind": "bspline", "degree": 3, "closed": false,
//                   "control_points": [[x,y,z], ...] }         or
//                 { "kind": "slice", "near": [x,y,z], "from": [x,y,z], "to": [x,y,z],
//                   "control_points": 12 }  (from, to optional; control_points default 12)
//                 { "kind": "boundary", "near": [x,y,z] },
//        "samples": 80,                     required; >= 5 open, >= 3 closed
//        "role": "shape" } ] }               optional: "shape" (default) keeps its shape in a
//                                            resize; "seam" is where the garment is cut into
//                                            pattern pieces (not a boundary; ignored by resize)
//
// Coordinates are converted from the file's "units" (cm, mm, m, in) to the
// garment's units. Unknown keys are refused (they are usually typos).
#include <refit/core/types.hpp>
#include <refit/features/plane.hpp>

#include <optional>
#include <string>
#include <vector>

namespace refit {

enum class CurveKind { bspline, slice, boundary };
/// What a curve is for: a shape to keep (paper section 4) or a seam line along
/// which the garment is cut into pattern pieces (refit/patterns).
enum class CurveRole { shape, seam };

const char* to_string(CurveKind kind);
const char* to_string(CurveRole role);

struct FeatureSpec {
  std::string name;
  std::string file;  // the feature file, for messages ("" when parsed from text without one)
  CurveKind kind = CurveKind::bspline;
  CurveRole role = CurveRole::shape;
  std::optional<FeaturePlane> plane;  // absent only for boundary (then the loop's PCA plane)
  std::size_t samples = 0;
  // bspline
  int degree = 3;
  bool closed = false;  // bspline: as given; boundary: true; slice: decided by the cut piece
  Points control_points;  // bspline control points (garment units), n x 3
  // slice and boundary
  Vec3 near = Vec3::Zero();
  std::optional<Vec3> from, to;       // slice clipping points
  std::size_t fit_control_points = 12;  // slice: control points of the least-squares B-spline
};

/// Metres per unit for "cm", "mm", "m", "in"; throws refit::Error naming `file` otherwise.
double metres_per_unit(const std::string& units, const std::string& file = "");

/// Parses and validates feature JSON text (see the format above). `file` names the
/// source in messages; `garment_units` are the units coordinates are converted to.
/// Throws refit::Error "FILE: feature 'NAME': problem" (or "FILE:LINE: ..." for
/// JSON syntax errors) on any invalid field: unknown kind or key, wrong type,
/// missing field, non-finite number, zero normal, degenerate segment or view,
/// too few samples or control points, duplicate names.
std::vector<FeatureSpec> parse_feature_json(const std::string& text, const std::string& file,
                                            const std::string& garment_units = "cm");

/// The specs of one role, in file order (a resize keeps the shapes; the
/// pattern maker cuts along the seams).
std::vector<FeatureSpec> features_with_role(const std::vector<FeatureSpec>& specs, CurveRole role);

/// Reads and parses a feature file (see parse_feature_json); throws refit::Error
/// when it cannot be read.
std::vector<FeatureSpec> read_feature_file(const std::string& path, const std::string& garment_units = "cm");

/// The fewest samples a curve may have: 5 open (eqs. 5-6 need two neighbours on
/// each side), 3 closed.
inline std::size_t min_samples(bool closed) { return closed ? 3 : 5; }
/// Largest 'samples' of a feature and 'control_points' of a fitted slice the
/// feature file accepts: a run stays within seconds (bench/README.md).
inline constexpr double kMaxSamples = 5000;
inline constexpr double kMaxFitControlPoints = 500;

}  // namespace refit
