#include <refit/features/feature_curves.hpp>

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/core/topology.hpp>
#include <refit/features/bspline.hpp>
#include <refit/features/slice.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

namespace refit {
namespace {

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

[[noreturn]] void fail(const FeatureSpec& s, const std::string& problem) {
  throw input_error(s.file, "feature '" + s.name + "': " + problem);
}

// Per-block extremes, then their extremes: min and max do not depend on the
// order, so neither does the result.
std::pair<double, double> plane_range(const Garment& g, const FeaturePlane& plane) {
  constexpr std::size_t kBlock = 1 << 15;
  const std::size_t n = g.vertex_count(), blocks = (n + kBlock - 1) / kBlock;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> block_lo(blocks, kInf), block_hi(blocks, -kInf);
  parallel_for(0, blocks, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t blk = b; blk < e; ++blk)
      for (std::size_t i = blk * kBlock; i < std::min(n, (blk + 1) * kBlock); ++i) {
        const double d = plane.signed_distance(row3(g.positions, static_cast<Index>(i)));
        block_lo[blk] = std::min(block_lo[blk], d);
        block_hi[blk] = std::max(block_hi[blk], d);
      }
  });
  double lo = kInf, hi = -kInf;
  for (std::size_t blk = 0; blk < blocks; ++blk) lo = std::min(lo, block_lo[blk]), hi = std::max(hi, block_hi[blk]);
  return {lo, hi};
}

void check_plane_hits(const FeatureGarment& g, const FeatureSpec& s) {
  if (!s.plane) return;
  const auto [lo, hi] = g.plane_range(*s.plane);
  if (lo > 0.0 || hi < 0.0)
    fail(s, "the plane misses the garment (the whole garment lies " + fmt(lo > 0.0 ? lo : -hi) +
                " units to one side of it)");
}

