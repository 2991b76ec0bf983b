#pragma once
// Step 2: shape matching on feature curves (paper section 4.3, eqs. 5-9, read
// with DESIGN.md). Per curve:
//  - the new feature plane is the PCA plane of the warped samples and warped
//    auxiliary points (its normal's sign and in-plane axes follow the best
//    rotation from the original to the warped points, so the curve is never
//    mirrored);
//  - E = w_r E_r + w_d E_d (eqs. 7-9) with (alpha, beta) of eqs. 5-6 stored in
//    the un-normalised frame (e = r_{i+2} - r_{i+1} and R e), so a rotation plus
//    uniform scaling of the curve costs nothing; the energy is quadratic and is
//    minimised as a sparse linear least-squares problem.
// Two ways to handle several curves (ShapeMatchingOptions::joint):
//  - joint (default, beyond the paper; joint_matching.cpp): ALL curves in one
//    least-squares problem over their 3D samples. A sample where a curve meets
//    an earlier one (a profile ending on the hem, crossed curves as in Fig. 5)
//    is not an unknown of its own: it is the point of the earlier curve's
//    polyline it lies on in the original (plus its original small offset from
//    it, turned and scaled with that curve), so meeting curves meet by
//    construction and both keep their shape. Each curve stays in its new plane
//    (which may move along its normal), its scale and in-plane rotation follow
//    the similarity that best carries the original samples onto the warped ones
//    (a weak term: the curve can give where the curves it meets need it, but no
//    curve floats its own scale), and one sample, the closest to body B, is held
//    where the warp put it. Samples the solve leaves inside body B or closer
//    than the clearance are held at the clearance along the body's normal and
//    the problem is solved again (clearance rounds);
//  - in order (the paper; match_shapes_in_order below): one curve at a time in
//    file order; two samples are fixed by the paper's heuristic (the two closest
//    to body B, the two closest to curves already processed: the two smallest
//    distances win), and every sample where the curve crosses an earlier curve
//    is fixed where the earlier curve's optimised polyline put the crossing (the
//    new plane is moved along its normal to pass through those points); each
//    curve is solved in 2D in its plane.
// Closed curves wrap their indices; open curves drop the end terms. Lengths in garment units; body callbacks run in parallel.
#include <refit/body/centre_tree.hpp>
#include <refit/features/bspline.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/warp/warp.hpp>

#include <functional>
#include <string>
#include <span>
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
  /// All curves in one solve, meeting curves sharing their meeting samples (see
  /// above). False: the paper's order-based rule (`--method paper`).
  bool joint = true;
  /// Joint solve: weight of the term that ties each curve's scale and in-plane
  /// rotation to the similarity fitted from its original to its warped samples
  /// (dimensionless, like w_r and w_d: see joint_matching.cpp).
  double scale_weight = 0.01;
  /// Joint solve: weight of the term that keeps each curve in its new plane.
  double plane_weight = 1e3;
  /// Joint solve: samples end at least this far outside body B (garment units; 0:
  /// no clearance rounds). The pipeline passes the collision clearance plus a
  /// margin, so the collision step finds nothing to move on the curves.
  double clearance = 0.0;
  int clearance_rounds = 6;
  /// Joint solve with a clearance: samples the warp leaves within this distance
  /// of body B (garment units; 0: off) that the solve moves more than
  /// follow_tolerance farther off are pulled back to that band (see
  /// joint_matching.cpp). The pipeline passes 1 cm: where the garment sat on
  /// body A it follows body B.
  double follow_body = 0.0;
  double follow_tolerance = 0.0;  // garment units
  /// Joint solve with a clearance: before a curve is bent clear of body B, it is
  /// turned and scaled in its plane about the point where it meets an earlier
  /// curve (or moved, turned and scaled in its plane when it meets none) to clear
  /// the body as a whole. Kept when that takes at least half of the bend away and
  /// no sample the warp left within placement_near of body B ends more than
  /// placement_band farther off than the warp put it (garment units; < 0: off).
  /// The pipeline passes the surface's near-body band (0.3 cm) and 1 cm.
  double placement_band = -1.0;
  double placement_near = 0.0;
  /// Joint solve: a curve whose plane lies within this many degrees of level on
  /// body A (its normal along body A's long axis: a hem, a waistline) keeps its
  /// plane level on body B instead of taking the warp's tilt; 0: off.
  double level_tolerance_deg = 2.0;
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
  /// Per curve: its plane is level against body A's long axis (see
  /// ShapeMatchingOptions::level_tolerance_deg; bind_features sets it; empty: none).
  std::vector<std::uint8_t> level;
};

