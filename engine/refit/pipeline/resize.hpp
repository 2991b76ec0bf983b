#pragma once
// The resize pipeline: the paper's three steps, read top to bottom in
// GarmentBinding::resize: the warp (section 3, eqs. 1-4), the feature curves
// (section 4, eqs. 5-9), the surface (section 5, eqs. 10-15), then the collision
// step and the report (beyond the paper). Bind once (garment + body A +
// features), apply to any number of bodies B.
// Units: positions in the garment's units (ResizeOptions::units); the physical
// constants of ResizeOptions are in cm and converted. Threads: the binding is
// read-only after construction and resize() is const; each step runs in
// parallel inside (core/parallel.hpp), with bit-identical results for any
// thread count. Bad input: refit::Error, its message naming the file.
#include <refit/body/body_mesh.hpp>
#include <refit/collision/layer_order.hpp>
#include <refit/core/garment.hpp>
#include <refit/core/progress.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/features/shape_matching.hpp>
#include <refit/features/symmetry.hpp>
#include <refit/metrics/metrics.hpp>
#include <refit/pipeline/garment_mirror.hpp>
#include <refit/surface/folds.hpp>
#include <refit/surface/surface.hpp>
#include <refit/warp/warp.hpp>

#include <nlohmann/json.hpp>

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace refit {

class BodySurface;
struct BodyTopology;

/// How far a resize goes: the warp alone (step 1), warp + feature curves (steps
/// 1-2: the garment is the warp, the curves are optimised), or all three steps.
enum class Stage { Warp, Features, Full };

/// The band beyond the warp's distance to body B that a sample following the
/// body (ResizeOptions::follow_body_cm) may keep.
inline constexpr double kFeatureFollowToleranceCm = 0.3;

struct ResizeOptions {
  std::string units = "cm";    // garment units; physical constants below are in cm
  Stage stage = Stage::Full;
  WarpOptions warp;
  ShapeMatchingOptions shape_matching;
  SymmetryMode symmetry = SymmetryMode::Auto;  // mirror one-sided features about x = c (docs/features.md)
  double symmetry_tolerance_cm = 1.0;          // Auto: largest mirror error (95th percentile) of garment and body A
  SurfaceOptions surface;      // epsilon and voxel in cm here; converted to garment units
  bool collision = true;       // push vertices inside body B out (beyond the paper)
  bool smooth_folds = true;    // the collision step first smooths out the faces the warp folded over (surface/folds.hpp)
  double clearance_cm = 0.2;   // ... to this distance outside the body
  /// With the collision step: feature samples the warp leaves within this of
  /// body B keep the warp's distance to it, to kFeatureFollowToleranceCm
  /// (ShapeMatchingOptions::follow_body): where a curve sat on body A it follows
  /// body B. 0 (default): the curves keep their shape there too (docs/method.md
  /// has the quality suite's figures of both).
  double follow_body_cm = 0.0;
  /// With the collision step: when it pushes a curve's faces farther than
  /// kFollowedCurveGapCm off the curve, the shape steps run again with the
  /// curve kept as far off body B as the push left it (docs/method.md).
  bool lift_pushed_curves = true;
  bool metrics = false;        // add fit, penetration and sanity metrics (warp and result) to the report
  double memory_budget_mb = 0; // a run estimated above this is refused before the work (0: the machine's memory)
};

struct ResizeResult {
  Points positions;                 // every garment vertex, in file order
  Points warped;                    // the warp alone (step 1), for comparison
  FeatureResult features;           // per feature curve: original, warped, optimised samples
  nlohmann::json report;            // stage timings (ms), counts, per-stage details
  std::vector<std::string> warnings;
};

/// What depends only on the garment, its features and body A, computed once;
/// `resize` does only what body B changes.
class GarmentBinding {
 public:
  /// Throws refit::Error for an empty garment, a bad body A, or features that
  /// miss the garment.
  GarmentBinding(std::shared_ptr<const Garment> garment, BodyMesh body_a, ResizeOptions options = {},
                 std::vector<FeatureSpec> features = {}, const Progress& progress = Progress(true));
  ~GarmentBinding();

  /// Resizes the garment to body B (same connectivity as A, else refit::Error).
  ResizeResult resize(const BodyMesh& body_b, const Progress& progress = Progress(true)) const;

  const Garment& garment() const { return *garment_; }
  const ReferenceBody& body_a() const { return body_a_; }
  const ResizeOptions& options() const { return options_; }
  /// Bind timings (ms): warp, features, surface.
  const nlohmann::json& bind_report() const { return bind_report_; }

 private:
  void check_memory_estimate();
  // The steps of resize(), in the paper's order; each adds its part of the
  // report, its time and its warnings to `result`.
  /// Returns the change to body B (its frames `frames_b`), made once for every point set warped to it.
  TriangleChange warp_step(const BodyMesh& body_b, const TriangleFrames& frames_b, ResizeResult& result,
                           const Progress& progress) const;
  bool body_b_symmetric(const BodyMesh& body_b, nlohmann::json& report) const;
  /// `lift`: per feature sample (or empty), a clearance it keeps at least beyond the option's.
  void feature_step(const TriangleChange& change_b, const BodySurface& surface_b, bool symmetric_b,
                    const std::vector<double>& lift, ResizeResult& result, const Progress& progress) const;
  /// Steps 2 to 4 on `result` (warped): features, surface, collision. Returns
  /// the feature samples carried where the surface step leaves them.
  Points shape_steps(const TriangleChange& change_b, const BodySurface& surface_b, bool symmetric_b,
                     const std::vector<double>& lift, ResizeResult& result, const Progress& progress) const;
  /// Per feature sample: the clearance from body B that keeps it where the
  /// collision step pushed it (carried from `before` to `after`), for the
  /// samples whose curve the step took farther off; empty when none.
  std::vector<double> lifts_from_pushes(const BodySurface& surface_b, const FeatureResult& curves,
                                        const Points& before, const Points& after) const;
  /// Per feature sample (all curves in order, at `samples` on the original), the
  /// clearance it keeps beyond the option's where a face under it dips towards body A.
  std::vector<double> dipping_face_clearance(const BodySurface& surface_a, const Points& samples) const;
  Points surface_step(const BodySurface& surface_b, bool symmetric_b, ResizeResult& result,
                      const Progress& progress) const;  // returns the features where the surface step leaves them
  void collision_step(const BodySurface& surface_b, bool symmetric_b, ResizeResult& result,
                      const Progress& progress) const;
  void metrics_step(const BodySurface& surface_b, ResizeResult& result, const Progress& progress) const;
  const Csr& vertex_adjacency_once() const;
  const FoldBinding& folds_once() const;

  std::shared_ptr<const Garment> garment_;
  ResizeOptions options_;
  nlohmann::json symmetry_report_;
  GarmentMirror mirror_;               // inactive unless the garment and body A are mirror-symmetric
  std::vector<Index> feature_mirror_;  // per feature sample (all curves, in order): its mirror partner, or kNoMirror
  ReferenceBody body_a_;
  std::shared_ptr<const BodyTopology> body_topology_;  // body A's triangles: every body B's surface shares them
  WarpBinding warp_;
  std::optional<FeatureBinding> features_;
  std::optional<SurfaceBinding> surface_;
  SurfaceAttachment feature_attachment_;  // where the feature samples (all curves, in order) sit on the garment
  std::vector<double> dip_clearance_;     // per feature sample: dipping_face_clearance (empty: none)
  std::vector<LayerCover> layer_covers_;  // where a layer lies over another (bind_layer_order; empty: one layer)
  nlohmann::json bind_report_;
  double memory_estimate_mb_ = 0.0;
  // The collision step's vertex adjacency: made by the first resize that needs
  // it (so a single body's peak memory is as before), kept for the next bodies.
  mutable std::once_flag adjacency_once_;
  mutable Csr adjacency_;
  // The same for the fold smoothing's faces of each vertex and faces agreeing on the original.
  mutable std::once_flag folds_once_;
  mutable FoldBinding folds_;
};

/// The surface step's options in garment units: `options.surface` keeps epsilon
/// and voxel in cm, and the agents keep clear of body B by twice the collision clearance.
SurfaceOptions surface_options_in_units(const ResizeOptions& options);

/// The report's fixed part: garment counts.
nlohmann::json garment_summary(const Garment& g);

inline constexpr const char* kVersion = "0.1.0";

/// With the collision step on, the joint feature solve keeps the curves this much
/// farther from body B than the collision clearance (ShapeMatchingOptions::clearance 0).
inline constexpr double kFeatureClearanceMarginCm = 0.05;
/// A feature sample the warp leaves this close to body B sat on body A (the quality suite's near-body distance).
inline constexpr double kFeatureNearBodyCm = 1.0;
/// The most a feature sample stands farther off body B for a face under it that dips (dipping_face_clearance).
inline constexpr double kDippingFaceCapCm = 1.0;
/// The pipeline runs its shape steps again, with the curves lifted where the
/// collision step pushed them, when that step leaves a curve farther off the
/// written garment than kFollowedCurveGapCm and this much farther than the
/// surface step left it (lifts_from_pushes).
inline constexpr double kPushedCurveToleranceCm = 0.01;
/// What a curve may come out farther off where a step that brings the farthest
/// closer is kept (the snap after the symmetrisation): a hundredth of a millimetre.
inline constexpr double kNegligibleGapChangeCm = 0.001;
/// A curve the written garment passes within this of counts as followed (issue 13's feature gap target).
inline constexpr double kFollowedCurveGapCm = 0.05;
/// The collision step's pushes of a symmetric pair are made alike when they differ by more than this.
inline constexpr double kSymmetricPushToleranceCm = 0.02;

}  // namespace refit
