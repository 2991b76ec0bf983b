#pragma once
// From feature specifications to sampled feature curves on the ORIGINAL garment (paper section 4.2, Fig. 3(d)),
// with the auxiliary points of section 4.3. Lengths in the garment's units; plain functions of their arguments.
#include <refit/core/garment.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/features/plane.hpp>
#include <refit/features/slice.hpp>

#include <cstdint>
#include <functional>
#include <utility>
#include <span>
#include <string>
#include <vector>

namespace refit {

/// A feature curve ready for binding: samples r_1..r_m on the original garment,
/// its feature plane, and auxiliary points scattered near the samples on that
/// plane (used only to estimate the new plane robustly, section 4.3).
struct FeatureCurve {
  std::string name;
  bool closed = false;
  Points samples;  // m x 3
  FeaturePlane plane;
  Points aux;      // (m * aux_per_sample) x 3, on `plane`
  /// m x 3: each sample's nearest point on the cut piece it was fitted to (so on
  /// the faces of its own layer: the fit leaves samples up to about 0.05 cm off),
  /// or empty: the samples themselves lie on the garment (or need not).
  Points on_piece;

  std::size_t size() const { return static_cast<std::size_t>(samples.rows()); }
  /// Mean distance between consecutive samples.
  double spacing() const;
};

/// Every curve's samples, one curve after another: the order in which a
/// binding numbers the samples of all curves.
Points all_samples(std::span<const FeatureCurve> curves);
/// The same rows as all_samples, each where its sample sits on the garment
/// (FeatureCurve::on_piece where known): the points to attach, so that a curve
/// is attached to the layer it was cut from, not to one just beneath it.
Points all_sample_anchors(std::span<const FeatureCurve> curves);

struct FeatureCurveOptions {
  std::size_t aux_per_sample = 4;
  double aux_radius = 3.0;     // auxiliary points lie within this many sample spacings of their sample
  double near_fraction = 0.1;  // `near`, `from`, `to` farther than this fraction of the garment's bbox diagonal are refused
  std::uint64_t seed = 0x5eedf00dULL;  // fixed: the same file always gives the same auxiliary points
};

/// Auxiliary points for samples on `plane`: aux_per_sample per sample, at a
/// deterministic pseudo-random (std::mt19937_64, fixed seed) in-plane offset of
/// at most aux_radius * spacing from the sample's projection on the plane.
Points auxiliary_points(const Points& samples, bool closed, const FeaturePlane& plane,
                        const FeatureCurveOptions& options = {}, std::uint64_t stream = 0);

/// A FeatureCurve from given samples (tests, programmatic use): fills `aux`.
/// Throws refit::Error when there are fewer samples than min_samples(closed).
FeatureCurve make_feature_curve(std::string name, Points samples, bool closed, const FeaturePlane& plane,
                                const FeatureCurveOptions& options = {}, std::uint64_t stream = 0);

/// Turns specs into sampled curves on the original garment g (same units as the
/// specs). bspline: control points projected onto the plane, sampled by arc
/// length. slice: the cut piece nearest `near` (clipped between the points
/// nearest `from` and `to`; a closed piece keeps the shorter arc), fitted with a
/// least-squares cubic B-spline. boundary: the boundary loop nearest `near` of
/// the faces after welding coincident vertices (so soups and split seams give
/// the whole loop), resampled by arc length, starting nearest `near`; plane
/// = the given one or the loop's PCA plane. Throws refit::Error "FILE: feature
/// 'NAME': problem" when a plane misses the garment, `near`/`from`/`to` is far
/// from every candidate, the garment has no boundary, or an open slice gets
/// fewer than 5 samples.
std::vector<FeatureCurve> build_feature_curves(const Garment& g, const std::vector<FeatureSpec>& specs,
                                               const FeatureCurveOptions& options = {});

/// What build_feature_curves reads of a garment, so that a garment not in
/// memory (the chunked mode, issue 14) gives the same curves.
struct FeatureGarment {
  Vec3 low = Vec3::Zero(), high = Vec3::Zero();  // the positions' bounding box
  /// The lowest and highest signed distance of a vertex to a plane.
  std::function<std::pair<double, double>(const FeaturePlane&)> plane_range;
  /// slice_garment(garment, plane, weld_tolerance).
  std::function<SliceResult(const FeaturePlane&, double)> slice;
  /// boundary_loops(weld_garment(garment, weld_tolerance)), each loop's positions.
  std::function<std::vector<Points>(double)> boundary_loops;
};
std::vector<FeatureCurve> build_feature_curves(const FeatureGarment& g, const std::vector<FeatureSpec>& specs,
                                               const FeatureCurveOptions& options = {});

/// `g` with coincident vertices (closer than `tolerance`, <= 0: 1e-6 of the bbox
/// diagonal) merged: faces re-indexed, repeated corners removed, faces left with
/// fewer than 3 corners dropped. Lines and points are dropped.
Garment weld_garment(const Garment& g, double tolerance = 0.0);

}  // namespace refit
