#include <refit/body/body_surface.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/features/curve_metrics.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/collision/collision.hpp>
#include <refit/core/topology.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/metrics/metrics.hpp>
#include <refit/pipeline/resize.hpp>
#include <refit/pipeline/input_checks.hpp>
#include <refit/pipeline/last_folds.hpp>
#include <refit/pipeline/resize_report.hpp>
#include <refit/pipeline/units.hpp>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <optional>

namespace refit {

namespace {

// Layers (collision/layer_order.hpp): another layer's surface within this of a
// vertex and over it is kept over it, by its distance in the input up to the
// gap (about a fabric's thickness).
constexpr double kLayerReachCm = 2.0;
constexpr double kLayerGapCm = 0.03;

// The corners (with a weight) of the faces the feature samples sit on.
std::vector<std::uint8_t> feature_corners(const SurfaceAttachment& attachment, Eigen::Index vertices) {
  std::vector<std::uint8_t> corner(static_cast<std::size_t>(vertices), 0);
  for (std::size_t k = 0; k < attachment.vertex.size(); ++k)
    for (int j = 0; j < 3; ++j)
      if (attachment.weight[k][j] != 0.0) corner[static_cast<std::size_t>(attachment.vertex[k][j])] = 1;
  return corner;
}

// What a feature sample needs to clear body B: the collision step's rule, out
// along the closest-point direction (inside: to the surface and the clearance
// beyond; farther than the clearance: a negative amount, for the follow step).
ClearanceNeed clearance_need(const BodySurface& body, const Vec3& p, double clearance) {
  ClearanceNeed need;
  const bool in = body.inside(p);
  ClosestPoint cp = in ? body.closest(p) : body.closest_within(p, clearance);
  if (!in && !(cp.distance < clearance)) cp = body.closest(p);
  const Vec3 towards = cp.point - p;
  const double len = towards.norm();
  need.direction = len > 1e-12 * (1.0 + p.norm()) ? Vec3((in ? towards : -towards) / len) : cp.normal;
  need.amount = in ? len + clearance : clearance - len;
  return need;
}

}  // namespace

nlohmann::json garment_summary(const Garment& g) {
  return {{"vertices", g.vertex_count()},
          {"faces", g.faces.rows()},
          {"lines", g.lines.rows()},
          {"points", g.points.rows()}};
}

SurfaceOptions surface_options_in_units(const ResizeOptions& options) {
  const double per_cm = units_per_cm(options.units);
  SurfaceOptions so = options.surface;
  so.epsilon *= per_cm;
  so.voxel *= per_cm;
  so.feature_bend_radius *= per_cm;
  so.near_body_band *= per_cm;
  // The solve stops on the size of its update, a length too: in mm it went on
  // 10 times longer than in cm and came out elsewhere (the skirt on F_thinner:
  // 0.5 cm apart).
  so.tolerance *= per_cm;
  so.tolerance_rms *= per_cm;
  so.clearance = 2.0 * options.clearance_cm * per_cm;
  return so;
}

GarmentBinding::~GarmentBinding() = default;

// A curve sample on a face that the input already sinks towards body A, a
// corner closer to it than the collision clearance (the skirt's waistband: a
// corner 0.19 cm inside body A under the front profile's top): the collision
// step pushes that corner out on body B too, and the written garment left the
// curve there (0.27 cm). The sample keeps its clearance plus how far that
// corner lies below it on body A (less the margin the curves already keep, at
// most kDippingFaceCapCm), so the face clears body B where it follows the curve.
std::vector<double> GarmentBinding::dipping_face_clearance(const BodySurface& surface_a, const Points& samples) const {
  const std::size_t n = feature_attachment_.vertex.size();
  std::vector<double> extra(n, 0.0);
  const double per_cm = units_per_cm(options_.units);
  const double clearance = options_.clearance_cm * per_cm, margin = kFeatureClearanceMarginCm * per_cm;
  const double cap = kDippingFaceCapCm * per_cm;
  // Signed by the closest triangle's normal: only points within about a
  // centimetre of body A count here, where that sign is the side they are on
  // (and the inside test's grid, 0.1-0.2 s to build, is not needed).
  const double reach = clearance + cap + margin;
  const auto signed_distance = [&](const Vec3& p) {
    const ClosestPoint cp = surface_a.closest_within(p, reach);
    if (!(cp.distance < reach)) return reach;
    return (p - cp.point).dot(cp.normal) < 0.0 ? -cp.distance : cp.distance;
  };
  parallel_for(0, n, 64, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      double lowest = std::numeric_limits<double>::infinity();
      for (const Index v : feature_attachment_.vertex[i])
        lowest = std::min(lowest, signed_distance(row3(garment_->positions, v)));
      if (!(lowest < clearance)) continue;
      const double below = signed_distance(row3(samples, Index(i))) - lowest;
      extra[i] = std::clamp(below - margin, 0.0, cap);
    }
  });
  return extra;
}

