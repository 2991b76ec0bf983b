#pragma once
// Step 2: shape matching on feature curves (paper section 4.3, eqs. 5-9, read
// with DESIGN.md). Per curve, in file order:
//  - the new feature plane is the PCA plane of the warped samples and warped
//    auxiliary points (its normal's sign and in-plane axes follow the best
//    rotation from the original to the warped points, so the curve is never
//    mirrored);
//  - the warped samples are projected into it (r'_i, 2D);
//  - E = w_r E_r + w_d E_d (eqs. 7-9) with (alpha, beta) of eqs. 5-6 stored in
//    the un-normalised frame (e = r_{i+2} - r_{i+1} and R e), so a rotation plus
//    uniform scaling of the curve costs nothing, is minimised as ONE sparse
//    linear least-squares problem in the 2m plane coordinates;
//  - two samples are fixed by the paper's heuristic (the two closest to body B,
//    the two closest to curves already processed: the two smallest distances
//    win), and every sample where the curve crosses an earlier curve is fixed
//    where the earlier curve's optimised polyline put the crossing (the new
//    plane is moved along its normal to pass through those points);
//  - closed curves wrap their indices; open curves drop the end terms.
#include <refit/features/feature_curves.hpp>
#include <refit/warp/warp.hpp>

#include <functional>
#include <string>
#include <vector>

namespace refit {

struct ShapeMatchingOptions {
  double shape_weight = 1.0;       // w_r (eq. 9)
  double closeness_weight = 0.1;   // w_d (eq. 9)
  /// The paper's sums E_r and E_d do not scale alike with the sample count m: a
  /// smooth distortion of the whole curve changes each local-frame prediction
  /// by O(1/m^2) of the distortion, so E_r ~ 1/m^3 while E_d ~ m, and with the
  /// raw sums w_d = 0.1 keeps nearly all of the warp's distortion for m in the
  /// tens or more (Fig. 6 could not be reproduced). When true (default), both
  /// terms are taken as discretisations of integrals made dimensionless with the
  /// curve length (E_r of the curvature change, E_d of the displacement), which
  /// amounts to using w_d / m^4 on the raw sums: the weights then mean the same
  /// for any sampling. False: the raw sums of eqs. 7-8.
  bool sampling_invariant = true;
  /// The two fixed samples should pin the curve, not a single edge of it: the
  /// second sample of each candidate pair (and the second fixed sample) is the
  /// closest one at least this fraction of the samples away from the first, when
  /// there is one. The paper takes the two closest (set 0 for that).
  double min_fixed_separation = 0.25;
  double crossing_tolerance = 1.0; // a later sample within this many sample spacings (the larger of the
                                   // two curves') of an earlier curve, in the original, is a crossing
};

/// The weight actually applied to the raw sum of eq. 8 for a curve of m samples
/// (closeness_weight, divided by m^4 when sampling_invariant).
double closeness_weight(const ShapeMatchingOptions& options, std::size_t m);

/// Coefficients of eqs. 5-6 for every sample, from the original samples in the
/// original plane: prediction from the frame at i+1 ("plus") and at i-1 ("minus").
/// Terms that do not exist (ends of open curves, zero-length frame edges) have valid = 0.
struct CurveShape {
  std::vector<double> alpha_plus, beta_plus, alpha_minus, beta_minus;
  std::vector<std::uint8_t> valid_plus, valid_minus;
};

/// A sample of a later curve that lies on an earlier curve (in the original).
struct Crossing {
  Index sample = 0;            // index in the later curve
  std::size_t earlier = 0;     // index of the earlier curve
  std::size_t segment = 0;     // edge of the earlier curve's polyline
  double t = 0.0;              // position on that edge
  double distance = 0.0;       // original distance of the sample to the earlier curve
};

/// Everything about the curves that does not depend on body B.
struct ShapeModel {
  std::vector<FeatureCurve> curves;
  std::vector<CurveShape> shapes;
  std::vector<std::vector<Crossing>> crossings;  // per curve, with earlier curves only
  ShapeMatchingOptions options;
};

/// Coefficients of eqs. 5-6 on the original curve (2D coordinates in c.plane).
CurveShape shape_coefficients(const FeatureCurve& c);

/// Coefficients and crossings for curves processed in the given order. Throws
/// refit::Error when a curve has fewer than min_samples(closed) samples.
ShapeModel prepare_shape_model(std::vector<FeatureCurve> curves, const ShapeMatchingOptions& options = {});

struct FixedSample {
  Index index = 0;
  std::string reason;     // "body": among the two closest to body B; "crossing": among the two closest to curves
                          // already processed, or on an earlier curve
  double distance = 0.0;  // to body B, or to the processed curves
};

struct CurveResult {
  std::string name;
  bool closed = false;
  Points original, warped, optimised;  // m x 3 each
  FeaturePlane plane;                  // the new feature plane
  std::vector<FixedSample> fixed;      // the two samples chosen by the heuristic
  std::vector<FixedSample> crossings;  // samples fixed where an earlier curve put the crossing
  double energy_warped = 0.0, energy_result = 0.0;  // eq. 9 (weights as applied) at the projected warped samples and at the result
  double shape_error_warped = 0.0, shape_error_result = 0.0;  // see curve_metrics.hpp
  double turning_angle_change_warped_deg = 0.0, turning_angle_change_result_deg = 0.0;
};

struct FeatureResult {
  std::vector<CurveResult> curves;
};

/// Distance from a point to body B; called in parallel, so it must be thread-safe.
using DistanceToBody = std::function<double(const Vec3&)>;

/// Optimises every curve of `model` in order (eqs. 5-9), given the warped
/// samples and warped auxiliary points of each curve (rows matching the
/// model's). Throws refit::Error when the counts do not match or a warped point
/// is not finite.
FeatureResult match_shapes(const ShapeModel& model, const std::vector<Points>& warped_samples,
                           const std::vector<Points>& warped_aux, const DistanceToBody& distance_to_body_b);

/// Bind once: the shape model plus the warp bindings of samples and auxiliary points on body A.
struct FeatureBinding {
  ShapeModel model;
  std::vector<WarpBinding> samples, aux;
};

/// Binds curves (on the original garment around body A) for repeated use.
FeatureBinding bind_features(const ReferenceBody& a, std::vector<FeatureCurve> curves,
                             const ShapeMatchingOptions& options = {});

/// Apply many: warps samples and auxiliary points with body B's frames and
/// optimises every curve (match_shapes).
FeatureResult optimise_features(const FeatureBinding& binding, const TriangleFrames& b_frames,
                                const DistanceToBody& distance_to_body_b);

}  // namespace refit
