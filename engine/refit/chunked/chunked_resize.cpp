// ChunkedBinding: GarmentBinding's stages, each a pass (or a few) over the
// garment's chunks. Where a stage needs the whole garment it keeps only what is
// small (curves, agents, layers), and the per-vertex work goes chunk by chunk.
#include <refit/chunked/chunked_resize.hpp>

#include <refit/body/body_surface.hpp>
#include <refit/chunked/chunked_attach.hpp>
#include <refit/chunked/chunked_features.hpp>
#include <refit/chunked/chunked_normals.hpp>
#include <refit/chunked/chunked_surface.hpp>
#include <refit/chunked/chunked_symmetry.hpp>
#include <refit/core/error.hpp>
#include <refit/pipeline/input_checks.hpp>
#include <refit/pipeline/resize_report.hpp>
#include <refit/pipeline/units.hpp>
#include <refit/surface/feature_snap.hpp>

#include <algorithm>
#include <cstring>
#include <functional>
#include <limits>

namespace refit {

struct ChunkedBinding::Bound {
  nlohmann::json symmetry_report;
  std::shared_ptr<const BodyTopology> body_topology;  // body A's triangles: every body B's surface shares them
  std::optional<FeatureBinding> features;
  std::optional<SurfaceBinding> surface;
  SurfaceAttachment feature_attachment;      // where the feature samples (all curves, in order) sit on the garment
  std::optional<RecordFile<std::uint32_t>> layers;  // per vertex (with layers)
  std::vector<Index> carries_feature;        // vertices of the faces feature samples sit on (sorted; with a zone)
  // Symmetry (GarmentBinding's): each vertex's mirror image on the garment, when symmetric.
  std::optional<ChunkedMirror> mirror;
  std::vector<Index> feature_mirror, body_mirror;
  double mirror_x = 0.0, mirror_tolerance = 0.0;
};

namespace {

// Rows [first, first + count) of a per-vertex record file, or an empty vector without one.
template <class T>
std::vector<T> rows_of(const std::optional<RecordFile<T>>& file, std::size_t first, std::size_t count) {
  std::vector<T> out;
  if (file) file->read(first, count, out);
  return out;
}

// The samples attached by `at` carried on the vertices of `positions` (carry's sums).
Points carried(const SurfaceAttachment& at, const PointFile& positions) {
  std::vector<Index> ids;
  for (const auto& v : at.vertex) ids.insert(ids.end(), v.begin(), v.end());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  Points p;
  PointGather(positions, 0).gather(ids, p);
  SurfaceAttachment local = at;
  for (auto& v : local.vertex)
    for (Index& i : v) i = Index(std::lower_bound(ids.begin(), ids.end(), i) - ids.begin());
  return carry(local, p);
}

// Whether any row of `b` differs from `a`'s in any bit.
bool any_moved(const PointFile& a, const PointFile& b, std::size_t chunk) {
  bool moved = false;
  Points rows;
  for (std::size_t first = 0; first < a.rows() && !moved; first += chunk) {
    const std::size_t count = std::min(chunk, a.rows() - first);
    Points ra;
    a.read(first, count, ra);
    b.read(first, count, rows);
    moved = std::memcmp(ra.data(), rows.data(), sizeof(double) * 3 * count) != 0;
  }
  return moved;
}

}  // namespace

void check_chunked_options(const ResizeOptions& options) {
  if (options.metrics) throw Error("--metrics is not available in the chunked mode");
  // Refused, never skipped: the output would differ from the in-memory mode's.
  if (options.stage == Stage::Full && options.collision)
    throw Error("the chunked mode does not do the collision step yet (use --no-collision)");
}

ChunkedBinding::~ChunkedBinding() = default;

ChunkedBinding::ChunkedBinding(std::shared_ptr<const GarmentStore> garment, BodyMesh body_a, ResizeOptions options,
                               std::vector<FeatureSpec> features, ChunkPlan plan, const Progress& progress)
    : store_(std::move(garment)),
      options_(std::move(options)),
      plan_(std::move(plan)),
      body_a_((check_body(body_a), std::move(body_a)), options_.warp),
      bound_(std::make_unique<Bound>()) {
  const GarmentStore& g = *store_;
  const double per_cm = units_per_cm(options_.units);
  if (g.vertex_count() == 0) throw Error("garment: empty garment (no vertices)");
  check_chunked_options(options_);
  check_garment_on_body_a(g.low(), g.high(), g.obj().file(), body_a_.mesh(), per_cm);
  Stopwatch clock;
  progress.stage("binding " + std::to_string(g.vertex_count()) + " garment vertices to " + body_a_.mesh().name +
                 " (in chunks of " + std::to_string(plan_.chunk_vertices) + ")");
  // The warp binds each chunk when it applies it: its per-vertex sets are the
  // largest thing a binding holds (4 bytes per vertex and triangle).
  bind_report_["warp"] = clock.ms();
  if (options_.stage == Stage::Warp) return;
  bound_->body_topology = body_topology(body_a_.mesh());

  clock.reset();
  const PointGather x(g.positions(), plan_.gather_bytes);
  // Each garment vertex's mirror image, found on the garment's surface, slab by slab.
  const double plane_x = mirror_plane_x(body_a_.mesh().vertices);
  const double tolerance = options_.symmetry_tolerance_cm * per_cm;
  double garment_error = 0.0;
  if (options_.symmetry != SymmetryMode::None) {
    progress.stage("finding the garment's mirror images");
    // Exact within twice the tolerance: every vertex symmetry pairs, and the 95th percentile.
    bound_->mirror = chunked_mirror_attach(g, x, plan_, plane_x, 2.0 * tolerance);
    garment_error = bound_->mirror->garment_error;
  }
  const SymmetryCheck sym = check_symmetry(plane_x, garment_error, body_a_.mesh().vertices, tolerance, options_.symmetry);
  if (sym.symmetric) {
    bound_->mirror_x = sym.plane_x;
    bound_->mirror_tolerance = sym.tolerance;
    bound_->body_mirror = mirror_pairs(body_a_.mesh().vertices, bound_->mirror_x, sym.tolerance);
  } else {
    bound_->mirror.reset();
  }
  bound_->symmetry_report = symmetry_report(sym);
  bind_report_["symmetry"] = clock.ms();
  if (!features.empty()) {
    clock.reset();
    progress.stage("sampling " + std::to_string(features.size()) + " feature curves");
    std::vector<FeatureCurve> curves = build_feature_curves(chunked_feature_garment(g, x, plan_), features);
    const std::size_t given = curves.size();
    if (sym.symmetric) {
      curves = add_mirrored_curves(std::move(curves), sym.plane_x);
      for (const std::string& name : drop_curves_off_garment(curves, given, sym.tolerance, [&](const Points& s) {
             return offset_lengths(chunked_attach(g, x, plan_, s));
           }))
        bound_->symmetry_report["mirrors_off_garment"].push_back(name);
    }
    for (std::size_t i = given; i < curves.size(); ++i) bound_->symmetry_report["mirrored_features"].push_back(curves[i].name);
    bound_->features = bind_features(body_a_, std::move(curves), options_.shape_matching);
    if (sym.symmetric) bound_->feature_mirror = sample_mirror_pairs(bound_->features->model.curves, bound_->mirror_x);
    bind_report_["features"] = clock.ms();
  }
  if (options_.stage == Stage::Full) {
    clock.reset();
    progress.stage("building the agent system");
    const SurfaceOptions so = surface_options_in_units(options_);
    const Points all = bound_->features ? all_samples(bound_->features->model.curves) : Points(0, 3);
    if (all.rows() > 0) {  // as in memory (resize.cpp): where each sample sits on its own layer
      const Points anchors = all_sample_anchors(bound_->features->model.curves);
      bound_->feature_attachment = chunked_attach(g, x, plan_, anchors);
      bound_->feature_attachment.offset += all - anchors;
    }
    std::vector<std::uint32_t> layers;
    try {
      SurfaceGarmentPart part = chunked_surface_part(g, x, plan_, all, so, bound_->feature_attachment, layers);
      bound_->surface = SurfaceBinding::bind_agents(std::move(part), all, so, bound_->feature_attachment);
    } catch (const Error& e) {  // e.g. a voxel size too small for the garment: name its file
      throw input_error(g.obj().file(), e.what());
    }
    if (!layers.empty()) {
      bound_->layers.emplace(plan_.folder);
      bound_->layers->write(0, std::span<const std::uint32_t>(layers));
    }
    if (so.feature_zone_rings > 0) {
      const SurfaceAttachment& at = bound_->feature_attachment;
      for (std::size_t k = 0; k < at.vertex.size(); ++k)
        for (int j = 0; j < 3; ++j)
          if (at.weight[k][j] != 0.0) bound_->carries_feature.push_back(at.vertex[k][j]);
      std::sort(bound_->carries_feature.begin(), bound_->carries_feature.end());
      bound_->carries_feature.erase(std::unique(bound_->carries_feature.begin(), bound_->carries_feature.end()),
                                    bound_->carries_feature.end());
    }
    bind_report_["surface"] = clock.ms();
  }
}

ChunkedResult ChunkedBinding::resize(const BodyMesh& body_b, const std::string& out, const Progress& progress) const {
  check_body(body_b);
  check_same_connectivity(body_a_.mesh(), body_b);
  const GarmentStore& g = *store_;
  const std::size_t nv = g.vertex_count(), chunk = plan_.chunk_vertices;
  ChunkedResult result;
  nlohmann::json& report = result.report;
  nlohmann::json& timings = report["timings_ms"];
  Stopwatch clock;

  // Step 1: primary resizing (section 3), bound and applied a chunk at a time.
  progress.stage("warping to " + body_b.name);
  report["memory_estimate_mb"] = plan_.estimate_mb;
  const TriangleFrames frames_b = compute_frames(body_b);
  check_body_b_scale(body_a_.mesh(), body_b, frames_b);
  PointFile warped(plan_.folder, nv);
  std::size_t capped = 0;
  const TriangleChange change = triangle_change(body_a_.frames(), frames_b);  // once for every chunk
  for_each_chunk(g.positions(), chunk, [&](std::size_t first, const Points& original) {
    const WarpBinding bound = body_a_.bind(original);
    capped += bound.capped;
    const Points w = bound.apply(change);
    if (!w.allFinite()) throw Error("internal: the warp produced a non-finite position");
    warped.write(first, w);
  });
  timings["warp"] = clock.ms();
  report["warp"] = {{"alpha", options_.warp.alpha},
                    {"max_triangles", options_.warp.max_triangles},
                    {"capped_vertices", capped},
                    {"degenerate_triangles_a", body_a_.frames().degenerate},
                    {"degenerate_triangles_b", frames_b.degenerate}};
  if (body_a_.frames().degenerate + frames_b.degenerate > 0)
    result.warnings.push_back(std::to_string(body_a_.frames().degenerate) + " degenerate triangles on body A and " +
                              std::to_string(frames_b.degenerate) + " on body B were skipped");
  const PointFile* final_positions = &warped;
  std::optional<PointFile> surfaced, symmetrised, resnapped, alike;

  // Body B is body A wherever the garment is bound, so the warp kept every vertex
  // to the bit: the garment as given is the answer (GarmentBinding::resize).
  const bool unchanged = options_.stage != Stage::Warp && !any_moved(g.positions(), warped, chunk);
  if (unchanged) report["unchanged"] = true;
  if (options_.stage != Stage::Warp && !unchanged) {
    clock.reset();
    const BodySurface surface_b(body_b, bound_->body_topology);
    const auto distance_b = [&](const Vec3& p) { return surface_b.closest(p).distance; };
    // Symmetrise only when body B is symmetric too (the same vertices as body A's, mirrored).
    bool symmetric_b = false;
    report["symmetry"] = bound_->symmetry_report;
    if (!bound_->body_mirror.empty()) {
      const double body_b_error = paired_mirror_error(body_b.vertices, bound_->body_mirror, bound_->mirror_x);
      symmetric_b = body_b_error <= bound_->mirror_tolerance;
      report["symmetry"]["body_b_error"] = body_b_error;
      report["symmetry"]["symmetrised"] = symmetric_b;
    }

    // Step 2: feature curves keep their shape (section 4): the curves are small.
    FeatureResult& curves = result.features;
    if (bound_->features) {
      progress.stage("optimising " + std::to_string(bound_->features->model.curves.size()) + " feature curves");
      curves = optimise_features(*bound_->features, change, distance_b);
      if (symmetric_b && !bound_->feature_mirror.empty()) {
        symmetrise_curves(curves, bound_->feature_mirror, bound_->mirror_x);
        restore_meetings(bound_->features->model, curves);
      }
      timings["features"] = clock.ms();
      report["features"] = features_report(curves);
    }

    // Step 3: the surface (section 5): the agents are solved in memory, then
    // every vertex is re-emitted a chunk at a time.
    Points feature_before_collision;
    if (bound_->surface) {
      const SurfaceBinding& surface = *bound_->surface;
      clock.reset();
      progress.stage("optimising the surface (" + std::to_string(surface.agent_count()) + " agents)");
      std::vector<const Points*> targets, warped_samples;
      for (const CurveResult& c : curves.curves) {
        targets.push_back(&c.optimised);
        warped_samples.push_back(&c.warped);
      }
      const Points feature_targets = concat_rows(targets), feature_warped = concat_rows(warped_samples);
      check_finite(feature_targets, "feature target");
      check_finite(feature_warped, "warped feature sample");
      const std::vector<Index> agent_vertices = surface.agent_vertices();
      Points at_agents;
      PointGather(warped, 0).gather(agent_vertices, at_agents);
      const auto distance = surface.body_distance(surface_b);
      const NearBody near = surface.near_body(surface_b);
      SurfaceBinding::AgentSolution sol =
          surface.solve_agents(surface.agent_positions(at_agents, agent_vertices, &feature_warped), feature_targets,
                               distance, nullptr);
      SurfaceStats& st = sol.stats;
      clock.reset();
      // The re-emission, chunk by chunk; what the snap needs of the vertices the
      // samples sit on is kept aside, and each vertex's feature agents in reach.
      const SurfaceAttachment& at = bound_->feature_attachment;
      std::vector<Index> sample_vertices;
      for (const auto& v : at.vertex) sample_vertices.insert(sample_vertices.end(), v.begin(), v.end());
      std::sort(sample_vertices.begin(), sample_vertices.end());
      sample_vertices.erase(std::unique(sample_vertices.begin(), sample_vertices.end()), sample_vertices.end());
      SnapVertices snap_vertices;
      struct SnapTerm {
        Index vertex;
        std::int32_t feature;
        float weight;
        float held;  // the vertex's share of the warp (SurfaceResult::held)
      };
      RecordFile<SnapTerm> snap_terms(plan_.folder);
      std::size_t snap_count = 0;
      bool any_weight = false;  // the snap's weights are not empty
      const bool snaps = surface.snaps();
      std::function<FeatureSnapReport(PointFile&)> snap_in_passes;  // the snap's passes on a file (set below when it snaps)
      surfaced.emplace(plan_.folder, nv);
      st.vertices_capped = st.vertices_without_agent = 0;
      for_each_chunk(g.positions(), chunk, [&](std::size_t first, const Points& original) {
        Points w;
        warped.read(first, std::size_t(original.rows()), w);
        const std::vector<std::uint32_t> layer = rows_of(bound_->layers, first, std::size_t(original.rows()));
        const VertexBlends blends = surface.vertex_blends(original, layer);
        st.vertices_capped += blends.capped;
        st.vertices_without_agent += blends.without_agent;
        std::vector<std::uint8_t> carries;
        if (surface.options().feature_zone_rings > 0) {
          carries.assign(std::size_t(original.rows()), 0);
          const auto lo = std::lower_bound(bound_->carries_feature.begin(), bound_->carries_feature.end(), Index(first));
          for (auto it = lo; it != bound_->carries_feature.end() && *it < first + carries.size(); ++it) carries[*it - first] = 1;
        }
        std::vector<float> held_share;
        const Points s = surface.emit_vertices(sol, original, w, blends, carries, near, held_share, st);
        surfaced->write(first, s);
        if (!snaps) return;
        // The snap's reach: its own (snap_radius > 0) or the blends', as SurfaceBinding::snap takes it.
        const bool kernel = surface.options().snap_radius > 0.0;
        const SnapReach own_reach = kernel ? surface.snap_reach(original, layer) : SnapReach{};
        const Csr& reach = kernel ? own_reach.reach : blends.reach;
        const std::vector<float>& weight = kernel ? own_reach.weight : blends.weight;
        any_weight = any_weight || !weight.empty();
        const auto held = [&](std::size_t i) { return held_share.empty() ? 0.0f : held_share[i]; };
        const auto lo = std::lower_bound(sample_vertices.begin(), sample_vertices.end(), Index(first));
        for (auto it = lo; it != sample_vertices.end() && *it < first + std::size_t(s.rows()); ++it) {
          const std::size_t i = *it - first;
          SnapVertex& v = snap_vertices[*it];
          v.position = row3(s, Index(i));
          v.held = held(i);
          const auto r = reach.row(i);
          v.reach.assign(r.begin(), r.end());
          if (!weight.empty()) v.weight.assign(weight.begin() + reach.offsets[i], weight.begin() + reach.offsets[i + 1]);
        }
        std::vector<SnapTerm> terms;
        for (std::size_t i = 0; i < std::size_t(s.rows()); ++i) {
          if (held(i) >= 1.0f || weight.empty()) continue;
          const auto r = reach.row(i);
          for (std::size_t q = 0; q < r.size(); ++q)
            if (surface.feature_of()[r[q]] >= 0)
              terms.push_back({Index(first + i), surface.feature_of()[r[q]], weight[reach.offsets[i] + q], held(i)});
        }
        snap_terms.write(snap_count, std::span<const SnapTerm>(terms));
        snap_count += terms.size();
      });
      if (snaps) {
        // The snap's small solve, then its corrections added chunk by chunk (as
        // apply_feature_snap adds them), in passes as SurfaceBinding::snap: a pass
        // that would not lower the gap is not applied; the sample vertices move
        // by each pass as the garment's do.
        const auto apply_pass = [&](const FeatureSnap& snap, const SnapKernel& kernel, PointFile& file) {
          std::vector<SnapTerm> batch;
          std::size_t next = 0, taken = 0, moved = 0;
          Index previous = std::numeric_limits<Index>::max();
          for_each_chunk(file, chunk, [&](std::size_t first, const Points& rows) {
            Points s = rows;
            const std::size_t end = first + std::size_t(rows.rows());
            for (;;) {
              if (taken == batch.size()) {
                if (next == snap_count) break;
                snap_terms.read(next, std::min<std::size_t>(1 << 16, snap_count - next), batch);
                next += batch.size();
                taken = 0;
              }
              const SnapTerm& t = batch[taken];
              if (t.vertex >= end) break;
              s.row(Eigen::Index(t.vertex - first)) += kernel.share(t.weight, t.feature, t.held) * snap.correction.row(t.feature);
              moved += t.vertex != previous;
              previous = t.vertex;
              ++taken;
            }
            file.write(first, s);
          });
          for (auto& [v, sv] : snap_vertices) {
            if (sv.held >= 1.0f || sv.weight.empty()) continue;
            for (std::size_t q = 0; q < sv.reach.size(); ++q) {
              const std::int32_t f = surface.feature_of()[sv.reach[q]];
              if (f >= 0) sv.position += kernel.share(sv.weight[q], f, sv.held) * snap.correction.row(f).transpose();
            }
          }
          return moved;
        };
        snap_in_passes = [&, apply_pass](PointFile& file) {
          FeatureSnapReport total;
          const int passes = std::max(1, surface.options().snap_passes);
          for (int pass = 0; pass < passes; ++pass) {
            const SnapKernel kernel = narrowed_kernel(at, snap_vertices, surface.feature_of(), surface.snap_share(pass));
            FeatureSnap snap = solve_feature_snap(feature_targets, at, snap_vertices, surface.feature_of(), any_weight,
                                                  surface.options().snap_regularisation, kernel);
            snap.report.gap_after = snapped_gap(snap, feature_targets, at, snap_vertices, surface.feature_of(), kernel);
            if (pass == 0) total = snap.report;
            total.gap_after = snap.report.gap_after;
            if (!(snap.report.gap_after < snap.report.gap_before)) {
              total.gap_after = snap.report.gap_before;
              break;
            }
            if (snap.correction.size() > 0 && snap_count > 0) {
              const std::size_t moved = apply_pass(snap, kernel, file);
              if (pass == 0) total.vertices_moved = moved;
            }
          }
          return total;
        };
        const FeatureSnapReport total = snap_in_passes(*surfaced);
        st.feature_gap_before_snap = total.gap_before;
        st.feature_gap = total.gap_after;
        st.vertices_snapped = total.vertices_moved;
      }
      st.ms.reconstruct = clock.ms();
      timings["surface"] = st.ms.solve + st.ms.reconstruct;
      report["surface"] = surface_report(st);
      if (st.anchored > 0)
        result.warnings.push_back(std::to_string(st.anchored) + " agents in " + std::to_string(st.anchored_groups) +
                                  " groups with no fixed agent were anchored at their warped positions");
      if (!st.converged)
        result.warnings.push_back("surface solve stopped after " + std::to_string(st.iterations) +
                                  " iterations with update " + std::to_string(st.final_update));
      final_positions = &*surfaced;
      // The agents' solve is not exactly mirror-symmetric: a symmetric pair gives a symmetric garment.
      if (symmetric_b) {
        symmetrised.emplace(plan_.folder, nv);
        {
          const PointGather s(*surfaced, plan_.gather_bytes);
          for_each_chunk(*surfaced, chunk, [&](std::size_t first, const Points& rows) {
            symmetrised->write(first, symmetrised_rows(bound_->mirror->records, s, first, rows, bound_->mirror_x,
                                                       bound_->mirror_tolerance));
          });
        }
        final_positions = &*symmetrised;
        // The snap again where the symmetrisation took the garment farther off the
        // curves, its moves made alike on both sides (GarmentBinding::surface_step).
        if (snaps) {
          const std::vector<double> gap_symmetrised = carried_curve_gaps(curves, carried(at, *symmetrised));
          bool closer = false;
          if (farther_off(carried_curve_gaps(curves, carried(at, *surfaced)), gap_symmetrised)) {
            Points p;
            PointGather(*symmetrised, 0).gather(sample_vertices, p);
            for (std::size_t k = 0; k < sample_vertices.size(); ++k)
              snap_vertices[sample_vertices[k]].position = row3(p, Index(k));
            resnapped.emplace(plan_.folder, nv);
            for_each_chunk(*symmetrised, chunk, [&](std::size_t first, const Points& rows) { resnapped->write(first, rows); });
            snap_in_passes(*resnapped);
            alike.emplace(plan_.folder, nv);
            const PointGather before(*symmetrised, plan_.gather_bytes / 2), after(*resnapped, plan_.gather_bytes / 2);
            for_each_chunk(*symmetrised, chunk, [&](std::size_t first, const Points& rows) {
              Points moved;
              resnapped->read(first, std::size_t(rows.rows()), moved);
              alike->write(first, symmetrised_move_rows(bound_->mirror->records, before, after, first, rows, moved,
                                                        bound_->mirror_tolerance));
            });
            closer = closer_to_curves(gap_symmetrised, carried_curve_gaps(curves, carried(at, *alike)),
                                      kNegligibleGapChangeCm * units_per_cm(options_.units));
            if (closer) final_positions = &*alike;  // else the symmetrised garment
          }
          report["surface"]["snapped_after_symmetrising"] = closer;
          report["surface"]["feature_gap_symmetrised"] = *std::max_element(gap_symmetrised.begin(), gap_symmetrised.end());
        }
      }
      feature_before_collision = carried(at, *final_positions);
    }
    if (bound_->surface && !curves.curves.empty())
      report_written_features(curves, carried(bound_->feature_attachment, *final_positions),
                              carried(bound_->feature_attachment, warped), feature_before_collision, report);
  }

  clock.reset();
  progress.stage("writing " + out);
  ObjEdits edits;
  edits.positions = [&](std::size_t first, std::size_t count, Points& rows) { final_positions->read(first, count, rows); };
  // As write_garment_obj: the normals faces use are recomputed when a vertex moved.
  std::optional<ChunkedNormals> normals;
  if (g.corner_normals() && any_moved(g.positions(), *final_positions, chunk)) normals = chunked_normals(g, *final_positions, plan_);
  if (normals)
    edits.normals = [&](std::size_t first, std::size_t count, Points& rows, std::vector<std::uint8_t>& recomputed) {
      normals->normals.read(first, count, rows);
      normals->recomputed.read(first, count, recomputed);
    };
  g.obj().write(out, edits);
  if (normals) {
    result.written.warnings = normals->warnings;
    result.written.normals_recomputed = normals->count;
  }
  timings["write"] = clock.ms();
  report["chunks"] = {{"vertices", plan_.chunk_vertices},
                      {"faces", plan_.chunk_faces},
                      {"estimate_mb", plan_.estimate_mb},
                      {"positions_in_memory", PointGather::resident_bytes(nv) <= plan_.gather_bytes}};
  return result;
}

}  // namespace refit
