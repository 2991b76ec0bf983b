#pragma once
// Left/right symmetry of a garment and body A about a plane x = c (issue 13,
// item 2). When the pair is mirror-symmetric, every feature curve acts on its
// mirror image too: a curve whose mirror is not already a feature (the left
// profile, but not a front profile lying on the plane) gets a mirrored copy, so
// the feature and surface steps treat both sides alike. Lengths in the garment's units; plain functions.
#include <refit/features/feature_curves.hpp>
#include <refit/features/shape_matching.hpp>

#include <functional>
#include <string>
#include <vector>

namespace refit {

enum class SymmetryMode { Auto, X, None };

/// Parses "auto", "x" or "none"; throws refit::Error otherwise.
SymmetryMode parse_symmetry(const std::string& s);

struct SymmetryCheck {
  double plane_x = 0.0;        // the mirror plane x = plane_x
  double garment_error = 0.0;  // 90th percentile distance from a mirrored garment vertex to the garment's surface
  double body_error = 0.0;     // 90th percentile distance from a mirrored body A vertex to the nearest body A vertex
  double tolerance = 0.0;      // both errors must be at most this for Auto to detect symmetry
  bool symmetric = false;      // used: forced by X, detected by Auto, never with None
};

/// The mirror plane's x: the middle of body A's bounding box in x.
double mirror_plane_x(const Points& body_a);

/// The pair's mirror error about x = plane_x. garment_mirror_distance: per garment
/// vertex, the distance from its mirror image to the garment's surface (garment
/// meshes need not be vertex-symmetric). tolerance: in the garment's units.
SymmetryCheck check_symmetry(double plane_x, const std::vector<double>& garment_mirror_distance, const Points& body_a,
                             double tolerance, SymmetryMode mode);
/// The same with the garment's error (the 90th percentile of those distances) given.
SymmetryCheck check_symmetry(double plane_x, double garment_error, const Points& body_a, double tolerance, SymmetryMode mode);
/// The rank (0-based, ascending) of the 90th percentile among `count` values:
/// the symmetry check's (robust to one-sided details up to a tenth of the garment).
std::size_t symmetry_percentile_rank(std::size_t count);

/// p mirrored about x = c.
Points mirror_x(const Points& p, double c);

/// How much of its way to the mean with its mirror image a vertex goes when the
/// garment is symmetrised, by the distance of that image to the garment's
/// surface: all of it within `tolerance`, none beyond twice that, eased
/// (smoothstep) between. All or nothing, the line where a garment's own
/// asymmetry crossed the tolerance was a crease (the dense 1M dress's top, whose
/// front stands up to 1.2 cm farther out on one side).
double symmetrised_share(double image_distance, double tolerance);

/// `curves` plus, for each curve whose mirror about x = c is not within
/// `coincide` spacings of an existing curve (itself included), its mirrored
/// copy named "<name>~mirror" (appended after all given curves, in their order).
std::vector<FeatureCurve> add_mirrored_curves(std::vector<FeatureCurve> curves, double c, double coincide = 2.0);

/// Per point, its distance to the original garment's surface.
using DistanceToGarment = std::function<std::vector<double>(const Points&)>;
/// Removes the curves from `first` on (the mirrored copies) whose samples are
/// not on the garment: the 90th percentile of their distances above
/// `tolerance` (a curve on a one-sided part, such as a jacket's overlapping
/// front). Returns their names, in order.
std::vector<std::string> drop_curves_off_garment(std::vector<FeatureCurve>& curves, std::size_t first, double tolerance,
                                                 const DistanceToGarment& distance);

/// For each sample of the concatenated curves `samples` (original garment), the
/// sample nearest its mirror about x = c, or -1 when none is within `tolerance`.
inline constexpr Index kNoMirror = static_cast<Index>(-1);
std::vector<Index> mirror_pairs(const Points& samples, double c, double tolerance);
/// mirror_pairs of all_samples(curves) within half the finest curve's spacing:
/// pairs only where the mirror image is a sample (a mirrored copy, a hem, a
/// profile on the plane).
std::vector<Index> sample_mirror_pairs(const std::vector<FeatureCurve>& curves, double c);

/// Makes `points` (rows matching mirror_pairs' samples) mirror-symmetric: each
/// paired row becomes the mean of itself and its partner's mirror image.
void symmetrise(Points& points, const std::vector<Index>& pairs, double c);

/// Largest distance between a row of `points` and the mirror image about x = c
/// of its partner (rows without one are skipped): 0 for a symmetric set.
double paired_mirror_error(const Points& points, const std::vector<Index>& pairs, double c);

/// Per curve of `result`, the largest distance from its samples carried on a
/// garment (`carried`: every curve's samples, concatenated in order) to its optimised curve.
std::vector<double> carried_curve_gaps(const FeatureResult& result, const Points& carried);
/// Whether the farthest of gaps `after` (carried_curve_gaps) is farther off than the farthest of `before`.
bool farther_off(const std::vector<double>& before, const std::vector<double>& after);
/// Whether gaps `after` (carried_curve_gaps) are better than `before`: no curve
/// farther off (beyond a thousandth: rounding), and the farthest closer (the
/// snap after the symmetrisation is kept only then). `slack`: what a curve
/// may come out farther off beyond that (garment units).
bool closer_to_curves(const std::vector<double>& before, const std::vector<double>& after, double slack = 0.0);

/// symmetrise() on the optimised samples of every curve (concatenated in order,
/// as mirror_pairs' samples), then their shape figures measured again.
void symmetrise_curves(FeatureResult& result, const std::vector<Index>& pairs, double c);

}  // namespace refit