GarmentBinding::GarmentBinding(std::shared_ptr<const Garment> garment, BodyMesh body_a, ResizeOptions options,
                               std::vector<FeatureSpec> features, const Progress& progress)
    : garment_(std::move(garment)),
      options_(std::move(options)),
      body_a_((check_body(body_a), std::move(body_a)), options_.warp) {
  features = features_with_role(features, CurveRole::shape);  // seams only cut patterns (refit/patterns)
  const double per_cm = units_per_cm(options_.units);
  if (garment_->vertex_count() == 0) throw Error("garment: empty garment (no vertices)");
  if (!garment_->positions.allFinite()) throw Error("garment: a vertex position is NaN or infinite");
  check_garment_on_body_a(*garment_, body_a_.mesh(), per_cm);
  check_memory_estimate();

  Stopwatch clock;
  progress.stage("binding " + std::to_string(garment_->vertex_count()) + " garment vertices to " + body_a_.mesh().name);
  warp_ = body_a_.bind(garment_->positions);
  bind_report_["warp"] = clock.ms();

  if (options_.stage == Stage::Warp) return;
  body_topology_ = body_topology(body_a_.mesh());
  clock.reset();
  // Each garment vertex's mirror image, found on the garment's surface (meshes need not be vertex-symmetric).
  const double plane_x = mirror_plane_x(body_a_.mesh().vertices);
  // Body A's surface, made once for the dipping faces and the layers.
  std::optional<BodySurface> body_a_surface;
  const auto surface_a = [&]() -> const BodySurface& {
    if (!body_a_surface) body_a_surface.emplace(body_a_.mesh(), body_topology_);
    return *body_a_surface;
  };
  // The garment's elements in a tree, made once for the mirror images and the feature samples.
  std::optional<GarmentLocator> locator;
  const auto locate = [&]() -> const GarmentLocator& {
    if (!locator) locator.emplace(*garment_);
    return *locator;
  };
  SurfaceAttachment mirror_at;
  std::vector<double> mirror_distance;
  if (options_.symmetry != SymmetryMode::None) {
    mirror_at = locate().attach(mirror_x(garment_->positions, plane_x));
    mirror_distance = offset_lengths(mirror_at);
  }
  const SymmetryCheck sym = check_symmetry(plane_x, mirror_distance, body_a_.mesh().vertices,
                                           options_.symmetry_tolerance_cm * per_cm, options_.symmetry);
  if (sym.symmetric)
    mirror_ = GarmentMirror(sym.plane_x, sym.tolerance, std::move(mirror_at), mirror_distance, body_a_.mesh().vertices);
  symmetry_report_ = symmetry_report(sym);
  bind_report_["symmetry"] = clock.ms();
  if (!features.empty()) {
    clock.reset();
    progress.stage("sampling " + std::to_string(features.size()) + " feature curves");
    std::vector<FeatureCurve> curves = build_feature_curves(*garment_, features);
    const std::size_t given = curves.size();
    if (sym.symmetric) {
      curves = add_mirrored_curves(std::move(curves), sym.plane_x);
      for (const std::string& name : drop_curves_off_garment(curves, given, sym.tolerance, [&](const Points& s) {
             return offset_lengths(locate().attach(s));
           }))
        symmetry_report_["mirrors_off_garment"].push_back(name);
    }
    for (std::size_t i = given; i < curves.size(); ++i) symmetry_report_["mirrored_features"].push_back(curves[i].name);
    ShapeMatchingOptions sm = options_.shape_matching;
    // The curves end clear of body B by the collision clearance and a margin, so
    // the collision step finds nothing to move on them (issue 13: the written garment follows the curves).
    if (options_.collision && sm.clearance <= 0.0) sm.clearance = (options_.clearance_cm + kFeatureClearanceMarginCm) * per_cm;
    // A curve the solve sinks into body B is first placed clear of it as a whole,
    // holding what sat on body A to the surface step's near-body band (none with
    // --near-body-band 0, the paper's eq. 14).
    if (options_.collision && sm.placement_band < 0.0 && options_.surface.near_body_band > 0.0) {
      sm.placement_band = options_.surface.near_body_band * per_cm;
      sm.placement_near = kFeatureNearBodyCm * per_cm;
    }
    // Where a curve sat on body A it follows body B (issue 13: vertices that sat on body A follow body B).
    if (options_.collision && sm.follow_body <= 0.0 && options_.follow_body_cm > 0.0) {
      sm.follow_body = options_.follow_body_cm * per_cm;
      sm.follow_tolerance = kFeatureFollowToleranceCm * per_cm;
    }
    features_ = bind_features(body_a_, std::move(curves), sm);
    if (sym.symmetric) feature_mirror_ = sample_mirror_pairs(features_->model.curves, sym.plane_x);
    bind_report_["features"] = clock.ms();
  }
  if (options_.stage == Stage::Full) {
    clock.reset();
    progress.stage("building the agent system");
    const SurfaceOptions so = surface_options_in_units(options_);
    const Points all = features_ ? all_samples(features_->model.curves) : Points(0, 3);
    // One pass over the garment for every curve's samples; the surface binding
    // and the report's shape_error_output share it. Each sample is attached
    // where it sits on its own layer, keeping its small offset from there.
    if (all.rows() > 0) {
      const Points anchors = all_sample_anchors(features_->model.curves);
      feature_attachment_ = locate().attach(anchors);
      feature_attachment_.offset += all - anchors;
      // With --follow-body the curves follow body B where they sat on body A instead.
      if (options_.collision && !(options_.follow_body_cm > 0.0)) dip_clearance_ = dipping_face_clearance(surface_a(), all);
    }
    try {
      surface_ = SurfaceBinding::bind(*garment_, all, so, all.rows() > 0 ? &feature_attachment_ : nullptr);
    } catch (const Error& e) {  // e.g. a voxel size too small for the garment: name its file
      throw input_error(garment_->source ? garment_->source->file : "garment", e.what());
    }
    bind_report_["surface"] = clock.ms();
    if (mirror_.active() && options_.collision) mirror_.set_layers(surface_->vertex_layers());
    // Which layer lies over which, for the collision step to keep them so.
    if (options_.collision && surface_->vertex_layers().size() == garment_->vertex_count()) {
      clock.reset();
      layer_covers_ = bind_layer_order(*garment_, surface_->vertex_layers(), surface_a(),
                                       kLayerReachCm * per_cm, kLayerGapCm * per_cm);
      bind_report_["layers"] = clock.ms();
    }
  }
}

