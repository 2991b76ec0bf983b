#include <refit/features/symmetry.hpp>

#include <refit/body/centre_tree.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/features/curve_metrics.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace refit {
namespace {

Vec3 mirror_point(const Vec3& p, double c) { return {2.0 * c - p.x(), p.y(), p.z()}; }
Vec3 mirror_dir(const Vec3& d) { return {-d.x(), d.y(), d.z()}; }

// 90th percentile: robust to one-sided details (a button, a label, a jacket's
// overlapping front: 7 % of the shared suit's vertices, whose 95th percentile
// is 1.1 cm). The vertices and curves that are not mirrored are left alone.
double symmetry_percentile(std::vector<double> d) {
  if (d.empty()) return 0.0;
  const std::size_t k = symmetry_percentile_rank(d.size());
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(k), d.end());
  return d[k];
}

// Per point, the distance from its mirror image to the nearest point of the set.
std::vector<double> vertex_mirror_distance(const Points& p, double c) {
  const std::size_t n = static_cast<std::size_t>(p.rows());
  std::vector<double> d(n);
  if (n == 0) return d;
  const PointTree tree(p);
  parallel_for(0, n, 1024, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) d[i] = std::sqrt(tree.nearest(mirror_point(row3(p, static_cast<Index>(i)), c)).second);
  });
  return d;
}

}  // namespace

SymmetryMode parse_symmetry(const std::string& s) {
  if (s == "auto") return SymmetryMode::Auto;
  if (s == "x") return SymmetryMode::X;
  if (s == "none") return SymmetryMode::None;
  throw Error("--symmetry: unknown mode '" + s + "' (use auto, x or none)");
}

double symmetrised_share(double image_distance, double tolerance) {
  if (image_distance <= tolerance) return 1.0;
  if (!(image_distance < 2.0 * tolerance)) return 0.0;
  const double t = 2.0 - image_distance / tolerance;  // 1 at the tolerance, 0 at twice it
  return smoothstep(t);
}

Points mirror_x(const Points& p, double c) {
  Points m = p;
  m.col(0) = (2.0 * c) - p.col(0).array();
  return m;
}

double mirror_plane_x(const Points& body_a) {
  return body_a.rows() > 0 ? 0.5 * (body_a.col(0).minCoeff() + body_a.col(0).maxCoeff()) : 0.0;
}

SymmetryCheck check_symmetry(double plane_x, const std::vector<double>& garment_mirror_distance, const Points& body_a,
                             double tolerance, SymmetryMode mode) {
  if (mode == SymmetryMode::None) return check_symmetry(plane_x, 0.0, body_a, tolerance, mode);
  return check_symmetry(plane_x, symmetry_percentile(garment_mirror_distance), body_a, tolerance, mode);
}

std::size_t symmetry_percentile_rank(std::size_t count) {
  return count == 0 ? 0 : std::min(count - 1, static_cast<std::size_t>(0.90 * static_cast<double>(count)));
}

SymmetryCheck check_symmetry(double plane_x, double garment_error, const Points& body_a, double tolerance,
                             SymmetryMode mode) {
  SymmetryCheck s;
  s.tolerance = tolerance;
  s.plane_x = plane_x;
  if (mode == SymmetryMode::None) return s;
  s.garment_error = garment_error;
  s.body_error = symmetry_percentile(vertex_mirror_distance(body_a, plane_x));
  s.symmetric = mode == SymmetryMode::X || (s.garment_error <= tolerance && s.body_error <= tolerance);
  return s;
}

std::vector<std::string> drop_curves_off_garment(std::vector<FeatureCurve>& curves, std::size_t first, double tolerance,
                                                 const DistanceToGarment& distance) {
  std::vector<std::string> dropped;
  std::vector<FeatureCurve> kept(std::make_move_iterator(curves.begin()),
                                 std::make_move_iterator(curves.begin() + std::ptrdiff_t(std::min(first, curves.size()))));
  for (std::size_t i = first; i < curves.size(); ++i) {
    if (symmetry_percentile(distance(curves[i].samples)) <= tolerance) kept.push_back(std::move(curves[i]));
    else dropped.push_back(curves[i].name);
  }
  curves = std::move(kept);
  return dropped;
}

