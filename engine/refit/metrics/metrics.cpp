#include <refit/metrics/metrics.hpp>

#include <refit/body/centre_tree.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/features/bspline.hpp>
#include <refit/features/curve_metrics.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/warp/warp.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace refit {

namespace {

constexpr std::size_t kGrain = 2048;

// Corner mean of face f.
Vec3 face_centre(const Garment& g, const Points& positions, std::size_t f) {
  Vec3 centre = Vec3::Zero();
  for (Index v : g.faces.row(f)) centre += row3(positions, v);
  return centre / double(g.faces.row_size(f));
}


bool finite_row(const Points& p, Eigen::Index i) { return p.row(i).allFinite(); }

// The value at quantile q of `v` (nearest rank); v is reordered.
double percentile(std::vector<double>& v, double q) {
  if (v.empty()) return 0.0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(std::floor(q * static_cast<double>(v.size() - 1) + 0.5)));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

nlohmann::json scores_json(const CurveScores& s) {
  return {{"shape_error", s.shape_error}, {"turning_change_deg", s.turning_change_deg}, {"straightness", s.straightness}};
}

}  // namespace

std::size_t count_face_centres_inside(const Garment& g, const Points& positions, const BodySurface& body) {
  body.prepare_inside_test();
  return deterministic_sum<std::size_t>(0, g.faces.rows(), kGrain, 0, [&](std::size_t f) {
    if (g.faces.row_size(f) < 3) return std::size_t{0};
    const Vec3 centre = face_centre(g, positions, f);
    return std::size_t{centre.allFinite() && body.inside(centre)};
  });
}


double profile_straightness(const Points& curve, const Points& original, bool closed) {
  if (curve.rows() != original.rows())
    throw Error("profile straightness: the curve has " + std::to_string(curve.rows()) + " points, its original " +
                std::to_string(original.rows()));
  if (original.rows() < 2) throw Error("profile straightness: a curve needs at least 2 points");
  const double length = polyline_length(original, closed);
  if (!(length > 0.0)) throw Error("profile straightness: the original curve has zero length");
  // Best similarity (rotation, uniform scale, translation) taking the original onto the curve.
  const Eigen::Matrix4d t = Eigen::umeyama(original.transpose(), curve.transpose(), true);
  double worst = 0.0;
  for (Eigen::Index i = 0; i < curve.rows(); ++i) {
    const Vec3 p = t.topLeftCorner<3, 3>() * original.row(i).transpose() + t.topRightCorner<3, 1>();
    worst = std::max(worst, (p - curve.row(i).transpose()).norm());
  }
  return worst / length;
}

CurveScores score_curve(const Points& curve, const Points& original, bool closed) {
  CurveScores s;
  s.straightness = profile_straightness(curve, original, closed);
  s.shape_error = shape_error(curve, original, closed);
  s.turning_change_deg = original.rows() >= 3 ? turning_angle_change_deg(curve, original, closed) : 0.0;
  return s;
}

FitMetrics measure_fit(const Points& original, const Points& result, const BodySurface& a, const BodySurface& b,
                       double band) {
  const std::size_t n = static_cast<std::size_t>(original.rows());
  // change[i] is NaN for vertices outside the band (or non-finite).
  std::vector<double> change(n, std::numeric_limits<double>::quiet_NaN());
  parallel_for(0, n, kGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const auto r = static_cast<Eigen::Index>(i);
      if (!finite_row(original, r) || !finite_row(result, r)) continue;
      if (!std::isfinite(a.closest_within(row3(original, static_cast<Index>(i)), band).distance)) continue;
      // Signed, so a vertex that ends inside B counts as the fit it lost.
      change[i] = b.signed_distance(row3(result, static_cast<Index>(i))) -
                  a.signed_distance(row3(original, static_cast<Index>(i)));
    }
  });
  FitMetrics f;
  f.band = band;
  f.vertices = deterministic_sum<std::size_t>(0, n, kGrain, 0, [&](std::size_t i) { return std::isnan(change[i]) ? 0 : 1; });
  if (f.vertices == 0) return f;
  const double sum = deterministic_sum(0, n, kGrain, 0.0, [&](std::size_t i) { return std::isnan(change[i]) ? 0.0 : change[i]; });
  const double sum_abs =
      deterministic_sum(0, n, kGrain, 0.0, [&](std::size_t i) { return std::isnan(change[i]) ? 0.0 : std::abs(change[i]); });
  f.mean_change = sum / static_cast<double>(f.vertices);
  f.mean_abs_change = sum_abs / static_cast<double>(f.vertices);
  for (double c : change)
    if (!std::isnan(c)) f.max_abs_change = std::max(f.max_abs_change, std::abs(c));
  return f;
}

