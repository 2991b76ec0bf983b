// `refit features --garment G.obj --features F.json --out C.obj [--units cm]`:
// samples every feature curve on the original garment and writes them as OBJ
// polylines (group `<name>_original`), so a feature file can be checked before
// resizing. Any invalid feature: one error line naming it, exit 1, nothing written.
#include "command.hpp"

#include <refit/features/curves_obj.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/obj_garment.hpp>

#include <cstdio>
#include <memory>
#include <string>

namespace {

struct FeaturesOptions {
  std::string garment, features, out, units = "cm";
};

const refit::cli::Register features_command(
    "features", "Sample the feature curves of a feature file on a garment and write them as OBJ polylines",
    [](CLI::App& app) {
      auto opt = std::make_shared<FeaturesOptions>();
      app.add_option("--garment", opt->garment, "Garment OBJ file")->required();
      app.add_option("--features", opt->features, "Feature file (JSON)")->required();
      app.add_option("--out", opt->out, "Output OBJ with one polyline per feature")->required();
      app.add_option("--units", opt->units, "Units of the garment: cm, mm, m or in")->capture_default_str();
      return [opt]() -> int {
        refit::check_outputs({opt->garment, opt->features}, {opt->out});  // before the work
        // Parse the feature file first: its errors need no garment.
        const auto specs = refit::read_feature_file(opt->features, opt->units);
        const refit::Garment g = refit::read_garment_obj(opt->garment);
        const auto curves = refit::build_feature_curves(g, specs);
        refit::write_curves_obj(opt->out, curves);
        for (const auto& c : curves)
          std::printf("%s: %zu samples, %s, length %.4g\n", c.name.c_str(), c.size(), c.closed ? "closed" : "open",
                      c.spacing() * static_cast<double>(c.closed ? c.size() : c.size() - 1));
        return 0;
      };
    });

}  // namespace
