#pragma once
// How good a resize is, in a few numbers (issue 5): fit near body A, garment
// vertices inside body B, surface sanity, and for feature curves their shape
// error, turning-angle change and profile straightness. Used by the pipeline's
// report and by `refit compare`, which scores any result with the same vertex
// order (Refit's or another tool's). Lengths in the garment's units (the 1 cm
// fit band converted by the caller); plain functions of their arguments,
// parallel inside, the same figures for any thread count.
#include <refit/body/body_mesh.hpp>
#include <refit/body/body_surface.hpp>
#include <refit/attach/attachment.hpp>
#include <refit/core/garment.hpp>
#include <refit/features/feature_file.hpp>

#include <nlohmann/json.hpp>

#include <array>
#include <string>
#include <vector>

namespace refit {

/// Garment vertices that were within `band` of body A: how their distance to the
/// body changed from A (original) to B (result). change = d_B(result) - d_A(original).
struct FitMetrics {
  double band = 1.0;
  std::size_t vertices = 0;     // vertices within the band on A
  double mean_change = 0.0;     // signed mean
  double mean_abs_change = 0.0;
  double max_abs_change = 0.0;
};

/// Garment vertices strictly inside body B.
struct PenetrationMetrics {
  std::size_t inside = 0;
  std::size_t checked = 0;      // finite vertices tested
  double fraction = 0.0;        // inside / checked
  double deepest = 0.0;         // distance to the surface of the deepest inside vertex
  long deepest_vertex = -1;     // its index, -1 when none
  std::size_t face_centres_inside = 0;  // faces whose centre is inside (the body poking through; compute_metrics only)
};

/// Surface sanity of the result against the original.
struct SanityMetrics {
  std::size_t nan_vertices = 0;   // rows with a NaN or infinite coordinate
  std::size_t faces_checked = 0;  // faces with a non-zero normal before and after
  std::size_t flipped_faces = 0;  // of those, normal turned by more than 90 degrees
  std::size_t edges = 0;          // distinct face and line edges with non-zero original length
  double edge_ratio_p1 = 0.0, edge_ratio_p50 = 0.0, edge_ratio_p99 = 0.0;  // result / original length
};

/// One feature curve in three states, row i of each the same material point.
/// `warped` may be empty (then the warp-alone numbers are absent).
struct FeatureCurveInput {
  std::string name;
  bool closed = false;
  Points original, warped, result;
};

struct CurveScores {
  double shape_error = 0.0;        // RMS after similarity alignment / length (features module)
  double turning_change_deg = 0.0; // mean |turning-angle change|, degrees (features module)
  double straightness = 0.0;       // max deviation after similarity alignment / length
};

struct FeatureCurveMetrics {
  std::string name;
  bool has_warp = false;
  CurveScores warp, result;
};

struct ResizeMetrics {
  FitMetrics fit;
  PenetrationMetrics penetration;
  SanityMetrics sanity;
  std::vector<FeatureCurveMetrics> features;
  std::size_t vertices = 0;

  /// {"vertices", "fit": {...}, "penetration": {...}, "sanity": {...}, "features": [...]}
  nlohmann::json to_json() const;
};

struct MetricsOptions {
  double fit_band = 1.0;  // garment units (1 cm)
  std::vector<FeatureCurveInput> features;
};

/// Every metric of a result. `result` has the original's vertex order. Throws
/// refit::Error when the vertex counts differ or a feature curve's states differ
/// in row count. Parallel; bit-identical for any thread count.
ResizeMetrics compute_metrics(const Garment& original, const Points& result, const BodySurface& a,
                              const BodySurface& b, const MetricsOptions& options = {});
/// Same, building the body surfaces (Embree) from the meshes.
ResizeMetrics compute_metrics(const Garment& original, const Points& result, const BodyMesh& a, const BodyMesh& b,
                              const MetricsOptions& options = {});

/// Fit change of the vertices within options.band of body A (see FitMetrics).
FitMetrics measure_fit(const Points& original, const Points& result, const BodySurface& a, const BodySurface& b,
                       double band);
/// Vertices of `positions` strictly inside `body` (non-finite rows skipped).
PenetrationMetrics measure_penetration(const Points& positions, const BodySurface& body);
/// NaN rows, flipped faces and edge-length ratio percentiles (see SanityMetrics).
SanityMetrics measure_sanity(const Garment& original, const Points& result);

/// Maximum distance between `curve` and `original` (row i to row i) after the
/// best similarity alignment of the original onto the curve (Eigen::umeyama),
/// divided by the original's length (closed: with the closing edge). 0 for a
/// similar copy; a profile that bulges or kinks scores its deviation. Throws
/// refit::Error when row counts differ, there are fewer than 2 rows, or the
/// original has zero length.
double profile_straightness(const Points& curve, const Points& original, bool closed);

/// Scores of one curve against its original (shape error, turning angle,
/// straightness). Throws as profile_straightness.
CurveScores score_curve(const Points& curve, const Points& original, bool closed);

/// Feature curves of `specs` on the original (features module), the warp alone
/// of their samples from body a to body b (step 1), and the same material
/// points on `result`: the input of the feature metrics. Throws as
/// build_feature_curves.
std::vector<FeatureCurveInput> feature_curve_inputs(const Garment& original, const Points& result, const BodyMesh& a,
                                                    const BodyMesh& b, const std::vector<FeatureSpec>& specs);

/// Faces (3 corners or more) whose centre (corner mean) is inside `body`. Parallel.
std::size_t count_face_centres_inside(const Garment& g, const Points& positions, const BodySurface& body);

}  // namespace refit
