// `refit inspect FILE.obj`: element counts and topology of a garment (counts,
// unreferenced vertices, edges, boundary and non-manifold edges, boundary loops,
// connected components, and the layers the surface step finds at the default
// agent budget), as `name: value` lines or, with --json, one JSON object.
#include "command.hpp"

#include <refit/core/topology.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/patterns/pattern.hpp>
#include <refit/patterns/report.hpp>
#include <refit/surface/surface.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace {

struct InspectOptions {
  std::string file, features, units = "cm";
  bool json = false;
};

const refit::cli::Register inspect_command(
    "inspect", "Print the element counts and topology of a garment OBJ", [](CLI::App& app) {
      auto opt = std::make_shared<InspectOptions>();
      app.add_option("file", opt->file, "Garment OBJ file")->required();
      app.add_flag("--json", opt->json, "Print one JSON object instead of 'name: value' lines");
      app.add_option("--features", opt->features, "Feature file whose seam curves also cut the panels");
      app.add_option("--units", opt->units, "Garment units (for the feature file)")->capture_default_str();
      return [opt]() -> int {
        const std::vector<refit::FeatureSpec> specs =
            opt->features.empty() ? std::vector<refit::FeatureSpec>{} : refit::read_feature_file(opt->features, opt->units);
        const refit::Garment g = refit::read_garment_obj(opt->file);
        // Pattern pieces as `refit flatten` cuts them (docs/patterns.md).
        const refit::PatternCut cut = refit::cut_pattern(g, specs, opt->file, opt->features);
        const refit::TopologyStats s = refit::topology_stats(g);
        // Layers as `refit resize` sees them (default agent budget): pieces with
        // their own agents; vertices on none (points, lines, small pieces) are loose.
        const refit::SurfaceOptions so;
        const std::vector<std::uint32_t> layer =
            g.vertex_count() > 0 ? refit::surface_layers(g, so, refit::surface_voxel(g, so)) : std::vector<std::uint32_t>{};
        const std::size_t layers = layer.empty() ? 0 : *std::max_element(layer.begin(), layer.end());
        const std::size_t loose = static_cast<std::size_t>(std::count(layer.begin(), layer.end(), 0u));
        const std::vector<std::pair<const char*, std::size_t>> rows = {
            {"vertices", s.vertices},
            {"faces", s.faces},
            {"lines", s.lines},
            {"points", s.points},
            {"unreferenced_vertices", s.unreferenced_vertices},
            {"edges", s.edges},
            {"boundary_edges", s.boundary_edges},
            {"non_manifold_edges", s.non_manifold_edges},
            {"boundary_loops", s.boundary_loops},
            {"components", s.components},
            {"layers", layers},
            {"loose_vertices", loose},
            {"panels", cut.panels.panels.size()},
        };
        if (opt->json) {
          nlohmann::ordered_json j;
          j["file"] = opt->file;
          for (const auto& [name, value] : rows) j[name] = value;
          nlohmann::ordered_json panels = nlohmann::ordered_json::array();
          for (const refit::Panel& p : cut.panels.panels) {
            nlohmann::ordered_json jp = {{"name", p.name}, {"faces", p.faces.size()}, {"vertices", p.vertices.size()},
                                         {"boundary_loops", p.loops.size()}};
            if (!p.problem.empty()) jp["problem"] = p.problem;
            panels.push_back(jp);
          }
          j["panel_list"] = panels;
          std::printf("%s\n", j.dump(2).c_str());
        } else {
          for (const auto& [name, value] : rows) std::printf("%s: %zu\n", name, value);
          for (const std::string& line : refit::panel_lines(cut)) std::printf("panel %s\n", line.c_str());
        }
        if (g.source)
          for (const std::string& w : g.source->warnings) std::fprintf(stderr, "refit: warning: %s\n", w.c_str());
        return 0;
      };
    });

}  // namespace