// What a run will need, from the sizes alone (issue 17): refused before the work
// when above the budget or this machine's memory, and given in the report.
void GarmentBinding::check_memory_estimate() {
  const SurfaceOptions so = surface_options_in_units(options_);
  double agents = 0.0;
  try {
    if (options_.stage == Stage::Full) agents = estimated_agent_count(*garment_, so);
  } catch (const Error& e) {  // a voxel size too small for the garment: name its file
    throw input_error(garment_->source ? garment_->source->file : "garment", e.what());
  }
  const double mb = estimated_memory_mb(garment_->vertex_count(), agents, body_a_.mesh().triangles.size());
  memory_estimate_mb_ = mb;
  const double budget = options_.memory_budget_mb > 0 ? options_.memory_budget_mb : physical_memory_mb();
  if (budget > 0 && mb > budget) {
    char text[200];
    std::snprintf(text, sizeof text, "a resize of %zu vertices and about %.3g agents needs an estimated %.0f MB, more than the %.0f MB %s",
                  garment_->vertex_count(), agents, mb, budget, options_.memory_budget_mb > 0 ? "of the memory budget" : "of this machine");
    throw ResourceError((garment_->source ? garment_->source->file : std::string("garment")) + ": " + text);
  }
}

ResizeResult GarmentBinding::resize(const BodyMesh& body_b, const Progress& progress) const {
  check_body(body_b);
  check_same_connectivity(body_a_.mesh(), body_b);
  ResizeResult result;
  result.report["memory_estimate_mb"] = memory_estimate_mb_;

  // Step 1: primary resizing (section 3).
  const TriangleFrames frames_b = compute_frames(body_b);
  const TriangleChange change_b = warp_step(body_b, frames_b, result, progress);
  if (options_.stage == Stage::Warp) return result;
  // Body B is body A wherever the garment is bound, so the warp kept every vertex
  // to the bit: the garment as given is the answer. The later steps only correct
  // what the warp changes, and the collision step moves nothing the input on A
  // had as it is (docs/method.md, "Identity").
  if ((result.warped.array() == garment_->positions.array()).all()) {
    result.report["unchanged"] = true;
    return result;
  }

  const Stopwatch body_clock;  // the feature step's time counts body B's surface
  const BodySurface surface_b(body_b, body_topology_);
  const bool symmetric_b = body_b_symmetric(body_b, result.report);
  const double body_ms = body_clock.ms();
  const nlohmann::json warp_report = result.report;  // a second pass starts from the warp again
  const std::vector<std::string> warp_warnings = result.warnings;
  Points feature_before_collision = shape_steps(change_b, surface_b, symmetric_b, {}, result, progress);
  if (surface_ && !result.features.curves.empty()) {
    Points written = carry(feature_attachment_, result.positions);
    // Where the collision step pushed a curve's faces off a bulge of body B
    // that the curve's own clearance did not see (a coarse face over the hips
    // of a heavier body), the curve is solved again at least as far off as
    // the push left it, so the surface follows it there and the step need not
    // push it (the shared skirt on a body heavier than F_heavier: 0.16 cm off
    // its curve after one pass). Kept only when every curve ends closer.
    const std::vector<double> lift = lifts_from_pushes(surface_b, result.features, feature_before_collision, written);
    bool lifted = false;
    if (!lift.empty()) {
      const Stopwatch again_clock;
      ResizeResult again{result.warped, result.warped, {}, warp_report, warp_warnings};
      Points again_before = shape_steps(change_b, surface_b, symmetric_b, lift, again, progress);
      Points again_written = carry(feature_attachment_, again.positions);
      if (closer_to_curves(carried_curve_gaps(result.features, written),
                           carried_curve_gaps(again.features, again_written),
                           kPushedCurveToleranceCm * units_per_cm(options_.units))) {
        result = std::move(again);
        feature_before_collision = std::move(again_before);
        written = std::move(again_written);
        lifted = true;
      }
      result.report["timings_ms"]["lift_pass"] = again_clock.ms();  // the steps again, kept or not
    }
    if (options_.collision) result.report["surface"]["lifted_off_pushes"] = lifted;
    report_written_features(result.features, written, carry(feature_attachment_, result.warped),
                            feature_before_collision, result.report);
  }
  if (features_) result.report["timings_ms"]["features"] = result.report["timings_ms"]["features"].get<double>() + body_ms;
  if (options_.metrics) metrics_step(surface_b, result, progress);
  return result;
}