Points sub_polyline(const Points& poly, bool closed, PolylinePoint a, PolylinePoint b) {
  const std::size_t n = static_cast<std::size_t>(poly.rows());
  std::vector<Vec3> pts{a.point};
  if (!closed) {
    const bool reversed = b.param() < a.param();
    if (reversed) std::swap(a, b);
    std::vector<Vec3> fwd{a.point};
    for (std::size_t v = a.segment + 1; v <= b.segment && v < n; ++v)
      if (static_cast<double>(v) > a.param()) fwd.push_back(row3(poly, static_cast<Index>(v)));
    fwd.push_back(b.point);
    if (reversed) std::reverse(fwd.begin(), fwd.end());
    pts = fwd;
  } else {
    // Forward arc from a to b, and the backward one; keep the shorter.
    auto arc = [&](const PolylinePoint& x, const PolylinePoint& y) {
      std::vector<Vec3> out{x.point};
      std::size_t v = (x.segment + 1) % n;
      const bool same_edge_ahead = x.segment == y.segment && y.t >= x.t;
      if (!same_edge_ahead) {
        for (std::size_t k = 0; k < n; ++k) {
          out.push_back(row3(poly, static_cast<Index>(v)));
          if (v == y.segment) break;
          v = (v + 1) % n;
        }
      }
      out.push_back(y.point);
      return out;
    };
    auto len = [](const std::vector<Vec3>& p) {
      double l = 0.0;
      for (std::size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
      return l;
    };
    std::vector<Vec3> f = arc(a, b), r = arc(b, a);
    std::reverse(r.begin(), r.end());
    pts = len(f) <= len(r) ? f : r;
  }
  // Drop repeated points (a clip point on a vertex).
  std::vector<Vec3> clean;
  for (const Vec3& p : pts)
    if (clean.empty() || (p - clean.back()).norm() > 0.0) clean.push_back(p);
  Points out(static_cast<Eigen::Index>(clean.size()), 3);
  for (std::size_t i = 0; i < clean.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = clean[i].transpose();
  return out;
}

// A drawn curve whose plane crosses the garment may still lie far from it (a
// B-spline 1000 cm away was silently ignored, issue 17): its farthest sample
// from the garment's box may be at most `limit` away.
void check_near_garment(const FeatureGarment& g, const FeatureSpec& s, const Points& samples, double limit) {
  const Eigen::RowVector3d lo = g.low.transpose(), hi = g.high.transpose();
  double farthest = 0.0;
  for (Eigen::Index k = 0; k < samples.rows(); ++k)
    farthest = std::max(farthest, (samples.row(k).cwiseMax(lo).cwiseMin(hi) - samples.row(k)).norm());
  if (farthest > limit)
    fail(s, "the curve lies up to " + fmt(farthest) + " units outside the garment's box (more than " + fmt(limit) + ")");
}

FeatureCurve build_slice(const FeatureGarment& g, const FeatureSpec& s, double diag, const FeatureCurveOptions& o,
                         std::uint64_t stream) {
  const SliceResult cut = g.slice(*s.plane, 1e-6 * diag);  // the default tolerance, diagonal known
  if (cut.pieces.empty()) fail(s, "the plane cuts none of the garment's faces");
  std::size_t best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < cut.pieces.size(); ++i) {
    const double d = nearest_on_polyline(cut.pieces[i].points, cut.pieces[i].closed, s.near).distance;
    if (d < best_d) best_d = d, best = i;
  }
  const double limit = o.near_fraction * diag;
  if (best_d > limit)
    fail(s, "'near' is " + fmt(best_d) + " units from the nearest cut piece (more than " + fmt(limit) +
                ", " + fmt(100 * o.near_fraction) + "% of the garment's size)");
  const SlicePiece& piece = cut.pieces[best];
  Points poly = piece.points;
  bool closed = piece.closed;
  if (s.from && s.to) {
    const PolylinePoint a = nearest_on_polyline(poly, closed, *s.from);
    const PolylinePoint b = nearest_on_polyline(poly, closed, *s.to);
    if (a.distance > limit) fail(s, "'from' is " + fmt(a.distance) + " units from the cut piece (more than " + fmt(limit) + ")");
    if (b.distance > limit) fail(s, "'to' is " + fmt(b.distance) + " units from the cut piece (more than " + fmt(limit) + ")");
    poly = sub_polyline(poly, closed, a, b);
    closed = false;
  }
  if (poly.rows() < 2 || !(polyline_length(poly, closed) > 1e-9 * diag))
    fail(s, "the cut piece (clipped between 'from' and 'to') has zero length");
  if (s.samples < min_samples(closed))
    fail(s, "'samples' is " + std::to_string(s.samples) + ": an open curve needs at least 5 samples");
  const BSpline spline = fit_bspline(poly, s.fit_control_points, s.degree, closed);
  FeatureCurve c = make_feature_curve(s.name, sample_by_arc_length(spline, s.samples), closed, *s.plane, o, stream);
  c.on_piece.resize(c.samples.rows(), 3);
  for (Eigen::Index i = 0; i < c.samples.rows(); ++i)
    c.on_piece.row(i) = nearest_on_polyline(poly, closed, row3(c.samples, Index(i))).point.transpose();
  return c;
}

FeatureCurve build_boundary(const FeatureGarment& g, const FeatureSpec& s, double diag, const FeatureCurveOptions& o,
                            std::uint64_t stream) {
  const std::vector<Points> polys = g.boundary_loops(1e-6 * diag);  // the default tolerance, diagonal known
  if (polys.empty()) fail(s, "the garment's faces have no boundary");
  std::size_t best = 0;
  PolylinePoint best_p;
  best_p.distance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < polys.size(); ++i) {
    const PolylinePoint p = nearest_on_polyline(polys[i], true, s.near);
    if (p.distance < best_p.distance) best_p = p, best = i;
  }
  const double limit = o.near_fraction * diag;
  if (best_p.distance > limit)
    fail(s, "'near' is " + fmt(best_p.distance) + " units from the nearest boundary loop (more than " + fmt(limit) +
                ", " + fmt(100 * o.near_fraction) + "% of the garment's size)");
  if (polys[best].rows() < 3) fail(s, "the boundary loop nearest 'near' has fewer than 3 vertices");
  // Start at the loop's point nearest `near`, so the samples do not depend on
  // where the loop happens to begin in the file.
  const Points& loop = polys[best];
  const Eigen::Index n = loop.rows();
  Points start_poly(n + 1, 3);
  start_poly.row(0) = best_p.point.transpose();
  for (Eigen::Index k = 0; k < n; ++k) start_poly.row(k + 1) = loop.row((static_cast<Eigen::Index>(best_p.segment) + 1 + k) % n);
  if ((start_poly.row(n) - start_poly.row(0)).norm() == 0.0) start_poly.conservativeResize(n, 3);
  const FeaturePlane plane = s.plane ? *s.plane : pca_plane(loop);
  return make_feature_curve(s.name, resample_polyline(start_poly, s.samples, true), true, plane, o, stream);
}

}  // namespace

