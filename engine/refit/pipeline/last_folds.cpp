// The faces the collision step's last rounds turn over (last_folds.hpp).
#include <refit/pipeline/last_folds.hpp>

#include <refit/core/parallel.hpp>

namespace refit {

LastFoldsReport smooth_out_last_folds(const Garment& g, const FoldBinding& binding, Points& positions,
                                      const Csr& adjacency, const std::vector<std::uint8_t>* pinned,
                                      const BodySurface& body_b, double clearance) {
  LastFoldsReport report;
  FoldOptions options;
  options.reshape_rounds = 0;
  Points smoothed = positions;
  report.folds = smooth_out_folds(g, binding, smoothed, adjacency, pinned, options);
  if (report.folds.smoothed == 0) return report;
  const std::size_t n = std::size_t(positions.rows());
  std::vector<std::uint8_t> held(n, 0);
  parallel_for(0, n, 4096, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const auto v = Eigen::Index(i);
      if (smoothed.row(v) == positions.row(v)) continue;
      const SignedClosestPoint at = body_b.closest_and_inside(row3(smoothed, Index(i)), clearance);
      if (at.inside || at.distance < clearance * (1.0 - 1e-3)) {
        held[i] = 1;
        continue;
      }
      positions.row(v) = smoothed.row(v);
    }
  });
  report.held = deterministic_sum<std::size_t>(0, n, 4096, 0, [&](std::size_t i) { return held[i]; });
  return report;
}

}  // namespace refit
