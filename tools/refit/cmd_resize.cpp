// `refit resize`: one garment, body A, one or many bodies B. Binds once, then
// resizes to each body; every output file is written atomically.
#include "command.hpp"
#include "manifest.hpp"
#include "patterns_output.hpp"
#include "report_file.hpp"

#include <refit/chunked/chunked_resize.hpp>
#include <refit/chunked/garment_store.hpp>
#include <refit/core/error.hpp>
#include <refit/core/heap.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/features/curves_obj.hpp>
#include <refit/pipeline/input_checks.hpp>
#include <refit/pipeline/resize.hpp>
#include <refit/pipeline/units.hpp>

#include <cstdio>
#include <filesystem>
#include <optional>

namespace refit::cli {
namespace {

struct ResizeArgs {
  std::string garment, from, out, out_dir, report, features, curves_out, units = "cm", stage = "full", symmetry, method = "refit";
  std::string to_list, shard;
  std::string memory_budget, temp_dir;
  std::size_t chunk_vertices = 0;
  std::vector<std::string> to;
  std::vector<std::string> to_outputs;  // with --to-list: the output of each body of `to`
  std::size_t threads = 0, max_triangles = WarpOptions{}.max_triangles;
  bool quiet = false, metrics = false, paper_closeness = false, no_shape_control = false, no_collision = false,
       encode_on_warped = false, paper_surface = false, keep_folds = false, plain_sweeps = false, v_cycles = false,
       ordered_features = false;
  SurfaceOptions surface;
  double clearance = 0.2;
  double follow_body = 0.0;
  double level_tolerance = ShapeMatchingOptions{}.level_tolerance_deg;
  PatternsOptions patterns;  // --patterns-out: the 2D patterns of each result (docs/patterns.md)
};

// A finite distance from 0 to 10 cm (the clearance, --follow-body): nan, inf or 1e6 would push the garment away (issue 17).
std::string check_clearance(const std::string& s) {
  double v = 0;
  try {
    std::size_t used = 0;
    v = std::stod(s, &used);
    if (used != s.size()) return "'" + s + "' is not a number";
  } catch (const std::exception&) {
    return "'" + s + "' is not a number";
  }
  if (!(v >= 0 && v <= 10)) return s + " is outside 0 to 10 cm";
  return {};
}

// Every file this run will write, in order: the garments (--out, or one per body
// in --out-dir), then --curves-out and --report.
std::vector<std::string> output_paths(const ResizeArgs& a) {
  std::vector<std::string> outs;
  if (!a.to_outputs.empty()) {
    outs = a.to_outputs;
  } else if (!a.out_dir.empty()) {
    for (const std::string& to : a.to)
      outs.push_back((std::filesystem::path(a.out_dir) / (std::filesystem::path(to).stem().string() + ".obj")).string());
  } else {
    outs.push_back(a.out);
  }
  if (!a.curves_out.empty()) outs.push_back(a.curves_out);
  if (!a.report.empty()) outs.push_back(a.report);
  for (const std::string& to : a.patterns.dir.empty() ? std::vector<std::string>{} : a.to)
    for (const std::string& p : pattern_paths(a.patterns.dir, std::filesystem::path(to).stem().string(), true))
      outs.push_back(p);
  return outs;
}

Stage parse_stage(const std::string& s) {
  if (s == "warp") return Stage::Warp;
  if (s == "features") return Stage::Features;
  if (s == "full") return Stage::Full;
  throw Error("--stage: unknown stage '" + s + "' (use warp, features or full)");
}

// --to-list MANIFEST [--shard I/N]: the bodies and outputs of the manifest's rows (of that shard).
void take_manifest(ResizeArgs& a) {
  if (!a.to.empty() || !a.out.empty() || !a.out_dir.empty())
    throw Error("--to-list names the bodies and their outputs: give no --to, --out or --out-dir");
  std::vector<ManifestRow> rows = read_manifest(a.to_list);
  if (!a.shard.empty()) rows = shard_rows(rows, parse_shard(a.shard));
  for (const ManifestRow& r : rows) {
    a.to.push_back(r.body);
    a.to_outputs.push_back(r.output);
    std::error_code ec;  // as --out-dir, the outputs' folders are made
    const std::filesystem::path folder = std::filesystem::path(r.output).parent_path();
    if (!folder.empty()) std::filesystem::create_directories(folder, ec);
    if (ec) throw input_error(r.output, "cannot create its folder: " + ec.message());
  }
}

// One body's resize: its report and warnings, and what writing its garment said.
struct BodyResult {
  nlohmann::json report;
  std::vector<std::string> warnings;
  ObjWriteReport written;
  FeatureResult features;
};

// What the in-memory and the chunked modes share: the bodies one after another,
// their outputs, warnings and reports.
struct Run {
  const ResizeArgs& a;
  bool batch;  // a failed body is skipped, exit 4
  const std::vector<std::string>& outs;
  const Progress& progress;
  Stopwatch& total;
  nlohmann::json garment;                 // the report's garment object
  std::vector<std::string> garment_warnings;
  double load_ms = 0.0;
  nlohmann::json bind_report;