Points all_sample_anchors(std::span<const FeatureCurve> curves) {
  Points out = all_samples(curves);
  Eigen::Index row = 0;
  for (const FeatureCurve& c : curves) {
    if (c.on_piece.rows() == c.samples.rows()) out.middleRows(row, c.samples.rows()) = c.on_piece;
    row += c.samples.rows();
  }
  return out;
}

Points all_samples(std::span<const FeatureCurve> curves) {
  Points out(0, 3);
  for (const FeatureCurve& c : curves) {  // a few curves of a few hundred samples
    out.conservativeResize(out.rows() + c.samples.rows(), 3);
    out.bottomRows(c.samples.rows()) = c.samples;
  }
  return out;
}

double FeatureCurve::spacing() const {
  const std::size_t m = size();
  if (m < 2) return 0.0;
  return polyline_length(samples, closed) / static_cast<double>(closed ? m : m - 1);
}

Points auxiliary_points(const Points& samples, bool closed, const FeaturePlane& plane, const FeatureCurveOptions& o,
                        std::uint64_t stream) {
  const std::size_t m = static_cast<std::size_t>(samples.rows());
  const double spacing = m > 1 ? polyline_length(samples, closed) / static_cast<double>(closed ? m : m - 1) : 0.0;
  const double radius = o.aux_radius * spacing;
  std::mt19937_64 rng(o.seed ^ (stream * 0x9E3779B97F4A7C15ULL));
  // Raw 53-bit draws: std::uniform_real_distribution may differ between
  // standard libraries, this does not.
  auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  Points aux(static_cast<Eigen::Index>(m * o.aux_per_sample), 3);
  Eigen::Index r = 0;
  for (std::size_t i = 0; i < m; ++i) {
    const Vec3 base = plane.project(row3(samples, static_cast<Index>(i)));
    for (std::size_t k = 0; k < o.aux_per_sample; ++k) {
      const double rad = radius * std::sqrt(uniform());
      const double ang = 2.0 * std::numbers::pi * uniform();
      aux.row(r++) = (base + rad * (std::cos(ang) * plane.axis_u + std::sin(ang) * plane.axis_v)).transpose();
    }
  }
  return aux;
}

FeatureCurve make_feature_curve(std::string name, Points samples, bool closed, const FeaturePlane& plane,
                                const FeatureCurveOptions& o, std::uint64_t stream) {
  const std::size_t m = static_cast<std::size_t>(samples.rows());
  if (m < min_samples(closed))
    throw Error("feature '" + name + "': " + std::to_string(m) + " samples: " + (closed ? "a closed" : "an open") +
                " curve needs at least " + std::to_string(min_samples(closed)) + " samples");
  if (!samples.allFinite()) throw Error("feature '" + name + "': a sample is not finite");
  FeatureCurve c;
  c.name = std::move(name);
  c.closed = closed;
  c.plane = plane;
  c.aux = auxiliary_points(samples, closed, plane, o, stream);
  c.samples = std::move(samples);
  return c;
}

