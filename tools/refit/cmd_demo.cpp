// `refit demo`: the built-in example end to end. A procedural mannequin pair
// (body B has a belly and wider hips, the case a loose dress copies wrongly), an
// A-line dress with its side, front and back profiles and hem as features;
// resized with the warp alone and with the full pipeline, everything written
// to one folder.
#include "body_options.hpp"
#include "command.hpp"
#include "report_file.hpp"

#include <refit/core/parallel.hpp>
#include <refit/features/curves_obj.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/metrics/render.hpp>
#include <refit/pipeline/resize.hpp>

#include <cstdio>
#include <filesystem>

namespace refit::cli {
namespace {

struct DemoArgs {
  std::string out_dir = "refit-demo";
  std::size_t vertices = 40000, threads = 0;
  bool quiet = false;
  mannequin::BodyParams body_b;
  DemoArgs() {
    body_b.belly = 6;
    body_b.hip = 104;
    body_b.waist = 76;
    body_b.bust = 92;
  }
};

int run(const DemoArgs& a) {
  ThreadLimit limit(a.threads);
  const Progress progress(a.quiet);
  namespace fs = std::filesystem;
  // The files appear one by one (the demo reads back what it wrote, as `refit
  // resize` would); each is checked before the work.
  OutputFolder folder(a.out_dir);
  const auto path = [&](const std::string& name) { return (fs::path(a.out_dir) / name).string(); };
  std::vector<std::string> outs;
  for (const char* name : {"body_A.obj", "body_B.obj", "dress_on_A.obj", "dress_features.json", "dress_on_B_warp_only.obj",
                           "dress_on_B.obj", "dress_curves.obj", "report.json", "before_after.png", "design_on_A.png"})
    outs.push_back(path(name));
  check_outputs({}, outs);

  progress.stage("generating the mannequins and the dress");
  const mannequin::BodyParams body_a;
  mannequin::GarmentParams dress;
  dress.target_vertices = a.vertices;
  write_body_obj(path("body_A.obj"), mannequin::make_body(body_a));
  write_body_obj(path("body_B.obj"), mannequin::make_body(a.body_b));
  write_garment_obj(path("dress_on_A.obj"), mannequin::make_garment(body_a, dress));
  const std::string features_json = mannequin::dress_features_json(body_a, dress);
  write_file_atomically(path("dress_features.json"), [&](std::ostream& out) { out << features_json; });

  // From here on the demo is what `refit resize` does with those files.
  auto garment = std::make_shared<const Garment>(read_garment_obj(path("dress_on_A.obj")));
  ResizeOptions options;
  options.metrics = true;
  const GarmentBinding binding(garment, read_body(path("body_A.obj")), options,
                               read_feature_file(path("dress_features.json")), progress);
  const BodyMesh body_b = read_body(path("body_B.obj"));
  ResizeResult result = binding.resize(body_b, progress);

  Garment out = *garment;
  out.positions = result.warped;
  write_garment_obj(path("dress_on_B_warp_only.obj"), out);
  out.positions = result.positions;
  write_garment_obj(path("dress_on_B.obj"), out);
  write_curves_obj(path("dress_curves.obj"), result.features);
  result.report["version"] = kVersion;
  result.report["garment"] = garment_summary(*garment);
  result.report["peak_memory_mb"] = peak_memory_mb();
  result.report["warnings"] = result.warnings;
  write_json_report(path("report.json"), result.report);

  // Pictures: the design on body A; then on body B the warp alone (left, with the
  // optimised feature curves drawn where the profiles should be) beside Refit's result (right).
  progress.stage("rendering pictures");
  RenderOptions views;
  views.width = 1200;
  views.height = 800;
  views.views = {View::front, View::side};
  std::vector<Points> curves;
  for (const CurveResult& c : result.features.curves) curves.push_back(c.optimised);
  Garment warp_only = *garment;
  warp_only.positions = result.warped;
  views.labels = {"warp alone (curves: where Refit puts the features)", "Refit"};
  char title[160];
  std::snprintf(title, sizeof title, "procedural dress on body_B (belly %+g cm, hip %g cm)", a.body_b.belly, a.body_b.hip);
  views.title = title;
  write_png(path("before_after.png"), render(body_b, warp_only, &out, curves, views));
  views.width = 600;
  views.labels = {};
  views.title = "the design on body_A";
  write_png(path("design_on_A.png"), render(binding.body_a().mesh(), *garment, nullptr, {}, views));

  folder.keep();
  std::printf("refit demo: dress of %zu vertices resized from body_A to body_B (belly %+g cm, hip %g cm)\n",
              garment->vertex_count(), a.body_b.belly, a.body_b.hip);
  std::printf("  %-16s %14s %14s %14s\n", "feature", "error (warp)", "error (curve)", "error (output)");
  for (const auto& f : result.report["features"])
    std::printf("  %-16s %14.5f %14.5f %14.5f\n", f["name"].get<std::string>().c_str(),
                f["shape_error_warped"].get<double>(), f["shape_error_result"].get<double>(),
                f.value("shape_error_output", 0.0));
  std::printf("  (shape error: RMS distance to the original curve after the best similarity, / curve length)\n");
  const auto& m = result.report["metrics"];
  std::printf("  vertices inside body B: warp %zu, result %zu\n", m["warp"]["penetration"].value("inside", std::size_t{0}),
              m["result"]["penetration"].value("inside", std::size_t{0}));
  std::printf("output: %s (dress_on_B.obj, dress_on_B_warp_only.obj, before_after.png, report.json, ...)\n",
              fs::absolute(a.out_dir).c_str());
  return 0;
}

const Register demo_command("demo", "Generate the built-in example (mannequin pair and dress), resize it and write everything",
                   [](CLI::App& app) {
                     auto a = std::make_shared<DemoArgs>();
                     app.add_option("--out-dir", a->out_dir, "Output folder")->capture_default_str();
                     app.add_option("--vertices", a->vertices, "Dress vertex count (approximate)")->capture_default_str();
                     add_body_options(app, a->body_b, "b-");
                     app.add_option("--threads", a->threads, "Worker threads (0 = all cores)")
                         ->check(CLI::Range(0, 1024))
                         ->capture_default_str();
                     app.add_flag("--quiet", a->quiet, "No progress on stderr");
                     return [a]() { return run(*a); };
                   });

}  // namespace
}  // namespace refit::cli