Points GarmentBinding::shape_steps(const TriangleChange& change_b, const BodySurface& surface_b, bool symmetric_b,
                                   const std::vector<double>& lift, ResizeResult& result,
                                   const Progress& progress) const {
  // Step 2: feature curves keep their shape (section 4).
  if (features_) feature_step(change_b, surface_b, symmetric_b, lift, result, progress);
  // Step 3: the surface follows the curves and keeps its local shape (section 5).
  Points feature_before_collision;
  if (surface_) feature_before_collision = surface_step(surface_b, symmetric_b, result, progress);
  if (!result.positions.allFinite()) throw Error("internal: the surface step produced a non-finite position");
  // Beyond the paper: nothing of the garment may end inside body B.
  if (surface_ && options_.collision) collision_step(surface_b, symmetric_b, result, progress);
  return feature_before_collision;
}

std::vector<double> GarmentBinding::lifts_from_pushes(const BodySurface& surface_b, const FeatureResult& curves,
                                                      const Points& before, const Points& after) const {
  // Only the collision step pushes; with follow-body the curves follow body B instead.
  if (!options_.collision || !options_.lift_pushed_curves || options_.follow_body_cm > 0.0) return {};
  const double per_cm = units_per_cm(options_.units), tolerance = kPushedCurveToleranceCm * per_cm;
  const std::vector<double> gaps_before = carried_curve_gaps(curves, before), gaps_after = carried_curve_gaps(curves, after);
  // Only where the written garment misses a curve: a lifted curve keeps its
  // shape less well (the outfit's profiles on F_shorter 8.9x closer to their
  // original shape than the warp after one pass, 4.4x after the lift).
  if (!(*std::max_element(gaps_after.begin(), gaps_after.end()) > kFollowedCurveGapCm * per_cm)) return {};
  std::vector<double> lift(static_cast<std::size_t>(after.rows()), 0.0);
  bool any = false;
  Eigen::Index first = 0;
  for (std::size_t c = 0; c < curves.curves.size(); ++c) {
    const Eigen::Index m = curves.curves[c].original.rows();
    if (gaps_after[c] > gaps_before[c] + tolerance) {
      // Each pushed sample keeps at least the distance from body B the push gave it.
      for (Eigen::Index i = first; i < first + m; ++i) {
        if ((after.row(i) - before.row(i)).norm() <= tolerance) continue;
        lift[static_cast<std::size_t>(i)] = surface_b.closest(row3(after, i)).distance;
        any = true;
      }
    }
    first += m;
  }
  if (!any) return {};
  // Both sides of a symmetric pair alike: the feature step makes its curves so.
  for (std::size_t i = 0; i < feature_mirror_.size() && i < lift.size(); ++i)
    if (feature_mirror_[i] != kNoMirror) lift[i] = lift[static_cast<std::size_t>(feature_mirror_[i])] =
        std::max(lift[i], lift[static_cast<std::size_t>(feature_mirror_[i])]);
  return lift;
}