Garment weld_garment(const Garment& g, double tolerance) {
  if (!(tolerance > 0.0)) tolerance = 1e-6 * bounding_box_diagonal(g.positions);
  const std::vector<Index> rep = weld_points(g.positions, tolerance);
  Garment w;
  w.positions = g.positions;  // unused vertices stay; boundary_loops ignores them
  // Each face's welded corners (consecutive repeats dropped, also across the
  // wrap); faces left with fewer than 3 are dropped. Sizes first, then the
  // rows in place: the same CSR for any thread count.
  const auto welded = [&](std::size_t f, Index* out) {
    const auto row = g.faces.row(f);
    std::size_t k = 0;
    for (Index v : row) {
      const Index r = rep[v];
      if (k == 0 || out[k - 1] != r) out[k++] = r;
    }
    while (k > 1 && out[k - 1] == out[0]) --k;
    return k >= 3 ? k : 0;
  };
  const std::size_t faces = g.faces.rows();
  constexpr std::size_t kGrain = 1 << 14;
  std::vector<Index> size(faces);
  parallel_for(0, faces, kGrain, [&](std::size_t b, std::size_t e) {
    std::vector<Index> row;
    for (std::size_t f = b; f < e; ++f) {
      row.resize(g.faces.row_size(f));
      size[f] = static_cast<Index>(welded(f, row.data()));
    }
  });
  std::vector<Index> kept;  // faces that stay, in order
  for (std::size_t f = 0; f < faces; ++f)
    if (size[f] > 0) kept.push_back(static_cast<Index>(f));
  w.faces.offsets.resize(kept.size() + 1);
  w.faces.offsets[0] = 0;
  for (std::size_t r = 0; r < kept.size(); ++r) w.faces.offsets[r + 1] = w.faces.offsets[r] + size[kept[r]];
  w.faces.indices.resize(w.faces.offsets.back());
  parallel_for(0, kept.size(), kGrain, [&](std::size_t b, std::size_t e) {
    std::vector<Index> row;
    for (std::size_t r = b; r < e; ++r) {
      row.resize(g.faces.row_size(kept[r]));
      welded(kept[r], row.data());
      std::copy_n(row.begin(), w.faces.row_size(r), w.faces.indices.begin() + w.faces.offsets[r]);
    }
  });
  return w;
}

std::vector<FeatureCurve> build_feature_curves(const Garment& g, const std::vector<FeatureSpec>& specs,
                                               const FeatureCurveOptions& o) {
  if (g.positions.rows() == 0) throw Error("feature curves: the garment has no vertices");
  FeatureGarment fg;
  fg.low = g.positions.colwise().minCoeff().transpose();
  fg.high = g.positions.colwise().maxCoeff().transpose();
  fg.plane_range = [&g](const FeaturePlane& plane) { return plane_range(g, plane); };
  fg.slice = [&g](const FeaturePlane& plane, double tolerance) { return slice_garment(g, plane, tolerance); };
  fg.boundary_loops = [&g](double tolerance) {
    const Garment w = weld_garment(g, tolerance);
    const std::vector<std::vector<Index>> loops = boundary_loops(w);
    std::vector<Points> polys(loops.size());
    for (std::size_t i = 0; i < loops.size(); ++i) {
      polys[i].resize(static_cast<Eigen::Index>(loops[i].size()), 3);
      for (std::size_t k = 0; k < loops[i].size(); ++k) polys[i].row(static_cast<Eigen::Index>(k)) = w.positions.row(loops[i][k]);
    }
    return polys;
  };
  return build_feature_curves(fg, specs, o);
}

std::vector<FeatureCurve> build_feature_curves(const FeatureGarment& g, const std::vector<FeatureSpec>& specs,
                                               const FeatureCurveOptions& o) {
  // bounding_box_diagonal's value, from the box.
  const double diag = Eigen::RowVector3d((g.high - g.low).transpose()).norm();
  std::vector<FeatureCurve> out;
  out.reserve(specs.size());
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const FeatureSpec& s = specs[i];
    check_plane_hits(g, s);
    try {
      switch (s.kind) {
        case CurveKind::bspline: {
          BSpline spline;
          spline.degree = s.degree;
          spline.closed = s.closed;
          spline.control.resize(s.control_points.rows(), 3);
          for (Eigen::Index k = 0; k < s.control_points.rows(); ++k)
            spline.control.row(k) = s.plane->project(row3(s.control_points, static_cast<Index>(k))).transpose();
          Points samples = sample_by_arc_length(spline, s.samples);
          check_near_garment(g, s, samples, o.near_fraction * diag);
          out.push_back(make_feature_curve(s.name, std::move(samples), s.closed, *s.plane, o, i));
          break;
        }
        case CurveKind::slice: out.push_back(build_slice(g, s, diag, o, i)); break;
        case CurveKind::boundary: out.push_back(build_boundary(g, s, diag, o, i)); break;
      }
    } catch (const Error& e) {
      const std::string what = e.what();
      if (what.find("feature '" + s.name + "'") != std::string::npos) throw;
      fail(s, what);  // e.g. a degenerate fit: still name the file and feature
    }
  }
  return out;
}

}  // namespace refit