  int bodies(const std::function<BodyResult(const BodyMesh& body_b, const std::string& out)>& resize,
             std::optional<OutputFolder>& folder) const {
    // Every output of the run appears together at its end, or none (a body that
    // fails in a batch is skipped: its files never appear).
    OutputBatch all_outputs;
    nlohmann::json reports = nlohmann::json::array();
    std::size_t failed = 0;
    Stopwatch clock;
    // A body's timings are what its `total` spent: the garment's load and the
    // binding (made once) only in the first body's report, as the Python batch reports them.
    bool setup_reported = false;
    for (std::size_t body = 0; body < a.to.size(); ++body) {
      const std::string& to = a.to[body];
      const std::string& out = outs[body];
      try {
        OutputBatch body_outputs;
        clock.reset();
        const BodyMesh body_b = read_body(to);
        const double load_b_ms = clock.ms();
        BodyResult result = resize(body_b, out);
        if (!a.curves_out.empty()) write_curves_obj(a.curves_out, result.features);
        nlohmann::json& r = result.report;
        r["timings_ms"]["load"] = (setup_reported ? 0.0 : load_ms) + load_b_ms;
        if (!setup_reported) r["timings_ms"]["bind"] = bind_report;
        r["timings_ms"]["total"] = total.ms();
        // On stderr too (not only in the report), naming the body or the output.
        for (const auto& w : result.warnings) std::fprintf(stderr, "refit: warning: %s: %s\n", to.c_str(), w.c_str());
        for (const auto& w : result.written.warnings) {
          std::fprintf(stderr, "refit: warning: %s: %s\n", out.c_str(), w.c_str());
          result.warnings.push_back(w);
        }
        if (result.written.normals_recomputed > 0)  // what the writer always does: the report says how many
          result.warnings.push_back(std::to_string(result.written.normals_recomputed) +
                                    " vn normals recomputed from the new positions");
        for (const auto& w : garment_warnings) result.warnings.push_back(w);
        r["version"] = kVersion;
        r["garment"] = garment;
        r["garment"]["file"] = a.garment;
        r["body_a"] = a.from;
        r["body_b"] = to;
        r["output"] = out;
        r["units"] = a.units;
        r["peak_memory_mb"] = peak_memory_mb();
        r["huge_pages"] = huge_pages_requested();
        r["warnings"] = result.warnings;
        reports.push_back(r);
        setup_reported = true;
        body_outputs.commit();
        progress.stage("done " + out);
        total.reset();
      } catch (const Error& e) {
        if (!batch) throw;
        ++failed;
        std::fprintf(stderr, "refit: error: %s (body skipped)\n", e.what());
        reports.push_back({{"body_b", to}, {"error", e.what()}});
      }
    }
    if (!a.report.empty()) {
      nlohmann::json doc = !batch ? reports[0] : nlohmann::json{{"version", kVersion}, {"bodies", reports}};
      write_json_report(a.report, doc);
    }
    all_outputs.commit();
    if (folder) folder->keep();
    if (failed > 0) {
      std::fprintf(stderr, "refit: %zu of %zu bodies failed\n", failed, a.to.size());
      return 4;
    }
    return 0;
  }
};

int run(ResizeArgs a) {
  Stopwatch total;
  ThreadLimit limit(a.threads);
  const Progress progress(a.quiet);
  if (!a.shard.empty() && a.to_list.empty()) throw Error("--shard needs --to-list");
  if (!a.to_list.empty()) {
    take_manifest(a);
    if (a.to.empty()) {
      progress.stage("shard " + a.shard + " of " + a.to_list + " is empty");
      return 0;
    }
  } else if (a.to.empty()) {
    throw Error("give --to BODY... or --to-list MANIFEST");
  }
  const bool batch = a.to.size() > 1 || !a.to_list.empty();  // a failed body is skipped, exit 4
  if (a.to.size() > 1 && a.out_dir.empty() && a.to_list.empty()) throw Error("several --to bodies need --out-dir DIR");
  if (a.out.empty() && a.out_dir.empty() && a.to_list.empty()) throw Error("give --out FILE or --out-dir DIR");
  if (!a.out.empty() && !a.out_dir.empty()) throw Error("give --out or --out-dir, not both");
  // --method paper: every choice the paper makes, each also a switch of its own
  // (docs/method.md); an explicit --symmetry still wins.
  const bool paper = a.method == "paper";
  ResizeOptions options;
  options.units = a.units;
  options.stage = parse_stage(a.stage);
  options.warp.max_triangles = a.max_triangles;
  options.surface = a.surface;
  options.shape_matching.sampling_invariant = !(a.paper_closeness || paper);
  options.shape_matching.joint = !(a.ordered_features || paper);
  options.shape_matching.level_tolerance_deg = paper ? 0.0 : a.level_tolerance;
  options.surface.encode_on_warped = a.encode_on_warped || paper;
  if (a.plain_sweeps || paper) options.surface.multigrid = false;
  if (a.v_cycles) options.surface.krylov = false;
  if (a.paper_surface || paper) {
    options.surface.fit_rotations = false;
    options.surface.smooth_blend = false;
    options.surface.emit_from_original = false;
    options.surface.smooth_passes = 0;
    options.surface.keep_clear_of_body = false;
    options.surface.feature_zone_rings = 0;  // no zone, no snap
    options.surface.feature_bend_radius = 0.0;
    options.surface.feature_slide_rings = 0;
    options.surface.near_body_band = 0.0;
    options.surface.layers = false;
    options.surface.follow_body_scale = false;
  }
  options.collision = !(a.no_collision || paper);
  options.smooth_folds = !a.keep_folds;
  options.symmetry = parse_symmetry(!a.symmetry.empty() ? a.symmetry : paper ? "none" : "auto");
  options.metrics = a.metrics;
  options.clearance_cm = a.clearance;
  options.follow_body_cm = a.follow_body;
  if (!a.curves_out.empty() && a.features.empty()) throw Error("--curves-out needs --features");
  if (!a.curves_out.empty() && batch) throw Error("--curves-out works with one --to body");
  if (!a.out_dir.empty()) {
    // --out-dir names each garment after its body's file: two bodies may not share a name.
    for (std::size_t i = 0; i < a.to.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (std::filesystem::path(a.to[i]).stem() == std::filesystem::path(a.to[j]).stem())
          throw Error("--out-dir: bodies " + a.to[j] + " and " + a.to[i] + " would both write " +
                      std::filesystem::path(a.to[i]).stem().string() + ".obj (rename one)");
  }
  // Every output is checked before the work; a folder made for the run goes
  // again if the run fails.
  std::optional<OutputFolder> folder, patterns_folder;
  if (!a.out_dir.empty()) folder.emplace(a.out_dir);
  if (!a.patterns.dir.empty()) patterns_folder.emplace(a.patterns.dir);
  const std::vector<std::string> outs = output_paths(a);
  std::vector<std::string> ins = {a.garment, a.from};
  ins.insert(ins.end(), a.to.begin(), a.to.end());
  if (!a.features.empty()) ins.push_back(a.features);
  check_outputs(ins, outs);

  Stopwatch clock;
  // --memory-budget: the in-memory run's limit too. Above it (or above this
  // machine's memory without one), or with --chunk-vertices, the garment is
  // resized in chunks streamed from and to disk (issue 14, docs/chunked.md).
  ChunkOptions chunking;
  if (!a.memory_budget.empty()) chunking.memory_budget = parse_size(a.memory_budget, "--memory-budget");
  chunking.chunk_vertices = a.chunk_vertices;
  chunking.temp_folder = a.temp_dir;
  options.memory_budget_mb = double(chunking.memory_budget) / (1024.0 * 1024.0);
  if (a.no_shape_control) options.stage = Stage::Warp;
  Run run{a, batch, outs, progress, total, {}, {}, 0.0, {}};
  BodyMesh body_a = read_body(a.from);
  check_human_size(body_a, units_per_cm(a.units));
  std::optional<ObjStream> obj;
  GarmentSize size;
  // The garment's sizes from its first pass when the choice needs them (a
  // budget, or a file large enough that the in-memory run might not fit).
  if (chunking.memory_budget > 0 || chunking.chunk_vertices > 0 || might_exceed_memory(a.garment)) {
    progress.stage("counting " + a.garment);
    // Under a budget the pass reads a sixteenth of it at a time (64 MB groups
    // took a 1M-vertex run under --memory-budget 100M to 141 MB).
    constexpr std::size_t kGroup = std::size_t(64) << 20;
    obj.emplace(a.garment, chunking.memory_budget > 0 ? std::clamp<std::size_t>(chunking.memory_budget / 16, 1 << 20, kGroup) : kGroup);
    size = {obj->bytes(), obj->vertex_count(), obj->face_count()};
  }
  const SurfaceOptions so = surface_options_in_units(options);
  const auto estimate_mb = [&, triangles = body_a.triangles.size()](std::size_t vertices) {
    return estimated_memory_mb(
        vertices, options.stage == Stage::Full ? estimated_agents(vertices, so.agent_budget, so.voxel) : 0.0, triangles);
  };
  const double in_memory_mb = estimate_mb(size.vertices);
  if (obj && use_chunks(size, chunking, in_memory_mb)) {
    try {
      check_chunked_options(options);
    } catch (const Error& e) {  // say why the run is chunked: the user may not have asked for it
      const std::string why = a.chunk_vertices > 0 ? "--chunk-vertices asks for the chunked mode"
                              : "its in-memory run (about " + std::to_string(long(in_memory_mb)) + " MB) is above " +
                                    (chunking.memory_budget > 0 ? "--memory-budget " + a.memory_budget : "this machine's memory") +
                                    ", so it is resized in chunks";
      throw input_error(a.garment, why + ", and " + e.what());
    }
    if (!a.patterns.dir.empty()) throw Error("--patterns-out works in memory only, not in chunks (give no --memory-budget or --chunk-vertices, or run refit flatten on the result)");
    const ChunkPlan plan = plan_chunks(size, chunking);
    progress.stage("reading " + a.garment + " into " + plan.folder.string() + " in chunks of " +
                   std::to_string(plan.chunk_vertices) + " vertices (about " + std::to_string(int(plan.estimate_mb)) +
                   " MB in all)");
    obj->set_group_bytes(plan.group_bytes);
    auto store = std::make_shared<const GarmentStore>(std::move(*obj), plan.folder);
    if (store->vertex_count() > 0) {
      Points sample;
      PointGather(store->positions(), 0).gather(depth_check_sample(store->vertex_count()), sample);
      check_garment_over_body_a(sample, store->low(), store->high(), a.garment, body_a, units_per_cm(a.units));
    }
    run.load_ms = clock.ms();
    run.garment = store->summary();
    run.garment_warnings = store->warnings();
    for (const auto& w : run.garment_warnings) std::fprintf(stderr, "refit: warning: %s\n", w.c_str());
    std::vector<FeatureSpec> features;
    if (!a.features.empty()) features = features_with_role(read_feature_file(a.features, a.units), CurveRole::shape);  // seams only cut patterns
    const ChunkedBinding binding(store, std::move(body_a), options, std::move(features), plan, progress);
    run.bind_report = binding.bind_report();
    return run.bodies(
        [&](const BodyMesh& body_b, const std::string& out) {
          ChunkedResult r = binding.resize(body_b, out, progress);
          return BodyResult{std::move(r.report), std::move(r.warnings), std::move(r.written), std::move(r.features)};
        },
        folder);
  }
  progress.stage("reading " + a.garment);
  obj.reset();
  // The file's text is read again chunk by chunk when each body is written: kept,
  // it was the largest single part of a dense garment's peak memory (bench/README.md).
  auto garment = std::make_shared<const Garment>(read_garment_obj(a.garment, SourceText::released));
  if (garment->vertex_count() > 0) {
    const std::vector<Index> ids = depth_check_sample(garment->vertex_count());
    Points sample(Eigen::Index(ids.size()), 3);
    for (std::size_t k = 0; k < ids.size(); ++k) sample.row(Eigen::Index(k)) = garment->positions.row(ids[k]);
    check_garment_over_body_a(sample, garment->positions.colwise().minCoeff().transpose(),
                              garment->positions.colwise().maxCoeff().transpose(), a.garment, body_a, units_per_cm(a.units));
  }
  run.load_ms = clock.ms();
  // The heap grown to the run's estimated peak at once, on every thread (refit/core/heap.hpp).
  // The estimate is the whole pipeline's: a run that stops short of the collision
  // step peaks far below it (the 1M dress's warp alone: 286 MB against 645).
  if (options.stage == Stage::Full && options.collision)
    grow_heap_for_run(std::size_t(estimate_mb(garment->vertex_count()) * 1024.0 * 1024.0));
  run.garment = garment_summary(*garment);
  run.garment_warnings = garment->source ? garment->source->warnings : std::vector<std::string>{};
  for (const auto& w : run.garment_warnings) std::fprintf(stderr, "refit: warning: %s\n", w.c_str());
  std::vector<FeatureSpec> features;
  if (!a.features.empty()) features = read_feature_file(a.features, a.units);
  std::optional<PatternWriter> patterns;  // cut on the original garment, once
  if (!a.patterns.dir.empty()) patterns.emplace(garment, features, a.garment, a.features, with_units(a.patterns, a.units));
  const GarmentBinding binding(garment, std::move(body_a), options, std::move(features), progress);
  run.bind_report = binding.bind_report();
  std::size_t resized = 0;
  const int status = run.bodies(
      [&](const BodyMesh& body_b, const std::string& out) {
        ResizeResult r = binding.resize(body_b, progress);
        Stopwatch write;
        if (++resized == a.to.size()) release_free_heap();  // the file's pages reuse it (refit/core/heap.hpp)
        progress.stage("writing " + out);
        ObjWriteReport written = write_garment_obj(out, *garment, r.positions);
        if (patterns) r.report["patterns"] = patterns->write(body_b.name, r.positions, true);
        r.report["timings_ms"]["write"] = write.ms();
        return BodyResult{std::move(r.report), std::move(r.warnings), std::move(written), std::move(r.features)};
      },
      folder);
  if (patterns_folder) patterns_folder->keep();
  return status;
}

// Switches that change the method or the solver: a help section of their own.
constexpr const char* kAdvanced = "Advanced (method switches and solver internals; docs/method.md)";

const Register resize_command("resize", "Resize a garment from body A to one or many bodies B", [](CLI::App& app) {
  auto a = std::make_shared<ResizeArgs>();
  app.add_option("--garment", a->garment, "Garment OBJ around body A")->required();
  app.add_option("--from", a->from, "Body A (OBJ, PLY, OFF or STL)")->required();
  app.add_option("--to", a->to, "Body B, or several bodies B (then use --out-dir)")->expected(1, -1);
  app.add_option("--to-list", a->to_list,
                 "Manifest CSV: body file, output file, optional name per row (instead of --to and --out)");
  app.add_option("--shard", a->shard, "With --to-list: only the I-th of N slices of the manifest, I from 0 (job arrays)")
      ->check(check_shard);
  app.add_option("--out", a->out, "Output OBJ (one body)");
  app.add_option("--out-dir", a->out_dir, "Output folder: writes DIR/<body-name>.obj per body");
  app.add_option("--report", a->report, "Write a JSON report");
  app.add_option("--units", a->units, "Garment units: cm, mm, m or in")
      ->check(CLI::IsMember({"cm", "mm", "m", "in"}))
      ->capture_default_str();
  app.add_option("--stage", a->stage, "Stop after: warp, features or full")->capture_default_str();
  app.add_option("--threads", a->threads, "Worker threads (0 = all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  app.add_option("--max-triangles", a->max_triangles, "Cap on the warp's triangle set per vertex")->capture_default_str()
      ->group(kAdvanced);
  app.add_option("--features", a->features, "Feature curves (JSON) whose shape must survive");
  app.add_option("--method", a->method,
                 "refit: Refit's choices; paper: the paper's (curves in order, plain feature sums, encoding on the warp, fan frames, "
                 "eq. 4 blend, no zone, layers, smoothing, symmetry or collision, Gauss-Seidel sweeps; docs/method.md)")
      ->check(CLI::IsMember({"refit", "paper"}))
      ->capture_default_str();
  app.add_option("--patterns-out", a->patterns.dir,
                 "Folder for each result's 2D patterns and grading view against the original (BODY.svg, .dxf, .json, "
                 "-grading.svg; seam curves of --features cut; docs/patterns.md)");
  add_pattern_options(app, a->patterns, "Advanced patterns (--patterns-out; docs/patterns.md)", "Patterns (with --patterns-out)");
  app.add_option("--curves-out", a->curves_out, "Write original, warped and optimised feature curves (OBJ l lines)");
  app.add_flag("--paper-closeness", a->paper_closeness,
               "Feature closeness term as the paper's plain sums (weak: keeps most of the warp's bend)")
      ->group(kAdvanced);
  app.add_flag("--ordered-features", a->ordered_features,
               "Feature curves one at a time in file order, a later curve's crossings fixed where an earlier one put "
               "them (the paper) instead of all curves in one solve sharing their meeting samples")
      ->group(kAdvanced);
  app.add_flag("--no-shape-control", a->no_shape_control, "The warp alone (same as --stage warp)");
  app.add_option("--voxel", a->surface.voxel, "Agent voxel size in cm (0 = from the garment size and --agents)")
      ->capture_default_str()
      ->group(kAdvanced);
  app.add_option("--agents", a->surface.agent_budget, "Agent budget for the automatic voxel size")->capture_default_str()
      ->group(kAdvanced);
  app.add_option("--epsilon", a->surface.epsilon, "Agents closer than this to body B (cm) keep their warped position")
      ->capture_default_str()
      ->group(kAdvanced);
  app.add_option("--near-body-band", a->surface.near_body_band,
                 "On a piece with features that mostly hangs off the body, agents within --epsilon of body B are "
                 "solved with the rest and held only where they would stand more than this (cm) farther off body B "
                 "than the warp puts them (0 = the paper's eq. 14 everywhere: held at the warp)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber)
      ->group(kAdvanced);
  app.add_option("--feature-zone", a->surface.feature_zone_rings,
                 "Within this many one-ring steps of a feature, the feature wins over --epsilon and the garment is "
                 "snapped through it (0 = the paper: --epsilon everywhere but on the features)")
      ->capture_default_str()
      ->check(CLI::Range(0, 16))
      ->group(kAdvanced);
  app.add_option("--zone-edge-blend", a->surface.zone_edge_blend,
                 "Where the feature zone meets the vertices kept at the warp near body B, a vertex takes the warp by "
                 "its blend's share outside the zone, eased over shares 0.5 +- this (0 = all or nothing by its nearest "
                 "agent: a cliff one edge wide on a fine mesh)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.5))
      ->group(kAdvanced);
  app.add_option("--feature-slide", a->surface.feature_slide_rings,
                 "Within this many one-ring steps of a feature, the agents --epsilon holds at the warp are solved with "
                 "the rest, kept no farther off body B than the warp, and keep a share of that fading to 0 at this "
                 "many steps, so the surface beside a feature slopes into the held part (0 = held at the warp, as "
                 "before; docs/method.md)")
      ->capture_default_str()
      ->check(CLI::Range(0, 64))
      ->group(kAdvanced);
  app.add_option("--snap-radius", a->surface.snap_radius,
                 "The snap through the features moves the vertices within this many voxels of each feature sample "
                 "(0 = through the reconstruction's blend weights, which can miss a sample's own corners)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 16.0))
      ->group(kAdvanced);
  app.add_option("--snap-remainder", a->surface.snap_remainder_share,
                 "The snap's passes after the first reach this share of --snap-radius only (at least three times the "
                 "farthest corner of each sample's face; 1 = every pass the whole radius, as before 2026-11-29: on a "
                 "fine mesh that alternates along the curve)")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 1.0))
      ->group(kAdvanced);
  app.add_option("--feature-bend", a->surface.feature_bend_radius,
                 "Within about this distance of a feature (cm) the surface is solved again so that it leaves the "
                 "feature with the feature's slope instead of a crease (0 = off: the paper's eq. 13 alone; docs/method.md)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0))
      ->group(kAdvanced);
  app.add_flag("--no-layers", [a](std::int64_t) { a->surface.layers = false; },
               "One agent per voxel for the whole garment, as the paper (by default each layer of a multi-layer "
               "garment gets its own agents, rings and blends)")
      ->group(kAdvanced);
  app.add_option("--max-iterations", a->surface.max_iterations, "Gauss-Seidel iterations, at most")->capture_default_str()
      ->group(kAdvanced);
  app.add_option("--tolerance", a->surface.tolerance, "Gauss-Seidel stops below this update norm (cm)")->capture_default_str()
      ->group(kAdvanced);
  app.add_option("--tolerance-rms", a->surface.tolerance_rms,
                 "If positive: stop when the update's RMS per free agent is below this (cm; instead of --tolerance on its L2 norm)")
      ->capture_default_str()
      ->group(kAdvanced);
  app.add_flag("--plain-sweeps", a->plain_sweeps,
               "The paper's plain Gauss-Seidel sweeps instead of multigrid cycles (same solution when both converge)")
      ->group(kAdvanced);
  app.add_flag("--v-cycles", a->v_cycles,
               "Bare multigrid V-cycles instead of BiCGSTAB preconditioned by them (same solution when both converge)")
      ->group(kAdvanced);
  app.add_flag("--encode-on-warped", a->encode_on_warped, "Encode the local shape on the warped garment, not the original")
      ->group(kAdvanced);
  app.add_flag("--absolute-size", [a](std::int64_t) { a->surface.follow_body_scale = false; },
               "Keep the garment's original absolute size between the features (the paper's encoding) instead of "
               "following the body's change of size and proportions")
      ->group(kAdvanced);
  app.add_flag("--paper-surface", a->paper_surface,
               "Surface step as the paper: fan-normal frames, eq. 4 blend of the warped vertices, no smoothing, no layers, "
               "absolute size, --feature-zone 0, --feature-bend 0, --near-body-band 0")
      ->group(kAdvanced);
  app.add_option("--symmetry", a->symmetry,
                 "auto: mirror each one-sided feature about x = c when garment and body A are mirror-symmetric; "
                 "x: always; none: never (default: auto; none with --method paper; docs/features.md)");
  app.add_flag("--no-collision", a->no_collision, "Do not push vertices inside body B out");
  app.add_flag("--keep-folds", a->keep_folds,
               "In the collision step, leave the faces the warp folded over (under the arms of a dense garment) as they are "
               "instead of smoothing them out first (docs/method.md)")
      ->group(kAdvanced);
  app.add_option("--clearance", a->clearance, "Collision clearance outside body B in cm (0 to 10)")
      ->check(check_clearance)
      ->capture_default_str();
  app.add_option("--follow-body", a->follow_body,
                 "Feature curve samples that sat within this of body A (cm, e.g. 1) keep their distance to body B, "
                 "so a fitted part follows the body; 0: the curves keep their shape there too (docs/method.md)")
      ->check(check_clearance)
      ->capture_default_str()
      ->group(kAdvanced);
  app.add_option("--level-tolerance", a->level_tolerance,
                 "A feature curve whose plane lies within this many degrees of level on body A (a hem, a waistline) "
                 "stays level on body B instead of taking the warp's tilt; 0: off (docs/method.md)")
      ->check(CLI::Range(0.0, 45.0))
      ->capture_default_str()
      ->group(kAdvanced);
  app.add_flag("--metrics", a->metrics, "Add fit, penetration and surface metrics of the warp and the result to the report");
  app.add_option("--memory-budget", a->memory_budget,
                 "Memory a run may use (e.g. 800M, 1G): above it the garment is resized in chunks streamed from and to "
                 "disk, with the same output (docs/chunked.md)");
  app.add_option("--chunk-vertices", a->chunk_vertices, "Resize in chunks of this many vertices (testing the chunked mode)")
      ->check(CLI::Range(std::size_t(1), std::size_t(1) << 40))
      ->group(kAdvanced);
  app.add_option("--temp-dir", a->temp_dir, "Folder for the chunked mode's temporary files (default: the system's)");
  app.add_flag("--quiet", a->quiet, "No progress on stderr");
  return [a]() { return run(*a); };
});

}  // namespace
}  // namespace refit::cli