TriangleChange GarmentBinding::warp_step(const BodyMesh& body_b, const TriangleFrames& frames_b, ResizeResult& result,
                                         const Progress& progress) const {
  const Stopwatch clock;
  progress.stage("warping to " + body_b.name);
  check_body_b_scale(body_a_.mesh(), body_b, frames_b);
  TriangleChange change_b = triangle_change(body_a_.frames(), frames_b);
  result.warped = warp_.apply(change_b);
  result.report["timings_ms"]["warp"] = clock.ms();
  result.report["warp"] = {{"alpha", options_.warp.alpha},
                           {"max_triangles", options_.warp.max_triangles},
                           {"capped_vertices", warp_.capped},
                           {"degenerate_triangles_a", body_a_.frames().degenerate},
                           {"degenerate_triangles_b", frames_b.degenerate}};
  if (body_a_.frames().degenerate + frames_b.degenerate > 0)
    result.warnings.push_back(std::to_string(body_a_.frames().degenerate) + " degenerate triangles on body A and " +
                              std::to_string(frames_b.degenerate) + " on body B were skipped");
  if (!result.warped.allFinite()) throw Error("internal: the warp produced a non-finite position");
  result.positions = result.warped;
  return change_b;
}

// Symmetrise only when body B is symmetric too (the same vertices as body A's, mirrored).
bool GarmentBinding::body_b_symmetric(const BodyMesh& body_b, nlohmann::json& report) const {
  report["symmetry"] = symmetry_report_;
  if (!mirror_.active()) return false;
  const auto [body_b_error, symmetric_b] = mirror_.body_error(body_b.vertices);
  report["symmetry"]["body_b_error"] = body_b_error;
  report["symmetry"]["symmetrised"] = symmetric_b;
  return symmetric_b;
}

