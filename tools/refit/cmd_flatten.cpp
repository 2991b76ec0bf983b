// `refit flatten --garment G.obj --out-dir DIR [--features F.json] [--original G0.obj]`:
// the garment's 2D pattern pieces (engine/refit/patterns; docs/patterns.md) as
// SVG, DXF and a JSON report; with --original, the grading view of G against
// the garment it was resized from (same connectivity), cut and featured on G0.
#include "command.hpp"
#include "patterns_output.hpp"

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/obj_garment.hpp>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace refit::cli {
namespace {

struct FlattenArgs {
  std::string garment, original, features, name;
  PatternsOptions out;
  std::size_t threads = 0;
  bool quiet = false;
};

void check_same_elements(const Garment& a, const Garment& b, const std::string& file) {
  if (a.vertex_count() != b.vertex_count() || a.faces.offsets != b.faces.offsets ||
      !std::equal(a.faces.indices.begin(), a.faces.indices.end(), b.faces.indices.begin(), b.faces.indices.end()))
    throw input_error(file, "not the same garment as --original (the vertices and faces must match)");
}

int run(const FlattenArgs& a) {
  ThreadLimit limit(a.threads);
  const std::string name = a.name.empty() ? std::filesystem::path(a.garment).stem().string() : a.name;
  std::vector<std::string> ins = {a.garment};
  if (!a.original.empty()) ins.push_back(a.original);
  if (!a.features.empty()) ins.push_back(a.features);
  OutputFolder folder(a.out.dir);  // goes again if the run fails
  check_outputs(ins, pattern_paths(a.out.dir, name, !a.original.empty()));

  std::vector<FeatureSpec> specs;
  if (!a.features.empty()) specs = read_feature_file(a.features, a.out.units);
  auto garment = std::make_shared<const Garment>(read_garment_obj(a.garment));
  std::shared_ptr<const Garment> original = garment;
  if (!a.original.empty()) {
    original = std::make_shared<const Garment>(read_garment_obj(a.original));
    check_same_elements(*original, *garment, a.garment);
  }
  const PatternWriter writer(original, specs, a.original.empty() ? a.garment : a.original, a.features, a.out);
  const nlohmann::json summary = writer.write(name, garment->positions, !a.original.empty());
  folder.keep();
  for (const auto& w : summary["warnings"]) std::fprintf(stderr, "refit: warning: %s\n", w.get<std::string>().c_str());
  if (!a.quiet) {
    std::printf("%zu panels, stretch p95 %.4f, seam mismatch max %.4f\n", writer.cut().panels.panels.size(),
                summary["stretch_p95"].get<double>(), summary["seam_mismatch_max"].get<double>());
    const PatternCut& cut = writer.cut();
    for (std::size_t k = 0; k < cut.panels.panels.size(); ++k) {
      std::string lengths;
      std::size_t count = 0;
      for (const Dart& d : cut.darts)
        if (d.panel == k) {
          char buf[32];
          std::snprintf(buf, sizeof buf, "%s%.1f", count++ ? ", " : "", d.length_3d);
          lengths += buf;
        }
      if (count > 0)
        std::printf("%s: %zu dart%s, %s %s long\n", cut.panels.panels[k].name.c_str(), count, count > 1 ? "s" : "",
                    lengths.c_str(), a.out.units.c_str());
    }
    for (const auto& key : {"svg", "dxf", "report", "grading_svg"})
      if (summary.contains(key)) std::printf("wrote %s\n", summary[key].get<std::string>().c_str());
  }
  return 0;
}

const Register flatten_command("flatten", "Flatten a garment into 2D pattern pieces: SVG, DXF and a JSON report", [](CLI::App& app) {
  auto a = std::make_shared<FlattenArgs>();
  app.add_option("--garment", a->garment, "Garment OBJ to flatten")->required();
  app.add_option("--out-dir", a->out.dir, "Output folder: NAME.svg, NAME.dxf, NAME.json (NAME-grading.svg)")->required();
  app.add_option("--features", a->features, "Feature file: seam curves cut, shape curves are drawn as internal lines");
  app.add_option("--original", a->original,
                 "The garment before resizing (same vertices and faces): adds the grading view; cuts and features are "
                 "placed on it");
  app.add_option("--name", a->name, "Base name of the output files (default: the garment file's name)");
  app.add_option("--units", a->out.units, "Garment units: cm, mm, m or in (the DXF keeps them)")
      ->check(CLI::IsMember({"cm", "mm", "m", "in"}))
      ->capture_default_str();
  add_pattern_options(app, a->out, "Advanced (the flattening; docs/patterns.md)");
  app.add_option("--threads", a->threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024))->capture_default_str();
  app.add_flag("--quiet", a->quiet, "Print nothing on success");
  return [a]() { return run(*a); };
});

}  // namespace
}  // namespace refit::cli