std::vector<FeatureCurve> add_mirrored_curves(std::vector<FeatureCurve> curves, double c, double coincide) {
  const std::size_t given = curves.size();
  std::vector<PointTree> trees;
  trees.reserve(given);
  for (const FeatureCurve& k : curves) trees.emplace_back(k.samples);
  for (std::size_t i = 0; i < given; ++i) {
    const FeatureCurve& src = curves[i];
    const Points m = mirror_x(src.samples, c);
    bool covered = false;
    for (std::size_t k = 0; k < given && !covered; ++k) {
      const double tol = coincide * std::max(src.spacing(), curves[k].spacing());
      double worst = 0.0;
      for (Index r = 0; r < m.rows(); ++r) worst = std::max(worst, std::sqrt(trees[k].nearest(row3(m, r)).second));
      covered = worst <= tol;
    }
    if (covered) continue;
    FeaturePlane plane;
    plane.point = mirror_point(src.plane.point, c);
    plane.axis_u = mirror_dir(src.plane.axis_u);
    plane.axis_v = mirror_dir(src.plane.axis_v);
    plane.normal = plane.axis_u.cross(plane.axis_v);  // keeps the frame right-handed
    // Auxiliary points: the source's, mirrored (the same estimate of the new plane on both sides).
    FeatureCurve mc;
    mc.name = src.name + "~mirror";
    mc.closed = src.closed;
    mc.samples = m;
    mc.plane = plane;
    mc.aux = mirror_x(src.aux, c);
    if (src.on_piece.rows() > 0) mc.on_piece = mirror_x(src.on_piece, c);
    curves.push_back(std::move(mc));
  }
  return curves;
}

std::vector<Index> mirror_pairs(const Points& samples, double c, double tolerance) {
  std::vector<Index> pairs(static_cast<std::size_t>(samples.rows()), kNoMirror);
  if (samples.rows() == 0) return pairs;
  const PointTree tree(samples);
  for (Index i = 0; i < samples.rows(); ++i) {
    const auto [j, d2] = tree.nearest(mirror_point(row3(samples, i), c));
    if (std::sqrt(d2) <= tolerance) pairs[static_cast<std::size_t>(i)] = j;
  }
  return pairs;
}

std::vector<Index> sample_mirror_pairs(const std::vector<FeatureCurve>& curves, double c) {
  double spacing = std::numeric_limits<double>::infinity();
  for (const FeatureCurve& curve : curves) spacing = std::min(spacing, curve.spacing());
  return mirror_pairs(all_samples(curves), c, 0.5 * spacing);
}

void symmetrise(Points& points, const std::vector<Index>& pairs, double c) {
  const Points before = points;
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (pairs[i] != kNoMirror) {
      const Vec3 p = 0.5 * (row3(before, static_cast<Index>(i)) + mirror_point(row3(before, pairs[i]), c));
      points.row(static_cast<Index>(i)) = p.transpose();
    }
}

double paired_mirror_error(const Points& points, const std::vector<Index>& pairs, double c) {
  double worst = 0.0;
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (pairs[i] != kNoMirror)
      worst = std::max(worst, (row3(points, static_cast<Index>(i)) - mirror_point(row3(points, pairs[i]), c)).norm());
  return worst;
}

void symmetrise_curves(FeatureResult& result, const std::vector<Index>& pairs, double c) {
  Index rows = 0;
  for (const CurveResult& r : result.curves) rows += r.optimised.rows();
  if (static_cast<std::size_t>(rows) != pairs.size()) throw Error("internal: mirror pairs do not match the feature samples");
  Points all(rows, 3);
  rows = 0;
  for (const CurveResult& r : result.curves) {
    all.middleRows(rows, r.optimised.rows()) = r.optimised;
    rows += r.optimised.rows();
  }
  symmetrise(all, pairs, c);
  rows = 0;
  for (CurveResult& r : result.curves) {
    r.optimised = all.middleRows(rows, r.optimised.rows());
    rows += r.optimised.rows();
    r.shape_error_result = shape_error(r.optimised, r.original, r.closed);
    r.turning_angle_change_result_deg = turning_angle_change_deg(r.optimised, r.original, r.closed);
  }
}

std::vector<double> carried_curve_gaps(const FeatureResult& result, const Points& carried) {
  std::vector<double> gaps;
  Eigen::Index first = 0;
  for (const CurveResult& c : result.curves) {
    const Eigen::Index m = c.optimised.rows();
    if (first + m > carried.rows()) throw Error("feature gaps: fewer carried samples than the curves have");
    gaps.push_back(m == 0 ? 0.0 : (carried.middleRows(first, m) - c.optimised).rowwise().norm().maxCoeff());
    first += m;
  }
  return gaps;
}

bool farther_off(const std::vector<double>& before, const std::vector<double>& after) {
  if (before.empty() || after.empty()) return false;
  return *std::max_element(after.begin(), after.end()) > *std::max_element(before.begin(), before.end());
}

bool closer_to_curves(const std::vector<double>& before, const std::vector<double>& after, double slack) {
  if (before.size() != after.size() || before.empty()) return false;
  for (std::size_t k = 0; k < before.size(); ++k)
    if (!(after[k] <= before[k] * 1.001 + slack)) return false;
  return *std::max_element(after.begin(), after.end()) < *std::max_element(before.begin(), before.end());
}

}  // namespace refit