/// The unit direction of a body's greatest extent (the principal axis of its
/// vertices with the largest variance; its sign: towards the larger coordinate).
Vec3 long_axis(const Points& body_vertices);
/// Per curve: whether its plane's normal lies within `tolerance_deg` of `axis`.
std::vector<std::uint8_t> level_curves(const std::vector<FeatureCurve>& curves, const Vec3& axis, double tolerance_deg);

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
  double scale_warped = 1.0, scale_result = 1.0;  // scale of the best similarity original -> warped, -> optimised
  bool closed = false;
  Points original, warped, optimised;  // m x 3 each
  FeaturePlane plane;                  // the new feature plane
  std::vector<FixedSample> fixed;      // in order: the two samples chosen by the heuristic; joint: the one held
  std::vector<FixedSample> crossings;  // samples on an earlier curve (in order: fixed where it put them; joint: shared)
  std::vector<FixedSample> cleared;    // joint: samples held at the clearance from body B (distance: how far they moved)
  std::vector<FixedSample> followed;   // joint: samples pulled back towards body B (distance: how far they moved)
  double placed = 0.0;                 // joint: how far the placement before the clearance bend moved a sample (largest)
  bool level = false;                  // joint: its plane kept level (ShapeModel::level)
  double energy_warped = 0.0, energy_result = 0.0;  // eq. 9 (weights as applied) at the projected warped samples and at the result
  double shape_error_warped = 0.0, shape_error_result = 0.0;  // see curve_metrics.hpp
  double turning_angle_change_warped_deg = 0.0, turning_angle_change_result_deg = 0.0;
};

/// Fills r's shape errors, turning-angle changes and similarity scales, warped
/// and optimised against the original (curve_metrics.hpp).
void measure_curve_result(CurveResult& r, bool closed);

struct FeatureResult {
  std::vector<CurveResult> curves;
};

/// Distance from a point to body B; called in parallel, so it must be thread-safe.
using DistanceToBody = std::function<double(const Vec3&)>;

/// What a point needs to clear body B by a clearance: the unit direction away
/// from the body and how far it must still move along it (< 0: clear, by how
/// much it is farther off than the clearance).
struct ClearanceNeed {
  Vec3 direction = Vec3::Zero();
  double amount = 0.0;
};
/// ClearanceNeed of a point for a given clearance; thread-safe.
using ClearanceToBody = std::function<ClearanceNeed(const Vec3&, double clearance)>;

/// Optimises every curve of `model` (eqs. 5-9), jointly or in order as the
/// model's options say, given the warped samples and warped auxiliary points of
/// each curve (rows matching the model's). `clearance_to_body_b` (joint solve,
/// with options.clearance > 0) keeps the samples clear of body B, each by the
/// clearance plus its `extra_clearance` (per sample of all curves in order;
/// empty: none). Throws refit::Error when the counts do not match or a warped
/// point is not finite.
FeatureResult match_shapes(const ShapeModel& model, const std::vector<Points>& warped_samples,
                           const std::vector<Points>& warped_aux, const DistanceToBody& distance_to_body_b,
                           const ClearanceToBody& clearance_to_body_b = {},
                           std::span<const double> extra_clearance = {});

/// The paper's rule: one curve after the other, in the model's order.
FeatureResult match_shapes_in_order(const ShapeModel& model, const std::vector<Points>& warped_samples,
                                    const std::vector<Points>& warped_aux, const DistanceToBody& distance_to_body_b);

/// All curves in one solve (joint_matching.cpp).
FeatureResult match_shapes_jointly(const ShapeModel& model, const std::vector<Points>& warped_samples,
                                   const std::vector<Points>& warped_aux, const DistanceToBody& distance_to_body_b,
                                   const ClearanceToBody& clearance_to_body_b,
                                   std::span<const double> extra_clearance = {});

/// Puts every crossing sample of `result` back on the curve it meets, where
/// the joint solve defines it (after a change of the optimised samples, such as
/// symmetrisation, that moved the two curves differently). Joint models only.
void restore_meetings(const ShapeModel& model, FeatureResult& result);

/// The new feature plane of a curve: PCA of the warped samples and warped
/// auxiliary points; its normal's sign and in-plane axes follow the best
/// rotation original -> warped (Kabsch), so the 2D frame keeps its handedness
/// and the curve is not mirrored.
FeaturePlane warped_feature_plane(const FeatureCurve& c, const Points& warped_samples, const Points& warped_aux);

/// Eq. 9 (weights as applied) at 2D coordinates x, with closeness to xw.
double shape_energy(const CurveShape& s, const Eigen::Matrix<double, Eigen::Dynamic, 2>& x,
                    const Eigen::Matrix<double, Eigen::Dynamic, 2>& xw, const ShapeMatchingOptions& o);

/// Nearest point of a polyline to q, given a k-d tree over its vertices: the
/// edges around the nearest vertex (exact for densely sampled curves).
PolylinePoint nearest_near_vertex(const PointTree& tree, const Points& poly, bool closed, const Vec3& q);

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
                                const DistanceToBody& distance_to_body_b, const ClearanceToBody& clearance_to_body_b = {},
                                std::span<const double> extra_clearance = {});
/// The same with the change to body B made once for the garment's warp too (triangle_change).
FeatureResult optimise_features(const FeatureBinding& binding, const TriangleChange& change_b,
                                const DistanceToBody& distance_to_body_b, const ClearanceToBody& clearance_to_body_b = {},
                                std::span<const double> extra_clearance = {});

}  // namespace refit