const Csr& GarmentBinding::vertex_adjacency_once() const {
  std::call_once(adjacency_once_, [&] { adjacency_ = vertex_adjacency(*garment_); });
  return adjacency_;
}

const FoldBinding& GarmentBinding::folds_once() const {
  std::call_once(folds_once_, [&] { folds_ = bind_folds(*garment_); });
  return folds_;
}

void GarmentBinding::feature_step(const TriangleChange& change_b, const BodySurface& surface_b, bool symmetric_b,
                                  const std::vector<double>& lift, ResizeResult& result,
                                  const Progress& progress) const {
  const Stopwatch clock;
  progress.stage("optimising " + std::to_string(features_->model.curves.size()) + " feature curves");
  if (features_->model.options.clearance > 0.0) surface_b.prepare_inside_test();
  FeatureResult& curves = result.features;
  // The dip only where the warp leaves that face's corner too close to body B as well.
  std::vector<double> extra = dip_clearance_;
  const double clearance = options_.clearance_cm * units_per_cm(options_.units);
  parallel_for(0, extra.size(), 64, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      if (extra[i] == 0.0) continue;
      bool close = false;
      for (const Index v : feature_attachment_.vertex[i]) {
        const Vec3 p = row3(result.warped, v);
        close = close || surface_b.inside(p) || surface_b.closer_than(p, clearance);
      }
      if (!close) extra[i] = 0.0;
    }
  });
  if (!lift.empty()) {
    if (extra.empty()) extra.assign(lift.size(), 0.0);
    const double base = features_->model.options.clearance;
    for (std::size_t i = 0; i < lift.size(); ++i) extra[i] = std::max(extra[i], lift[i] - base);
  }
  curves = optimise_features(
      *features_, change_b, [&](const Vec3& p) { return surface_b.closest(p).distance; },
      [&](const Vec3& p, double clearance) { return clearance_need(surface_b, p, clearance); }, extra);
  if (symmetric_b && !feature_mirror_.empty()) {
    symmetrise_curves(curves, feature_mirror_, mirror_.plane_x());
    restore_meetings(features_->model, curves);
  }
  result.report["timings_ms"]["features"] = clock.ms();
  result.report["features"] = features_report(curves);
}