PenetrationMetrics measure_penetration(const Points& positions, const BodySurface& body) {
  const std::size_t n = static_cast<std::size_t>(positions.rows());
  std::vector<double> depth(n, -1.0);  // -1: not inside; -2: not finite
  parallel_for(0, n, kGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const auto r = static_cast<Eigen::Index>(i);
      if (!finite_row(positions, r)) {
        depth[i] = -2.0;
        continue;
      }
      const Vec3 p = row3(positions, static_cast<Index>(i));
      if (body.inside(p)) depth[i] = body.closest(p).distance;
    }
  });
  PenetrationMetrics m;
  for (std::size_t i = 0; i < n; ++i) {
    if (depth[i] == -2.0) continue;
    ++m.checked;
    if (depth[i] < 0.0) continue;
    ++m.inside;
    if (m.deepest_vertex < 0 || depth[i] > m.deepest) {
      m.deepest = depth[i];
      m.deepest_vertex = static_cast<long>(i);
    }
  }
  m.fraction = m.checked ? static_cast<double>(m.inside) / static_cast<double>(m.checked) : 0.0;
  return m;
}

SanityMetrics measure_sanity(const Garment& original, const Points& result) {
  if (result.rows() != original.positions.rows())
    throw Error("result has " + std::to_string(result.rows()) + " vertices, the garment " +
                std::to_string(original.positions.rows()));
  SanityMetrics s;
  const std::size_t n = static_cast<std::size_t>(result.rows());
  s.nan_vertices = deterministic_sum<std::size_t>(0, n, kGrain, 0, [&](std::size_t i) {
    return finite_row(result, static_cast<Eigen::Index>(i)) ? 0 : 1;
  });

  const std::size_t nf = original.faces.rows();
  std::vector<std::uint8_t> state(nf, 0);  // 0 skipped, 1 kept, 2 flipped
  parallel_for(0, nf, kGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t f = begin; f < end; ++f) {
      const auto face = original.faces.row(f);
      const Vec3 n0 = face_normal(original.positions, face), n1 = face_normal(result, face);
      if (!n0.allFinite() || !n1.allFinite() || n0.squaredNorm() == 0.0 || n1.squaredNorm() == 0.0) continue;
      state[f] = n0.dot(n1) < 0.0 ? 2 : 1;
    }
  });
  for (auto v : state) {
    s.faces_checked += v != 0;
    s.flipped_faces += v == 2;
  }

  // Distinct undirected edges of faces and polylines.
  std::vector<std::uint64_t> keys;
  keys.reserve(original.faces.indices.size() + original.lines.indices.size());
  auto add = [&](Index a, Index b) {
    if (a != b) keys.push_back((static_cast<std::uint64_t>(std::min(a, b)) << 32) | std::max(a, b));
  };
  for (std::size_t f = 0; f < nf; ++f) {
    const auto face = original.faces.row(f);
    for (std::size_t k = 0; k < face.size(); ++k) add(face[k], face[(k + 1) % face.size()]);
  }
  for (std::size_t l = 0; l < original.lines.rows(); ++l) {
    const auto line = original.lines.row(l);
    for (std::size_t k = 0; k + 1 < line.size(); ++k) add(line[k], line[k + 1]);
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<double> ratio(keys.size(), std::numeric_limits<double>::quiet_NaN());
  parallel_for(0, keys.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t e = begin; e < end; ++e) {
      const Index a = static_cast<Index>(keys[e] >> 32), b = static_cast<Index>(keys[e] & 0xFFFFFFFFu);
      const double l0 = (row3(original.positions, a) - row3(original.positions, b)).norm();
      const double l1 = (row3(result, a) - row3(result, b)).norm();
      if (l0 > 0.0 && std::isfinite(l1)) ratio[e] = l1 / l0;
    }
  });
  ratio.erase(std::remove_if(ratio.begin(), ratio.end(), [](double r) { return std::isnan(r); }), ratio.end());
  s.edges = ratio.size();
  s.edge_ratio_p1 = percentile(ratio, 0.01);
  s.edge_ratio_p50 = percentile(ratio, 0.50);
  s.edge_ratio_p99 = percentile(ratio, 0.99);
  return s;
}

