#include <refit/features/shape_matching.hpp>

#include <refit/body/centre_tree.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/features/bspline.hpp>
#include <refit/features/curve_metrics.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

namespace refit {
namespace {

using Vec2 = Eigen::Vector2d;
using Coords = Eigen::Matrix<double, Eigen::Dynamic, 2>;

Vec2 rot(const Vec2& d) { return {d.y(), -d.x()}; }  // R = [0 1; -1 0] (section 4.3)

}  // namespace

PolylinePoint nearest_near_vertex(const PointTree& tree, const Points& poly, bool closed, const Vec3& q) {
  const Index v = tree.nearest(q).first;
  const std::size_t m = static_cast<std::size_t>(poly.rows());
  PolylinePoint best;
  best.distance = std::numeric_limits<double>::infinity();
  auto try_edge = [&](std::size_t e) {
    const auto [t, p] = closest_on_segment(q, row3(poly, static_cast<Index>(e)), row3(poly, static_cast<Index>((e + 1) % m)));
    const double dist = (p - q).norm();
    if (dist < best.distance) best.distance = dist, best.segment = e, best.t = t, best.point = p;
  };
  if (v > 0) try_edge(v - 1);
  else if (closed) try_edge(m - 1);
  if (v + 1 < m) try_edge(v);
  else if (closed) try_edge(v);
  if (!std::isfinite(best.distance)) {  // a single-edge-less curve cannot happen (m >= 3)
    best.point = row3(poly, v);
    best.distance = (best.point - q).norm();
  }
  return best;
}

double shape_energy(const CurveShape& s, const Coords& x, const Coords& xw, const ShapeMatchingOptions& o) {
  const double wd = closeness_weight(o, static_cast<std::size_t>(x.rows()));
  const std::size_t m = static_cast<std::size_t>(x.rows());
  auto X = [&](std::size_t i) -> Vec2 { return x.row(static_cast<Eigen::Index>(i)).transpose(); };
  double er = 0.0, ed = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    if (s.valid_plus[i]) {
      const std::size_t i1 = (i + 1) % m, i2 = (i + 2) % m;
      const Vec2 d = X(i2) - X(i1);
      er += (X(i) - (X(i1) + s.alpha_plus[i] * d + s.beta_plus[i] * rot(d))).squaredNorm();
    }
    if (s.valid_minus[i]) {
      const std::size_t i1 = (i + m - 1) % m, i2 = (i + m - 2) % m;
      const Vec2 d = X(i2) - X(i1);
      er += (X(i) - (X(i1) + s.alpha_minus[i] * d + s.beta_minus[i] * rot(d))).squaredNorm();
    }
    ed += (X(i) - Vec2(xw.row(static_cast<Eigen::Index>(i)).transpose())).squaredNorm();
  }
  return o.shape_weight * er + wd * ed;
}

FeaturePlane warped_feature_plane(const FeatureCurve& c, const Points& ws, const Points& wa) {
  FeaturePlane p = pca_plane(ws, wa);
  const Eigen::Index n = ws.rows() + wa.rows();
  Eigen::Matrix3Xd src(3, n), dst(3, n);
  src << c.samples.transpose(), c.aux.transpose();
  dst << ws.transpose(), wa.transpose();
  const Eigen::Matrix3d R = Eigen::umeyama(src, dst, false).topLeftCorner<3, 3>();
  if (p.normal.dot(R * c.plane.normal) < 0.0) p.normal = -p.normal;
  Vec3 u = R * c.plane.axis_u;
  u -= u.dot(p.normal) * p.normal;
  if (u.norm() > 1e-9) p.axis_u = u.normalized();
  else p.axis_u = (p.axis_u - p.axis_u.dot(p.normal) * p.normal).normalized();
  p.axis_v = p.normal.cross(p.axis_u);
  return p;
}

double closeness_weight(const ShapeMatchingOptions& o, std::size_t m) {
  const double md = static_cast<double>(m);
  return o.sampling_invariant ? o.closeness_weight / (md * md * md * md) : o.closeness_weight;
}

