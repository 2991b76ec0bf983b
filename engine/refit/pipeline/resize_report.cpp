// The parts of a resize report that the in-memory and the chunked pipelines share.
#include <refit/pipeline/resize_report.hpp>

#include <refit/features/curve_metrics.hpp>

namespace refit {

Points concat_rows(const std::vector<const Points*>& parts) {
  Eigen::Index n = 0;
  for (const Points* p : parts) n += p->rows();
  Points out(n, 3);
  Eigen::Index r = 0;
  for (const Points* p : parts) {
    out.middleRows(r, p->rows()) = *p;
    r += p->rows();
  }
  return out;
}

nlohmann::json symmetry_report(const SymmetryCheck& sym) {
  return {{"plane_x", sym.plane_x},          {"garment_error", sym.garment_error},
          {"body_a_error", sym.body_error},  {"tolerance", sym.tolerance},
          {"symmetric", sym.symmetric},      {"mirrored_features", nlohmann::json::array()}};
}

nlohmann::json surface_report(const SurfaceStats& s) {
  return {{"agents", s.agents},
          {"garment_agents", s.garment_agents},
          {"feature_agents", s.feature_agents},
          {"layers", s.layers},
          {"voxel", s.voxel},
          {"voxel_auto", s.voxel_was_auto},
          {"one_ring_degree_mean", s.ring_degree_mean},
          {"one_ring_degree_max", s.ring_degree_max},
          {"fixed_body", s.fixed_body},
          {"fixed_feature", s.fixed_feature},
          {"fixed_clearance", s.fixed_clearance},
          {"banded", s.banded},
          {"feature_slid", s.feature_slid},
          {"fixed_band", s.fixed_band},
          {"feature_bend_agents", s.feature_bend_agents},
          {"feature_bend_rings", s.feature_bend_rings},
          {"feature_bend_rounds", s.feature_bend_rounds},
          {"clearance_rounds", s.clearance_rounds},
          {"anchored", s.anchored},
          {"anchored_groups", s.anchored_groups},
          {"anchored_followed", s.anchored_followed},
          {"iterations", s.iterations},
          {"final_update", s.final_update},
          {"converged", s.converged},
          {"vertices_without_agent", s.vertices_without_agent},
          {"vertices_kept_near_body", s.vertices_kept},
          {"feature_zone_agents", s.feature_zone_agents},
          {"feature_gap_before_snap", s.feature_gap_before_snap},
          {"feature_gap", s.feature_gap},
          {"vertices_snapped", s.vertices_snapped},
          {"levels", s.levels},
          {"coarse_iterations", s.coarse_iterations},
          {"krylov_iterations", s.krylov_iterations},
          {"residual_reduction", s.reduction},
          {"tolerance", s.tolerance},
          {"timings_ms",
           {{"sample", s.ms.sample},
            {"agents", s.ms.agents},
            {"one_ring", s.ms.one_ring},
            {"encode", s.ms.encode},
            {"solve", s.ms.solve},
            {"reconstruct", s.ms.reconstruct}}}};
}

void report_written_features(const FeatureResult& curves, const Points& on_result, const Points& on_warp,
                             const Points& before_collision, nlohmann::json& report) {
  auto& list = report["features"];
  Eigen::Index first = 0;
  double gap = 0.0;
  for (std::size_t i = 0; i < curves.curves.size(); ++i) {
    const CurveResult& c = curves.curves[i];
    const Eigen::Index m = c.original.rows();
    list[i]["shape_error_output"] = shape_error(on_result.middleRows(first, m), c.original, c.closed);
    list[i]["shape_error_output_before_collision"] = shape_error(before_collision.middleRows(first, m), c.original, c.closed);
    // The same measure on the warped garment: on a coarse mesh, carrying samples
    // on its faces adds faceting that the free-point warp of the samples has not.
    list[i]["shape_error_output_warped"] = shape_error(on_warp.middleRows(first, m), c.original, c.closed);
    Eigen::Index worst = 0;
    const double curve_gap = (on_result.middleRows(first, m) - c.optimised).rowwise().norm().maxCoeff(&worst);
    list[i]["gap_output"] = curve_gap;
    list[i]["gap_output_sample"] = worst;
    list[i]["gap_output_before_collision"] = (before_collision.middleRows(first, m) - c.optimised).rowwise().norm().maxCoeff();
    gap = std::max(gap, curve_gap);
    first += m;
  }
  report["surface"]["feature_gap_written"] = gap;
}

nlohmann::json features_report(const FeatureResult& curves) {
  nlohmann::json list = nlohmann::json::array();
  for (const CurveResult& c : curves.curves) {
    nlohmann::json fixed = nlohmann::json::array();
    for (const FixedSample& f : c.fixed) fixed.push_back({{"index", f.index}, {"reason", f.reason}, {"distance", f.distance}});
    nlohmann::json crossings = nlohmann::json::array();
    for (const FixedSample& f : c.crossings) crossings.push_back({{"index", f.index}, {"distance", f.distance}});
    nlohmann::json cleared = nlohmann::json::array();
    for (const FixedSample& f : c.cleared) cleared.push_back({{"index", f.index}, {"moved", f.distance}});
    nlohmann::json followed = nlohmann::json::array();
    for (const FixedSample& f : c.followed) followed.push_back({{"index", f.index}, {"moved", f.distance}});
    list.push_back({{"name", c.name},
                    {"samples", c.original.rows()},
                    {"closed", c.closed},
                    {"fixed", fixed},
                    {"crossings", crossings},
                    {"cleared", cleared},
                    {"followed", followed},
                    {"placed", c.placed},
                    {"level", c.level},
                    {"scale_warped", c.scale_warped},
                    {"scale_result", c.scale_result},
                    {"shape_error_warped", c.shape_error_warped},
                    {"shape_error_result", c.shape_error_result},
                    {"turning_angle_change_warped_deg", c.turning_angle_change_warped_deg},
                    {"turning_angle_change_result_deg", c.turning_angle_change_result_deg}});
  }
  return list;
}

}  // namespace refit
