// `refit compare`: scores any resize result with the garment's vertex order
// (Refit's or another tool's) with every metric of the metrics module.
#include "command.hpp"
#include "report_file.hpp"

#include <refit/core/error.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/metrics/metrics.hpp>

#include <cstdio>
#include <memory>

namespace refit::cli {
namespace {

struct CompareArgs {
  std::string garment, from, to, result, features, report;
  double fit_band = 1.0;
};

int run(const CompareArgs& a) {
  if (!a.report.empty()) check_outputs({a.garment, a.from, a.to, a.result, a.features}, {a.report});  // before the work
  const Garment garment = read_garment_obj(a.garment);
  const Garment result = read_garment_obj(a.result);
  if (result.positions.rows() != garment.positions.rows())
    throw input_error(a.result, "has " + std::to_string(result.positions.rows()) + " vertices but the garment " +
                                    a.garment + " has " + std::to_string(garment.positions.rows()) +
                                    ": compare needs the same vertex order");
  const BodyMesh body_a = read_body(a.from);
  const BodyMesh body_b = read_body(a.to);
  check_same_connectivity(body_a, body_b);
  MetricsOptions options;
  options.fit_band = a.fit_band;
  if (!a.features.empty())
    options.features =
        feature_curve_inputs(garment, result.positions, body_a, body_b, read_feature_file(a.features, "cm"));
  const ResizeMetrics m = compute_metrics(garment, result.positions, body_a, body_b, options);

  std::printf("vertices      %zu\n", m.vertices);
  std::printf("fit           %zu vertices within %g of A: distance change mean %+.4f, mean |.| %.4f, max |.| %.4f\n",
              m.fit.vertices, m.fit.band, m.fit.mean_change, m.fit.mean_abs_change, m.fit.max_abs_change);
  std::printf("penetration   %zu inside B (%.3f%%), deepest %.4f\n", m.penetration.inside,
              100.0 * m.penetration.fraction, m.penetration.deepest);
  std::printf("sanity        %zu NaN vertices, %zu of %zu faces flipped, edge ratio p1 %.4f p50 %.4f p99 %.4f\n",
              m.sanity.nan_vertices, m.sanity.flipped_faces, m.sanity.faces_checked, m.sanity.edge_ratio_p1,
              m.sanity.edge_ratio_p50, m.sanity.edge_ratio_p99);
  for (const auto& f : m.features) {
    std::printf("feature %-20s result: shape %.5f turn %.3f deg straight %.5f", f.name.c_str(), f.result.shape_error,
                f.result.turning_change_deg, f.result.straightness);
    if (f.has_warp)
      std::printf(" | warp: shape %.5f turn %.3f deg straight %.5f", f.warp.shape_error, f.warp.turning_change_deg,
                  f.warp.straightness);
    std::printf("\n");
  }
  if (!a.report.empty()) {
    nlohmann::json doc = m.to_json();
    doc["inputs"] = {{"garment", a.garment}, {"from", a.from}, {"to", a.to}, {"result", a.result}, {"features", a.features}};
    write_json_report(a.report, doc);
  }
  return 0;
}

const Register compare_command("compare", "score a resize result (any tool's, same vertex order) against the garment and bodies",
                   [](CLI::App& app) -> std::function<int()> {
                     auto args = std::make_shared<CompareArgs>();
                     app.add_option("--garment", args->garment, "garment OBJ on body A")->required();
                     app.add_option("--from", args->from, "body A")->required();
                     app.add_option("--to", args->to, "body B")->required();
                     app.add_option("--result", args->result, "resized garment OBJ (same vertex order)")->required();
                     app.add_option("--features", args->features, "feature file (JSON) to score feature curves");
                     app.add_option("--report", args->report, "write the metrics as JSON here");
                     app.add_option("--fit-band", args->fit_band, "fit: vertices within this distance of A (default 1)");
                     return [args] { return run(*args); };
                   });

}  // namespace
}  // namespace refit::cli