CurveShape shape_coefficients(const FeatureCurve& c) {
  const std::size_t m = c.size();
  CurveShape s;
  s.alpha_plus.assign(m, 0.0);
  s.beta_plus.assign(m, 0.0);
  s.alpha_minus.assign(m, 0.0);
  s.beta_minus.assign(m, 0.0);
  s.valid_plus.assign(m, 0);
  s.valid_minus.assign(m, 0);
  std::vector<Vec2> r(m);
  for (std::size_t i = 0; i < m; ++i) r[i] = c.plane.to_2d(row3(c.samples, static_cast<Index>(i)));
  auto coeff = [&](std::size_t i, std::size_t i1, std::size_t i2, double& a, double& b) {
    const Vec2 d = r[i2] - r[i1], e = r[i] - r[i1];
    const double dd = d.squaredNorm();
    if (!(dd > 0.0)) return false;
    a = e.dot(d) / dd;
    b = e.dot(rot(d)) / dd;
    return true;
  };
  for (std::size_t i = 0; i < m; ++i) {
    if (c.closed || i + 2 < m) s.valid_plus[i] = coeff(i, (i + 1) % m, (i + 2) % m, s.alpha_plus[i], s.beta_plus[i]);
    if (c.closed || i >= 2)
      s.valid_minus[i] = coeff(i, (i + m - 1) % m, (i + m - 2) % m, s.alpha_minus[i], s.beta_minus[i]);
  }
  return s;
}

ShapeModel prepare_shape_model(std::vector<FeatureCurve> curves, const ShapeMatchingOptions& options) {
  ShapeModel model;
  model.options = options;
  for (const FeatureCurve& c : curves) {
    if (c.size() < min_samples(c.closed))
      throw Error("feature '" + c.name + "': " + std::to_string(c.size()) + " samples: " +
                  (c.closed ? "a closed" : "an open") + " curve needs at least " +
                  std::to_string(min_samples(c.closed)) + " samples");
    model.shapes.push_back(shape_coefficients(c));
  }
  model.crossings.resize(curves.size());
  std::vector<PointTree> trees;
  trees.reserve(curves.size());
  for (const FeatureCurve& c : curves) trees.emplace_back(c.samples);
  for (std::size_t k = 1; k < curves.size(); ++k) {
    const FeatureCurve& ck = curves[k];
    const std::size_t m = ck.size();
    std::vector<std::uint8_t> taken(m, 0);
    for (std::size_t j = 0; j < k; ++j) {
      const FeatureCurve& cj = curves[j];
      const double tol = options.crossing_tolerance * std::max(ck.spacing(), cj.spacing());
      std::vector<PolylinePoint> near(m);
      for (std::size_t i = 0; i < m; ++i)
        near[i] = nearest_near_vertex(trees[j], cj.samples, cj.closed, row3(ck.samples, static_cast<Index>(i)));
      // Each run of consecutive samples within tol is one crossing: its closest sample.
      // For a closed curve, start the scan outside any run.
      std::size_t start = 0;
      if (ck.closed) {
        while (start < m && near[start].distance < tol) ++start;
        if (start == m) continue;  // the whole curve runs along the earlier one: no crossing point
      }
      std::size_t best = m;
      auto flush = [&] {
        if (best != m && !taken[best]) {
          taken[best] = 1;
          model.crossings[k].push_back({static_cast<Index>(best), j, near[best].segment, near[best].t, near[best].distance});
        }
        best = m;
      };
      for (std::size_t step = 0; step < m; ++step) {
        const std::size_t i = (start + step) % m;
        if (near[i].distance < tol) {
          if (best == m || near[i].distance < near[best].distance) best = i;
        } else {
          flush();
        }
      }
      flush();
    }
    std::sort(model.crossings[k].begin(), model.crossings[k].end(),
              [](const Crossing& a, const Crossing& b) { return a.sample < b.sample; });
  }
  model.curves = std::move(curves);
  return model;
}

FeatureResult match_shapes(const ShapeModel& model, const std::vector<Points>& warped_samples,
                           const std::vector<Points>& warped_aux, const DistanceToBody& distance_to_body_b,
                           const ClearanceToBody& clearance_to_body_b, std::span<const double> extra_clearance) {
  if (model.options.joint)
    return match_shapes_jointly(model, warped_samples, warped_aux, distance_to_body_b, clearance_to_body_b,
                                extra_clearance);
  return match_shapes_in_order(model, warped_samples, warped_aux, distance_to_body_b);
}

