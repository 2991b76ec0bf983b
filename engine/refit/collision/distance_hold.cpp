#include <refit/collision/distance_hold.hpp>

#include <refit/collision/unfold.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/topology.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace refit {

namespace {

constexpr std::size_t kGrain = 1024;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// What a held vertex at p needs to be `target` from the body again, less the tolerance.
Vec3 hold_move(const Vec3& p, double target, const BodySurface& body, const DistanceHoldOptions& o) {
  const SignedClosestPoint at = body.signed_closest_within(p, target + o.reach);
  if (!std::isfinite(at.distance)) return Vec3::Zero();  // far off: not the body it sat on
  const double signed_distance = at.inside ? -at.distance : at.distance;
  const double change = target - signed_distance;
  const double excess = change - std::clamp(change, -o.tolerance, o.tolerance);
  if (excess == 0.0) return Vec3::Zero();
  // Away from the body along its normal at the closest point (the closest-point
  // direction; on the surface itself only the face normal is left).
  const Vec3 towards = at.point - p;
  const double len = towards.norm();
  Vec3 out = at.normal;
  if (len > 1e-12 * (1.0 + p.norm())) out = at.inside ? Vec3(towards / len) : Vec3(-towards / len);
  return excess * out;
}

}  // namespace

std::vector<double> near_body_distances(const Points& positions, const BodySurface& body_a, double band) {
  const std::size_t n = static_cast<std::size_t>(positions.rows());
  std::vector<double> d(n, kNaN);
  parallel_for(0, n, kGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const SignedClosestPoint at = body_a.signed_closest_within(row3(positions, Index(i)), band);
      if (std::isfinite(at.distance) && !at.inside) d[i] = at.distance;
    }
  });
  return d;
}

DistanceHoldReport hold_body_distance(const Garment& g, Points& positions, const BodySurface& body_b,
                                      const std::vector<double>& distance_a, const DistanceHoldOptions& options) {
  const std::size_t n = g.vertex_count();
  if (std::size_t(positions.rows()) != n || distance_a.size() != n)
    throw Error("distance hold: " + std::to_string(positions.rows()) + " positions and " +
                std::to_string(distance_a.size()) + " distances for a garment of " + std::to_string(n) + " vertices");
  if (options.pinned && options.pinned->size() != n)
    throw Error("distance hold: the pinned vertex flags do not match the garment");
  DistanceHoldReport report;
  const auto held = [&](std::size_t v) {
    return std::isfinite(distance_a[v]) && positions.row(Eigen::Index(v)).allFinite();
  };
  std::vector<Vec3> move(n, Vec3::Zero());
  std::vector<double> change(n, 0.0);
  parallel_for(0, n, kGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) {
      if (!held(v) || (options.pinned && (*options.pinned)[v])) continue;
      move[v] = hold_move(row3(positions, Index(v)), distance_a[v], body_b, options);
      change[v] = move[v].norm();
    }
  });
  std::vector<Index> corrected;
  for (std::size_t v = 0; v < n; ++v) {
    report.held += held(v);
    if (change[v] > 0.0) {
      corrected.push_back(Index(v));
      report.largest_change = std::max(report.largest_change, change[v] + options.tolerance);
    }
  }
  report.corrected = corrected.size();
  if (corrected.empty()) return report;

  // The region a move spreads over: up to smoothing_rings edges from a corrected vertex.
  const Csr adj = vertex_adjacency(g);
  std::vector<std::int32_t> ring(n, -1);
  std::vector<Index> region = corrected;
  for (Index v : corrected) ring[v] = 0;
  for (std::size_t head = 0; head < region.size(); ++head) {
    const Index v = region[head];
    if (ring[v] >= options.smoothing_rings) continue;
    for (Index j : adj.row(v))
      if (ring[j] < 0 && positions.row(Eigen::Index(j)).allFinite()) {
        ring[j] = ring[v] + 1;
        region.push_back(j);
      }
  }
  std::sort(region.begin(), region.end());  // mesh order: deterministic and cache-friendly
  const std::size_t m = region.size();
  std::vector<long> slot(n, -1);
  for (std::size_t k = 0; k < m; ++k) slot[region[k]] = long(k);
  const auto slot_of = [&](Index v) -> long { return slot[v]; };

  // Held and pinned vertices keep their own move (zero when they need none); the
  // others average their neighbours' (out-of-region ones count as zero: the falloff).
  std::vector<Vec3> disp(m), next(m);
  std::vector<std::uint8_t> fixed(m);
  for (std::size_t k = 0; k < m; ++k) {
    const Index v = region[k];
    disp[k] = move[v];
    fixed[k] = held(v) || (options.pinned && (*options.pinned)[v]);
  }
  for (int pass = 0; pass < options.smoothing_passes; ++pass) {
    parallel_for(0, m, kGrain, [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k) {
        if (fixed[k]) {
          next[k] = disp[k];
          continue;
        }
        Vec3 sum = disp[k];
        for (Index j : adj.row(region[k]))
          if (slot[j] >= 0) sum += disp[std::size_t(slot[j])];
        next[k] = sum / (1.0 + double(adj.row_size(region[k])));
      }
    });
    std::swap(disp, next);
  }
  unfold(g, positions, region, slot_of, options.unfold_passes, disp);
  for (std::size_t k = 0; k < m; ++k) {
    if (options.pinned && (*options.pinned)[region[k]]) disp[k] = Vec3::Zero();
    const double d = disp[k].norm();
    if (d > 0.0) {
      ++report.moved;
      report.max_displacement = std::max(report.max_displacement, d);
    }
  }
  parallel_for(0, m, kGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) positions.row(region[k]) += disp[k].transpose();
  });
  return report;
}

nlohmann::json DistanceHoldReport::to_json() const {
  return {{"held", held},
          {"corrected", corrected},
          {"largest_change", largest_change},
          {"moved", moved},
          {"max_displacement", max_displacement}};
}

}  // namespace refit