ResizeMetrics compute_metrics(const Garment& original, const Points& result, const BodySurface& a,
                              const BodySurface& b, const MetricsOptions& options) {
  if (result.rows() != original.positions.rows())
    throw Error("result has " + std::to_string(result.rows()) + " vertices but the garment has " +
                std::to_string(original.positions.rows()) + ": they must have the same vertex order");
  ResizeMetrics m;
  m.vertices = static_cast<std::size_t>(result.rows());
  m.fit = measure_fit(original.positions, result, a, b, options.fit_band);
  m.penetration = measure_penetration(result, b);
  m.penetration.face_centres_inside = count_face_centres_inside(original, result, b);
  m.sanity = measure_sanity(original, result);
  for (const auto& c : options.features) {
    if (c.result.rows() != c.original.rows() || (c.warped.rows() != 0 && c.warped.rows() != c.original.rows()))
      throw Error("feature '" + c.name + "': its original, warped and result curves differ in point count");
    FeatureCurveMetrics f;
    f.name = c.name;
    f.result = score_curve(c.result, c.original, c.closed);
    if (c.warped.rows() != 0) {
      f.has_warp = true;
      f.warp = score_curve(c.warped, c.original, c.closed);
    }
    m.features.push_back(std::move(f));
  }
  return m;
}

ResizeMetrics compute_metrics(const Garment& original, const Points& result, const BodyMesh& a, const BodyMesh& b,
                              const MetricsOptions& options) {
  const BodySurface sa(a), sb(b, sa.topology());  // bodies of the same triangles
  return compute_metrics(original, result, sa, sb, options);
}

std::vector<FeatureCurveInput> feature_curve_inputs(const Garment& original, const Points& result, const BodyMesh& a,
                                                    const BodyMesh& b, const std::vector<FeatureSpec>& specs) {
  std::vector<FeatureCurveInput> inputs;
  const std::vector<FeatureSpec> shapes = features_with_role(specs, CurveRole::shape);
  if (shapes.empty()) return inputs;
  const std::vector<FeatureCurve> curves = build_feature_curves(original, shapes);
  const ReferenceBody ref(a);
  const TriangleFrames frames_b = compute_frames(b);
  for (const auto& c : curves) {
    FeatureCurveInput in;
    in.name = c.name;
    in.closed = c.closed;
    in.original = c.samples;
    in.warped = ref.bind(c.samples).apply(frames_b);
    in.result = carry_points(original, result, c.samples);
    inputs.push_back(std::move(in));
  }
  return inputs;
}

nlohmann::json ResizeMetrics::to_json() const {
  nlohmann::json j;
  j["vertices"] = vertices;
  j["fit"] = {{"band", fit.band},
              {"vertices", fit.vertices},
              {"mean_change", fit.mean_change},
              {"mean_abs_change", fit.mean_abs_change},
              {"max_abs_change", fit.max_abs_change}};
  j["penetration"] = {{"inside", penetration.inside},
                      {"checked", penetration.checked},
                      {"fraction", penetration.fraction},
                      {"deepest", penetration.deepest},
                      {"deepest_vertex", penetration.deepest_vertex},
                      {"face_centres_inside", penetration.face_centres_inside}};
  j["sanity"] = {{"nan_vertices", sanity.nan_vertices},
                 {"faces_checked", sanity.faces_checked},
                 {"flipped_faces", sanity.flipped_faces},
                 {"edges", sanity.edges},
                 {"edge_ratio_p1", sanity.edge_ratio_p1},
                 {"edge_ratio_p50", sanity.edge_ratio_p50},
                 {"edge_ratio_p99", sanity.edge_ratio_p99}};
  j["features"] = nlohmann::json::array();
  for (const auto& f : features) {
    nlohmann::json e = {{"name", f.name}, {"result", scores_json(f.result)}};
    if (f.has_warp) e["warp"] = scores_json(f.warp);
    j["features"].push_back(std::move(e));
  }
  return j;
}

}  // namespace refit