FeatureResult match_shapes_in_order(const ShapeModel& model, const std::vector<Points>& warped_samples,
                                    const std::vector<Points>& warped_aux, const DistanceToBody& distance_to_body_b) {
  const std::size_t count = model.curves.size();
  if (warped_samples.size() != count || warped_aux.size() != count)
    throw Error("feature optimisation: warped points given for " + std::to_string(warped_samples.size()) +
                " curves, expected " + std::to_string(count));
  const ShapeMatchingOptions& o = model.options;
  FeatureResult result;
  result.curves.reserve(count);
  for (std::size_t k = 0; k < count; ++k) {
    const FeatureCurve& c = model.curves[k];
    const CurveShape& shape = model.shapes[k];
    const Points& ws = warped_samples[k];
    const Points& wa = warped_aux[k];
    const std::size_t m = c.size();
    if (static_cast<std::size_t>(ws.rows()) != m || wa.rows() != c.aux.rows())
      throw Error("feature '" + c.name + "': warped sample or auxiliary point count does not match the curve");
    if (!ws.allFinite() || !wa.allFinite()) throw Error("feature '" + c.name + "': a warped sample is not finite");

    CurveResult r;
    r.name = c.name;
    r.closed = c.closed;
    r.original = c.samples;
    r.warped = ws;
    r.plane = warped_feature_plane(c, ws, wa);
    // Crossings are fixed where the earlier curves put them, in 3D. The plane moves
    // along its normal to pass through them (their mean offset): a crossing off the
    // plane is one sample out of the curve's plane, a kink the in-plane shape
    // matching cannot see. Measured on the real dress: the side profiles' hem
    // crossing sat off their planes and kept them 2-12x below the warp's shape
    // error instead of thousands of times.
    if (!model.crossings[k].empty()) {
      double offset = 0.0;
      for (const Crossing& x : model.crossings[k])
        offset += r.plane.signed_distance(point_on(result.curves[x.earlier].optimised, x.segment, x.t));
      r.plane.point += (offset / static_cast<double>(model.crossings[k].size())) * r.plane.normal;
    }
    Coords xw(static_cast<Eigen::Index>(m), 2);
    for (std::size_t i = 0; i < m; ++i) xw.row(static_cast<Eigen::Index>(i)) = r.plane.to_2d(row3(ws, static_cast<Index>(i))).transpose();

    // Fixed samples (section 4.3 heuristic). Candidates: the two closest to
    // body B and the two closest to curves already processed.
    std::vector<double> dbody(m);
    parallel_for(0, m, 256, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) dbody[i] = distance_to_body_b(row3(ws, static_cast<Index>(i)));
    });
    for (std::size_t i = 0; i < m; ++i)
      if (std::isnan(dbody[i])) throw Error("feature '" + c.name + "': the distance to body B is NaN");
    struct Cand {
      double d;
      Index i;
      const char* why;
    };
    std::vector<Cand> cand;
    // Index distance along the curve (wrapping for closed curves).
    const std::size_t min_sep = std::max<std::size_t>(1, static_cast<std::size_t>(o.min_fixed_separation * static_cast<double>(m)));
    auto separated = [&](std::size_t i, std::size_t j) {
      const std::size_t d = i > j ? i - j : j - i;
      return (c.closed ? std::min(d, m - d) : d) >= min_sep;
    };
    // The closest sample, then the closest one well separated from it (or, if
    // none is, the next closest).
    auto two_smallest = [&](const std::vector<double>& d, const char* why) {
      std::vector<Index> idx(m);
      for (std::size_t i = 0; i < m; ++i) idx[i] = static_cast<Index>(i);
      std::sort(idx.begin(), idx.end(), [&](Index a, Index b) { return d[a] < d[b] || (d[a] == d[b] && a < b); });
      if (!std::isfinite(d[idx[0]])) return;
      cand.push_back({d[idx[0]], idx[0], why});
      std::size_t second = 1;
      for (std::size_t q = 1; q < m; ++q)
        if (separated(idx[q], idx[0])) {
          second = q;
          break;
        }
      if (std::isfinite(d[idx[second]])) cand.push_back({d[idx[second]], idx[second], why});
    };
    two_smallest(dbody, "body");
    if (!model.crossings[k].empty()) {
      // Samples on an earlier curve are the closest to the processed curves (they
      // are fixed where that curve put them): they are the candidates. Fixing a
      // neighbour at its warped position instead would kink the curve there.
      std::vector<Crossing> xs = model.crossings[k];
      std::stable_sort(xs.begin(), xs.end(), [](const Crossing& a, const Crossing& b) { return a.distance < b.distance; });
      for (std::size_t q = 0; q < xs.size() && q < 2; ++q) cand.push_back({xs[q].distance, xs[q].sample, "crossing"});
    } else if (k > 0) {
      Eigen::Index rows = 0;
      for (std::size_t j = 0; j < k; ++j) rows += result.curves[j].optimised.rows();
      Points done(rows, 3);
      rows = 0;
      for (std::size_t j = 0; j < k; ++j) {
        done.middleRows(rows, result.curves[j].optimised.rows()) = result.curves[j].optimised;
        rows += result.curves[j].optimised.rows();
      }
      const PointTree tree(done);
      std::vector<double> dproc(m);
      parallel_for(0, m, 256, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) dproc[i] = std::sqrt(tree.nearest(row3(ws, static_cast<Index>(i))).second);
      });
      two_smallest(dproc, "crossing");
    }
    std::stable_sort(cand.begin(), cand.end(), [](const Cand& a, const Cand& b) {
      return a.d < b.d || (a.d == b.d && a.i < b.i);
    });
    std::vector<Vec2> fixed_pos(m);
    std::vector<std::uint8_t> is_fixed(m, 0);
    auto fix = [&](const Cand& cd) {
      is_fixed[cd.i] = 1;
      fixed_pos[cd.i] = xw.row(cd.i).transpose();
      r.fixed.push_back({cd.i, cd.why, cd.d});
    };
    if (!cand.empty()) fix(cand[0]);
    for (int pass = 0; pass < 2 && r.fixed.size() < 2; ++pass)
      for (const Cand& cd : cand)
        if (!is_fixed[cd.i] && (pass == 1 || separated(cd.i, cand[0].i))) {
          fix(cd);
          break;
        }
    if (r.fixed.size() < 2) throw Error("feature '" + c.name + "': no two distinct samples to fix (distance to body B not finite?)");
    // Crossings keep the point the earlier curve gave them (exactly, in 3D).
    std::vector<std::pair<Index, Vec3>> exact;
    for (const Crossing& x : model.crossings[k]) {
      const Vec3 target = point_on(result.curves[x.earlier].optimised, x.segment, x.t);
      is_fixed[x.sample] = 1;
      fixed_pos[x.sample] = r.plane.to_2d(target);
      exact.emplace_back(x.sample, target);
      r.crossings.push_back({x.sample, "crossing", x.distance});
    }

    // The unknowns are corrections u to `base`, the similarity copy of the
    // original through the two fixed samples: E_r(base) = 0, so the system only
    // has to find a small u, which keeps the badly conditioned (bending-like)
    // system accurate for long curves.
    Coords base(static_cast<Eigen::Index>(m), 2);
    {
      auto cplx = [](const Vec2& v) { return std::complex<double>(v.x(), v.y()); };
      const Index i0 = r.fixed[0].index, i1 = r.fixed[1].index;
      const auto r0 = cplx(c.plane.to_2d(row3(c.samples, i0))), r1 = cplx(c.plane.to_2d(row3(c.samples, i1)));
      const auto p0 = cplx(fixed_pos[i0]), p1 = cplx(fixed_pos[i1]);
      const std::complex<double> a = r1 != r0 ? (p1 - p0) / (r1 - r0) : std::complex<double>(1.0, 0.0);
      for (std::size_t i = 0; i < m; ++i) {
        const auto z = p0 + a * (cplx(c.plane.to_2d(row3(c.samples, static_cast<Index>(i)))) - r0);
        base.row(static_cast<Eigen::Index>(i)) << z.real(), z.imag();
      }
    }
    const double wd_eff = closeness_weight(o, m);
    std::vector<Eigen::Index> col(m, -1);
    Eigen::Index free = 0;
    for (std::size_t i = 0; i < m; ++i)
      if (!is_fixed[i]) col[i] = free++;
    Coords x = base;
    for (std::size_t i = 0; i < m; ++i)
      if (is_fixed[i]) x.row(static_cast<Eigen::Index>(i)) = fixed_pos[i].transpose();
    if (free > 0) {
      std::vector<Eigen::Triplet<double>> trip;
      std::vector<double> rhs;
      trip.reserve(m * 24);
      rhs.reserve(m * 6);
      Eigen::Index row = 0;
      auto ufixed = [&](std::size_t i) -> Vec2 { return fixed_pos[i] - base.row(static_cast<Eigen::Index>(i)).transpose(); };
      // Adds the 2 rows  sum_k M_k u_{idx_k} = 0  (weight w), moving fixed terms right.
      auto add = [&](const std::size_t* idx, const Eigen::Matrix2d* M, int terms, double w) {
        Vec2 b = Vec2::Zero();
        bool any = false;
        for (int t = 0; t < terms; ++t) {
          const std::size_t i = idx[t];
          if (col[i] < 0) {
            b -= w * M[t] * ufixed(i);
            continue;
          }
          any = true;
          for (int rr = 0; rr < 2; ++rr)
            for (int cc = 0; cc < 2; ++cc)
              if (M[t](rr, cc) != 0.0) trip.emplace_back(row + rr, 2 * col[i] + cc, w * M[t](rr, cc));
        }
        if (!any) return;
        rhs.push_back(b.x());
        rhs.push_back(b.y());
        row += 2;
      };
      const double wr = std::sqrt(o.shape_weight), wd = std::sqrt(wd_eff);
      const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
      Eigen::Matrix2d Rm;
      Rm << 0, 1, -1, 0;
      for (std::size_t i = 0; i < m; ++i) {
        // r_i - [r_{i1} + alpha (r_{i2} - r_{i1}) + beta R (r_{i2} - r_{i1})]  (eqs. 5-7)
        if (shape.valid_plus[i]) {
          const std::size_t idx[3] = {i, (i + 1) % m, (i + 2) % m};
          const double a = shape.alpha_plus[i], b = shape.beta_plus[i];
          const Eigen::Matrix2d M[3] = {I, -(1.0 - a) * I + b * Rm, -a * I - b * Rm};
          add(idx, M, 3, wr);
        }
        if (shape.valid_minus[i]) {
          const std::size_t idx[3] = {i, (i + m - 1) % m, (i + m - 2) % m};
          const double a = shape.alpha_minus[i], b = shape.beta_minus[i];
          const Eigen::Matrix2d M[3] = {I, -(1.0 - a) * I + b * Rm, -a * I - b * Rm};
          add(idx, M, 3, wr);
        }
        if (col[i] >= 0) {  // eq. 8: u_i = r'_i - base_i
          trip.emplace_back(row, 2 * col[i], wd);
          trip.emplace_back(row + 1, 2 * col[i] + 1, wd);
          rhs.push_back(wd * (xw(static_cast<Eigen::Index>(i), 0) - base(static_cast<Eigen::Index>(i), 0)));
          rhs.push_back(wd * (xw(static_cast<Eigen::Index>(i), 1) - base(static_cast<Eigen::Index>(i), 1)));
          row += 2;
        }
      }
      Eigen::SparseMatrix<double> A(row, 2 * free);
      A.setFromTriplets(trip.begin(), trip.end());
      const Eigen::Map<const Eigen::VectorXd> b(rhs.data(), static_cast<Eigen::Index>(rhs.size()));
      const Eigen::SparseMatrix<double> AtA = A.transpose() * A;
      Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(AtA);
      if (solver.info() != Eigen::Success) throw Error("feature '" + c.name + "': the shape matching system is singular");
      const Eigen::VectorXd sol = solver.solve(A.transpose() * b);
      if (solver.info() != Eigen::Success || !sol.allFinite())
        throw Error("feature '" + c.name + "': the shape matching solve failed");
      for (std::size_t i = 0; i < m; ++i)
        if (col[i] >= 0) x.row(static_cast<Eigen::Index>(i)) += Vec2(sol(2 * col[i]), sol(2 * col[i] + 1)).transpose();
    }
    r.energy_warped = shape_energy(shape, xw, xw, o);
    r.energy_result = shape_energy(shape, x, xw, o);
    r.optimised.resize(static_cast<Eigen::Index>(m), 3);
    for (std::size_t i = 0; i < m; ++i)
      r.optimised.row(static_cast<Eigen::Index>(i)) = r.plane.to_3d(x.row(static_cast<Eigen::Index>(i)).transpose()).transpose();
    for (const auto& [i, p] : exact) r.optimised.row(i) = p.transpose();
    measure_curve_result(r, c.closed);
    result.curves.push_back(std::move(r));
  }
  return result;
}