Points GarmentBinding::surface_step(const BodySurface& surface_b, bool symmetric_b, ResizeResult& result,
                                    const Progress& progress) const {
  const Stopwatch clock;
  progress.stage("optimising the surface (" + std::to_string(surface_->agent_count()) + " agents)");
  std::vector<const Points*> targets, warped;
  for (const CurveResult& c : result.features.curves) {
    targets.push_back(&c.optimised);
    warped.push_back(&c.warped);
  }
  const Points feature_warped = concat_rows(warped), feature_targets = concat_rows(targets);
  SurfaceResult s = surface_->apply(result.warped, feature_targets, surface_b, &feature_warped);
  result.report["timings_ms"]["surface"] = clock.ms();
  result.report["surface"] = surface_report(s.stats);
  result.positions = std::move(s.positions);
  // The agents' solve is not exactly mirror-symmetric (its ordering and blends are not):
  // a symmetric pair gives a symmetric garment.
  if (symmetric_b) {
    const bool snaps = surface_->snaps();
    std::vector<double> snapped;
    if (snaps) snapped = carried_curve_gaps(result.features, carry(feature_attachment_, result.positions));
    mirror_.symmetrise(result.positions);
    // The mean with the mirror image is carried on the other side's faces; on a
    // mesh that is not mirror-symmetric that bends the garment off the curves
    // the snap reached (the real outfit on F_thinner: 0.046 -> 0.053 cm, 0.072
    // once written). So the snap again, its moves made alike on both sides: a
    // move is smooth, so carrying it on the other side's faces loses little
    // (the snap's own moves are not alike where the two sides' faces are cut
    // differently: the skirt's waist 0.05 cm out of symmetry). Kept only when
    // no curve ends farther off and the farthest comes closer: where the two
    // sides' snaps differ (samples in conflict), their mean can be farther off
    // than either (the suit on M_heavier: 0.23 -> 0.25 cm, its creases' 2D
    // straightness 1.9x -> 1.0x the warp's; on F_thinner two creases 0.03 cm
    // farther off, the others 0.02 closer). And run only when the
    // symmetrisation took the farthest curve farther off than the snap left it:
    // elsewhere its small moves next to the body gave the collision step
    // corners to push (the 135k dress on F_shorter: written 0.004 -> 0.017 cm).
    if (snaps) {
      const std::vector<double> symmetrised =
          carried_curve_gaps(result.features, carry(feature_attachment_, result.positions));
      bool closer = false;
      if (farther_off(snapped, symmetrised)) {
        const Points before = result.positions;  // a copy of the garment only when the snap runs
        surface_->snap(result.positions, feature_targets, s.held);
        mirror_.symmetrise_moves(before, result.positions);
        closer = closer_to_curves(symmetrised,
                                  carried_curve_gaps(result.features, carry(feature_attachment_, result.positions)),
                                  kNegligibleGapChangeCm * units_per_cm(options_.units));
        if (!closer) result.positions = before;
      }
      result.report["surface"]["snapped_after_symmetrising"] = closer;
      result.report["surface"]["feature_gap_symmetrised"] = *std::max_element(symmetrised.begin(), symmetrised.end());
    }
  }
  if (s.stats.anchored > 0)
    result.warnings.push_back(std::to_string(s.stats.anchored) + " agents in " + std::to_string(s.stats.anchored_groups) +
                              " groups with no fixed agent were anchored at their warped positions");
  if (!s.stats.converged)
    result.warnings.push_back("surface solve stopped after " + std::to_string(s.stats.iterations) +
                              " iterations with update " + std::to_string(s.stats.final_update));
  // Where the surface step leaves each feature, before the collision step moves it.
  return carry(feature_attachment_, result.positions);
}

