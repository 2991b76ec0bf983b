#include <refit/core/error.hpp>
#include <refit/pipeline/resize.hpp>
#include <refit/pipeline/units.hpp>

namespace refit {

nlohmann::json garment_summary(const Garment& g) {
  return {{"vertices", g.vertex_count()},
          {"faces", g.faces.rows()},
          {"lines", g.lines.rows()},
          {"points", g.points.rows()}};
}

GarmentBinding::GarmentBinding(std::shared_ptr<const Garment> garment, BodyMesh body_a, ResizeOptions options,
                               const Progress& progress)
    : garment_(std::move(garment)), options_(std::move(options)), body_a_((check_body(body_a), std::move(body_a)), options_.warp) {
  units_per_cm(options_.units);  // validates the unit name
  if (garment_->vertex_count() == 0) throw Error("garment: empty garment (no vertices)");
  Stopwatch clock;
  progress.stage("binding " + std::to_string(garment_->vertex_count()) + " garment vertices to " + body_a_.mesh().name);
  warp_ = body_a_.bind(garment_->positions);
  bind_ms_ = clock.ms();
}

ResizeResult GarmentBinding::resize(const BodyMesh& body_b, const Progress& progress) const {
  check_body(body_b);
  check_same_connectivity(body_a_.mesh(), body_b);
  ResizeResult result;
  nlohmann::json& timings = result.report["timings_ms"];
  Stopwatch clock;

  // Step 1: primary resizing (section 3).
  progress.stage("warping to " + body_b.name);
  const TriangleFrames frames_b = compute_frames(body_b);
  result.positions = warp_.apply(frames_b);
  timings["warp"] = clock.ms();
  result.report["warp"] = {{"alpha", options_.warp.alpha},
                           {"max_triangles", options_.warp.max_triangles},
                           {"capped_vertices", warp_.capped},
                           {"degenerate_triangles_a", body_a_.frames().degenerate},
                           {"degenerate_triangles_b", frames_b.degenerate}};
  if (body_a_.frames().degenerate + frames_b.degenerate > 0)
    result.warnings.push_back(std::to_string(body_a_.frames().degenerate) + " degenerate triangles on body A and " +
                              std::to_string(frames_b.degenerate) + " on body B were skipped");
  if (!result.positions.allFinite()) throw Error("internal: the warp produced a non-finite position");
  return result;
}

}  // namespace refit