void measure_curve_result(CurveResult& r, bool closed) {
  r.shape_error_warped = shape_error(r.warped, r.original, closed);
  r.shape_error_result = shape_error(r.optimised, r.original, closed);
  r.turning_angle_change_warped_deg = turning_angle_change_deg(r.warped, r.original, closed);
  r.turning_angle_change_result_deg = turning_angle_change_deg(r.optimised, r.original, closed);
  r.scale_warped = similarity_scale(r.original, r.warped);
  r.scale_result = similarity_scale(r.original, r.optimised);
}

Vec3 long_axis(const Points& v) {
  if (v.rows() < 2) return Vec3::Zero();
  const Eigen::RowVector3d mean = v.colwise().mean();
  const Eigen::Matrix3d cov = (v.rowwise() - mean).transpose() * (v.rowwise() - mean);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Vec3 axis = eig.eigenvectors().col(2);  // eigenvalues ascending
  const Eigen::Index k = [&] {
    Eigen::Index i;
    axis.cwiseAbs().maxCoeff(&i);
    return i;
  }();
  return axis(k) < 0.0 ? Vec3(-axis) : axis;
}

std::vector<std::uint8_t> level_curves(const std::vector<FeatureCurve>& curves, const Vec3& axis, double tolerance_deg) {
  std::vector<std::uint8_t> level(curves.size(), 0);
  if (!(tolerance_deg > 0.0) || axis.squaredNorm() == 0.0) return level;
  const double cos_min = std::cos(tolerance_deg * M_PI / 180.0);
  for (std::size_t k = 0; k < curves.size(); ++k) level[k] = std::abs(curves[k].plane.normal.dot(axis)) >= cos_min;
  return level;
}