void GarmentBinding::collision_step(const BodySurface& surface_b, bool symmetric_b, ResizeResult& result,
                                    const Progress& progress) const {
  const Stopwatch clock;
  progress.stage("resolving penetrations");
  CollisionOptions co;
  const double per_cm = units_per_cm(options_.units);
  co.clearance = options_.clearance_cm * per_cm;
  co.near_band *= per_cm;  // the defaults are in cm
  co.max_lift *= per_cm;
  co.face_clearance *= per_cm;
  co.probe_radius *= per_cm;
  // The corners of the faces the curves sit on stay where the surface step put them (unless too close themselves).
  std::vector<std::uint8_t> pinned;
  if (!result.features.curves.empty()) {
    pinned = feature_corners(feature_attachment_, result.positions.rows());
    co.pinned = &pinned;
  }
  // Folds first: the smoothing may move vertices towards the body, the pushes then clear them.
  const Csr& adjacency = vertex_adjacency_once();
  const std::vector<std::uint8_t>* keep = pinned.empty() ? nullptr : &pinned;
  FoldReport folds, folds_after;
  double folds_ms = 0.0;
  if (options_.smooth_folds) {
    const Stopwatch folds_clock;
    folds = smooth_out_folds(*garment_, folds_once(), result.positions, adjacency, keep);
    folds_ms += folds_clock.ms();
  }
  // After the rounds: both sides of a symmetric pair pushed alike, and the folds
  // the pushes made smoothed out; one more round clears what that moved. The
  // smoothing's moves are not made alike after it: a vertex's mirror move is
  // read off the mirror face, and on a split mesh that turned slivers over
  // again (the 1M dress on F_thinner: 25 faces after the smoothing left 4).
  const Points before = symmetric_b ? result.positions : Points();
  auto alike = [&](const Points& now) { return mirror_.alike_pushes(before, now, kSymmetricPushToleranceCm * per_cm, co.max_lift); };
  // With a symmetric pair twice: the round after the first pass pushes out on
  // one side what the capped means left too close (the shared skirt on
  // F_heavier: 0.20 cm out of symmetry after one pass, 0.09 after two).
  if (symmetric_b) co.after_rounds_passes = 2;
  // The folds smoothed at every pass: the round after the first pass turned
  // slivers under the bust of the 135k dress on F_thinner over, which the
  // second pass's smoothing takes out (3 faces in the written garment, 0).
  int hook_calls = 0;
  if (symmetric_b || options_.smooth_folds)
    co.after_rounds = [&](const Points& now) {
      std::vector<std::pair<Index, Vec3>> moves;
      if (symmetric_b) moves = alike(now);
      if (!options_.smooth_folds) return moves;
      const Stopwatch folds_clock;
      Points p = now;
      for (const auto& [i, q] : moves) p.row(i) = q.transpose();
      const FoldReport pass = smooth_out_folds(*garment_, folds_once(), p, adjacency, keep);
      if (hook_calls++ == 0) folds_after.folded_before = pass.folded_before;  // the passes' figures summed, the last's left
      folds_after.folded_after = pass.folded_after;
      folds_after.smoothed += pass.smoothed;
      folds_after.rounds += pass.rounds;
      if (pass.smoothed > 0) {
        moves.clear();
        for (Index i = 0; i < p.rows(); ++i)
          if (p.row(i) != now.row(i)) moves.emplace_back(i, row3(p, i));
      }
      folds_ms += folds_clock.ms();
      return moves;
    };
  co.adjacency = &adjacency;
  co.faces_of_vertex = &folds_once().faces_of_vertex;  // made once, with the folds' binding
  if (!layer_covers_.empty()) co.layers = &layer_covers_;
  const CollisionReport c = resolve_penetrations(*garment_, result.positions, surface_b, co);
  LastFoldsReport last;
  if (options_.smooth_folds) {
    const Stopwatch folds_clock;
    last = smooth_out_last_folds(*garment_, folds_once(), result.positions, adjacency, keep, surface_b, co.clearance);
    folds_ms += folds_clock.ms();
  }
  result.report["timings_ms"]["collision"] = clock.ms();
  result.report["collision"] = c.to_json();
  if (symmetric_b) result.report["collision"]["not_pushed_alike"] = mirror_.pushed_apart();  // images on another layer
  if (options_.smooth_folds) {
    auto figures = [](const FoldReport& f) {
      return nlohmann::json{{"folded", f.folded_before}, {"left", f.folded_after}, {"smoothed", f.smoothed}, {"rounds", f.rounds}};
    };
    result.report["collision"]["folds"] = figures(folds);
    result.report["collision"]["folds"]["after_pushes"] = figures(folds_after);
    result.report["collision"]["folds"]["after_rounds"] = figures(last.folds);
    result.report["collision"]["folds"]["after_rounds"]["held"] = last.held;
    result.report["timings_ms"]["collision_folds"] = folds_ms;  // part of the collision step's
  }
  if (c.inside_after > 0)
    result.warnings.push_back(std::to_string(c.inside_after) + " vertices are still inside body B after collision resolution");
  if (c.faces_inside_after > 0)
    result.warnings.push_back(std::to_string(c.faces_inside_after) +
                              " faces still have the body poking through them after collision resolution");
}

void GarmentBinding::metrics_step(const BodySurface& surface_b, ResizeResult& result, const Progress& progress) const {
  const Stopwatch clock;
  progress.stage("measuring");
  const BodySurface surface_a(body_a_.mesh(), body_topology_);
  result.report["metrics"] = {{"warp", compute_metrics(*garment_, result.warped, surface_a, surface_b).to_json()},
                              {"result", compute_metrics(*garment_, result.positions, surface_a, surface_b).to_json()}};
  result.report["timings_ms"]["metrics"] = clock.ms();
}

}  // namespace refit