FeatureBinding bind_features(const ReferenceBody& a, std::vector<FeatureCurve> curves, const ShapeMatchingOptions& options) {
  FeatureBinding b;
  b.model = prepare_shape_model(std::move(curves), options);
  if (options.joint && options.level_tolerance_deg > 0.0)
    b.model.level = level_curves(b.model.curves, long_axis(a.mesh().vertices), options.level_tolerance_deg);
  for (const FeatureCurve& c : b.model.curves) {
    b.samples.push_back(a.bind(c.samples));
    b.aux.push_back(a.bind(c.aux));
  }
  return b;
}

FeatureResult optimise_features(const FeatureBinding& binding, const TriangleFrames& b_frames,
                                const DistanceToBody& distance_to_body_b, const ClearanceToBody& clearance_to_body_b,
                                std::span<const double> extra_clearance) {
  if (binding.samples.empty()) return optimise_features(binding, TriangleChange{}, distance_to_body_b, clearance_to_body_b, extra_clearance);
  return optimise_features(binding, triangle_change(*binding.samples.front().reference, b_frames), distance_to_body_b,
                           clearance_to_body_b, extra_clearance);
}

// One change to body B for every curve (each apply would form it for all of body A's triangles).
FeatureResult optimise_features(const FeatureBinding& binding, const TriangleChange& change_b,
                                const DistanceToBody& distance_to_body_b, const ClearanceToBody& clearance_to_body_b,
                                std::span<const double> extra_clearance) {
  std::vector<Points> ws, wa;
  for (std::size_t k = 0; k < binding.model.curves.size(); ++k) {
    ws.push_back(binding.samples[k].apply(change_b));
    wa.push_back(binding.aux[k].apply(change_b));
  }
  return match_shapes(binding.model, ws, wa, distance_to_body_b, clearance_to_body_b, extra_clearance);
}

}  // namespace refit
