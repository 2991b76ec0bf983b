// Procedural garments around the analytic mannequin: quad grids whose rows are
// horizontal rings outside the body's cross-section at their height.
#include "mannequin/mannequin.hpp"
#include "mannequin/shape_math.hpp"

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace refit::mannequin {
namespace {


/// Directions (cos phi, sin phi) = (x, z) of N columns, phi_k = pi/2 - 2 pi k/N:
/// column 0 is the front centre, N/4 the left side, N/2 the back, 3N/4 the right
/// (exact there, so the profiles lie exactly in the planes x = 0 and z = 0).
struct Columns {
  std::vector<double> c, s;
  explicit Columns(int n) : c(static_cast<std::size_t>(n)), s(static_cast<std::size_t>(n)) {
    for (int k = 0; k < n; ++k) {
      const auto i = static_cast<std::size_t>(k);
      if ((4 * k) % n == 0) {
        static constexpr double qc[4] = {0, 1, 0, -1}, qs[4] = {1, 0, -1, 0};
        c[i] = qc[4 * k / n];
        s[i] = qs[4 * k / n];
      } else {
        const double psi = 2.0 * kPi * k / n;
        c[i] = std::sin(psi);
        s[i] = std::cos(psi);
      }
    }
  }
};

/// Perimeter of the star-shaped curve r(c, s) (256-gon).
template <class R>
double perimeter(R&& r) {
  constexpr int n = 256;
  double len = 0;
  double px = 0, pz = 0;
  for (int k = 0; k <= n; ++k) {
    const double phi = 2.0 * kPi * k / n, c = std::cos(phi), s = std::sin(phi), rr = r(c, s);
    if (k > 0) len += std::hypot(rr * c - px, rr * s - pz);
    px = rr * c;
    pz = rr * s;
  }
  return len;
}

/// Arc length of the side (phi = 0) and front (phi = pi/2) profiles between y0
/// and y1 (mean of the two), and n+1 heights spaced evenly along it.
struct Profile {
  double length = 0;
  std::vector<double> cum, ys;
  template <class R>
  Profile(double y0, double y1, R&& r) {
    constexpr int kSamples = 2000;
    cum.assign(kSamples + 1, 0.0);
    ys.resize(kSamples + 1);
    double ps = r(y0, 1.0, 0.0), pf = r(y0, 0.0, 1.0);
    ys[0] = y0;
    for (int i = 1; i <= kSamples; ++i) {
      const double y = y0 + (y1 - y0) * i / kSamples, dy = (y1 - y0) / kSamples;
      const double rs = r(y, 1.0, 0.0), rf = r(y, 0.0, 1.0);
      cum[static_cast<std::size_t>(i)] =
          cum[static_cast<std::size_t>(i - 1)] + 0.5 * (std::hypot(dy, rs - ps) + std::hypot(dy, rf - pf));
      ys[static_cast<std::size_t>(i)] = y;
      ps = rs;
      pf = rf;
    }
    length = cum.back();
  }
  std::vector<double> rows(int n) const {
    std::vector<double> out(static_cast<std::size_t>(n) + 1);
    std::size_t j = 0;
    for (int r = 0; r <= n; ++r) {
      const double target = length * r / n;
      while (j + 2 < cum.size() && cum[j + 1] < target) ++j;
      const double span = cum[j + 1] - cum[j];
      const double f = span > 0 ? std::clamp((target - cum[j]) / span, 0.0, 1.0) : 0.0;
      out[static_cast<std::size_t>(r)] = ys[j] + f * (ys[j + 1] - ys[j]);
    }
    out.front() = ys.front();
    out.back() = ys.back();
    return out;
  }
};

int round_at_least(double v, int lo) { return std::max(lo, static_cast<int>(std::lround(v))); }
int columns_for(double circumference, double h) { return 4 * round_at_least(circumference / (4.0 * h), 2); }

/// Radii of a ring `e` cm outside the torso at height y, measured along the
/// surface normal rather than horizontally (where the torso slopes, as on the
/// shoulders, a horizontal offset e would leave much less than e of room).
void torso_offset_row(const BodyShape& body, double y, double e, const Columns& col, double* r) {
  constexpr double dy = 0.05;
  const auto sec = body.torso(y), lo = body.torso(y - dy), hi = body.torso(y + dy);
  for (std::size_t k = 0; k < col.c.size(); ++k) {
    const double c = col.c[k], s = col.s[k];
    const double slope = (BodyShape::radius(hi, c, s) - BodyShape::radius(lo, c, s)) / (2 * dy);
    r[k] = BodyShape::radius(sec, c, s) + e * std::min(4.0, std::sqrt(1.0 + slope * slope));
  }
}

/// Spacing h whose count(h) is closest to target (a few fixed-point steps:
/// counts scale like 1/h^2).
template <class Count>
double choose_spacing(double h, std::size_t target, Count&& count) {
  double best_h = h, best_err = 1e300;
  for (int it = 0; it < 8; ++it) {
    const double n = static_cast<double>(count(h));
    const double err = std::abs(n - static_cast<double>(target));
    if (err < best_err) {
      best_err = err;
      best_h = h;
    }
    h *= std::sqrt(n / static_cast<double>(target));
  }
  return best_h;
}

/// A closed-ring quad grid: rows at heights ys (ascending), N columns,
/// radius(row, k) the distance from the axis x = z = 0. Faces face outward.
template <class RowFill>
Garment ring_grid(const std::vector<double>& ys, int n, const Columns& col, RowFill&& fill_row) {
  Garment g;
  const std::size_t rows = ys.size(), cols = static_cast<std::size_t>(n);
  g.positions.resize(static_cast<Eigen::Index>(rows * cols), 3);
  double* px = g.positions.col(0).data();
  double* py = g.positions.col(1).data();
  double* pz = g.positions.col(2).data();
  parallel_for(0, rows, 4, [&](std::size_t r0, std::size_t r1) {
    std::vector<double> radius(cols);
    for (std::size_t j = r0; j < r1; ++j) {
      fill_row(j, radius.data());
      for (std::size_t k = 0; k < cols; ++k) {
        const std::size_t i = j * cols + k;
        px[i] = radius[k] * col.c[k];
        py[i] = ys[j];
        pz[i] = radius[k] * col.s[k];
      }
    }
  });
  const std::size_t quads = (rows - 1) * cols;
  g.faces.offsets.resize(quads + 1);
  g.faces.indices.resize(4 * quads);
  parallel_for(0, rows - 1, 4, [&](std::size_t r0, std::size_t r1) {
    for (std::size_t j = r0; j < r1; ++j)
      for (std::size_t k = 0; k < cols; ++k) {
        const std::size_t f = j * cols + k, k1 = (k + 1) % cols;
        Index* q = g.faces.indices.data() + 4 * f;
        q[0] = static_cast<Index>(j * cols + k);
        q[1] = static_cast<Index>(j * cols + k1);
        q[2] = static_cast<Index>((j + 1) * cols + k1);
        q[3] = static_cast<Index>((j + 1) * cols + k);
        g.faces.offsets[f + 1] = static_cast<Index>(4 * (f + 1));
      }
  });
  g.faces.offsets[0] = 0;
  return g;
}

// ---------------------------------------------------------------- dress

/// The dress: bodice at ease e_b from y_w up to y_top; below the waist every
/// column runs straight down to the hem, F further from the axis.
struct DressPlan {
  const BodyShape& body;
  double y_h = 0, y_w = 0, y_top = 0, e_b = 0, F = 0;
  BodyShape::TorsoSection waist;

  DressPlan(const BodyShape& b, double ease) : body(b) {
    const Landmarks& L = b.levels();
    y_h = L.knee;
    y_w = L.waist;
    y_top = L.armpit - 0.005 * L.height;
    e_b = 1.5 + ease;
    waist = b.torso(y_w);
    // Smallest flare whose straight lines clear the body (hips, belly, legs)
    // by the bodice ease; at least a quarter of the skirt length (an A-line).
    double need = 0;
    for (int i = 0; i < 240; ++i) {
      const double y = y_h + (y_w - y_h) * i / 240.0, frac = (y_w - y) / (y_w - y_h);
      for (int j = 0; j < 128; ++j) {
        const double phi = 2.0 * kPi * j / 128, c = std::cos(phi), s = std::sin(phi);
        need = std::max(need, (b.extent(y, c, s) + e_b - rw(c, s)) / frac);
      }
    }
    F = std::max(0.25 * (y_w - y_h), 1.03 * need);
  }
  double rw(double c, double s) const { return BodyShape::radius(waist, c, s) + e_b; }
  double r(double y, double c, double s) const {
    if (y <= y_w) return rw(c, s) + F * (y_w - y) / (y_w - y_h);
    return BodyShape::radius(body.torso(y), c, s) + e_b;
  }
};

Garment make_dress(const BodyShape& body, double ease, std::size_t target) {
  const DressPlan d(body, ease);
  const auto rf = [&](double y, double c, double s) { return d.r(y, c, s); };
  const Profile bodice(d.y_w, d.y_top, rf);
  const double skirt_len = std::hypot(d.y_w - d.y_h, d.F);
  const double c_hem = perimeter([&](double c, double s) { return d.r(d.y_h, c, s); });
  const double c_w = perimeter([&](double c, double s) { return d.r(d.y_w, c, s); });
  const double c_top = perimeter([&](double c, double s) { return d.r(d.y_top, c, s); });
  const double c_avg = (skirt_len * 0.5 * (c_hem + c_w) + bodice.length * 0.5 * (c_w + c_top)) /
                       (skirt_len + bodice.length);
  struct Layout {
    int n, skirt_rows, bodice_rows;
  };
  const auto layout = [&](double h) {
    return Layout{columns_for(c_avg, h), round_at_least(skirt_len / h, 2), round_at_least(bodice.length / h, 1)};
  };
  const auto count = [&](double h) {
    const Layout l = layout(h);
    return static_cast<std::size_t>(l.n) * static_cast<std::size_t>(l.skirt_rows + 1 + l.bodice_rows);
  };
  const double area = c_avg * (skirt_len + bodice.length);
  const Layout l = layout(choose_spacing(std::sqrt(area / static_cast<double>(target)), target, count));

  std::vector<double> ys;
  for (int i = 0; i <= l.skirt_rows; ++i) ys.push_back(d.y_h + (d.y_w - d.y_h) * i / l.skirt_rows);
  ys.back() = d.y_w;
  const std::vector<double> top = bodice.rows(l.bodice_rows);
  ys.insert(ys.end(), top.begin() + 1, top.end());

  const Columns col(l.n);
  return ring_grid(ys, l.n, col, [&](std::size_t j, double* r) {
    const double y = ys[j];
    if (y <= d.y_w) {
      const double add = d.F * (d.y_w - y) / (d.y_w - d.y_h);
      for (std::size_t k = 0; k < col.c.size(); ++k) r[k] = d.rw(col.c[k], col.s[k]) + add;
    } else {
      torso_offset_row(body, y, d.e_b, col, r);
    }
  });
}

// ---------------------------------------------------------------- top

Garment make_top(const BodyShape& body, double ease, std::size_t target) {
  const Landmarks& L = body.levels();
  const double e = 0.8 + ease, y0 = 0.50 * L.height, y1 = L.neck - 0.005 * L.height;
  const auto rf = [&](double y, double c, double s) { return BodyShape::radius(body.torso(y), c, s) + e; };
  const Profile prof(y0, y1, rf);
  double c_avg = 0;
  for (int i = 0; i < 8; ++i) {
    const double y = y0 + (y1 - y0) * (i + 0.5) / 8;
    c_avg += perimeter([&](double c, double s) { return rf(y, c, s); }) / 8;
  }
  const auto count = [&](double h) {
    return static_cast<std::size_t>(columns_for(c_avg, h)) * static_cast<std::size_t>(round_at_least(prof.length / h, 2) + 1);
  };
  const double h = choose_spacing(std::sqrt(c_avg * prof.length / static_cast<double>(target)), target, count);
  const int n = columns_for(c_avg, h);
  const std::vector<double> ys = prof.rows(round_at_least(prof.length / h, 2));
  const Columns col(n);
  return ring_grid(ys, n, col, [&](std::size_t j, double* r) { torso_offset_row(body, ys[j], e, col, r); });
}

// ---------------------------------------------------------------- trousers

/// Trousers: a ring grid from the crotch level up to the waist, and two leg
/// grids below. The crotch ring is the lowest upper row (front centre F, back
/// centre B) plus m seam points on x = 0 from B to F; the left leg's top ring is
/// F, the left half, B, the seam B->F; the right leg's is B, the right half, F,
/// the seam F->B, so each seam edge has one face of each leg.
Garment make_trousers(const BodyShape& body, double ease, std::size_t target) {
  const Landmarks& L = body.levels();
  const double s_h = L.height / 165.0;
  const double e = 1.2 + ease;
  const double y_w = L.waist, y_hip = L.hip, y_ct = L.crotch - 2.0 * s_h, y_a = 0.05 * L.height;
  const double blend = 10.0 * s_h;
  const auto hip = body.torso(y_hip);
  const auto upper_r = [&](double y, double c, double s) {
    return BodyShape::radius(y >= y_hip ? body.torso(y) : hip, c, s) + e;
  };
  const Profile prof(y_ct, y_w, upper_r);
  const double c_hip = perimeter([&](double c, double s) { return upper_r(y_hip, c, s); });
  const double z_f = upper_r(y_ct, 0, 1), z_b = -upper_r(y_ct, 0, -1);
  const double leg_len = y_ct - y_a;
  const auto knee = body.leg(L.knee);
  const double c_leg = 2 * kPi * std::sqrt(0.5 * ((knee.rx + e) * (knee.rx + e) + (knee.rz + e) * (knee.rz + e)));

  struct Layout {
    int n, up_rows, seam, leg_rows;
    int ring() const { return n / 2 + 1 + seam; }
    std::size_t count() const {
      return static_cast<std::size_t>(n) * static_cast<std::size_t>(up_rows) + static_cast<std::size_t>(seam) +
             2 * static_cast<std::size_t>(ring()) * static_cast<std::size_t>(leg_rows);
    }
  };
  const auto layout = [&](double h) {
    const int n = columns_for(c_hip, h);
    return Layout{n, round_at_least(prof.length / h, 1) + 1, round_at_least((z_f - z_b) / (c_hip / n), 1),
                  round_at_least(leg_len / h, 2)};
  };
  const double area = c_hip * prof.length + 2 * c_leg * leg_len;
  const Layout l = layout(
      choose_spacing(std::sqrt(area / static_cast<double>(target)), target, [&](double h) { return layout(h).count(); }));

  const int n = l.n, m = l.seam, ring = l.ring();
  const std::vector<double> ys = prof.rows(l.up_rows - 1);
  const Columns col(n);
  Garment g = ring_grid(ys, n, col, [&](std::size_t j, double* r) {
    if (ys[j] >= y_hip) return torso_offset_row(body, ys[j], e, col, r);
    for (std::size_t k = 0; k < col.c.size(); ++k) r[k] = BodyShape::radius(hip, col.c[k], col.s[k]) + e;
  });
  const std::size_t n_up = static_cast<std::size_t>(n) * static_cast<std::size_t>(l.up_rows);
  const std::size_t seam_base = n_up;
  const std::size_t leg_base = seam_base + static_cast<std::size_t>(m);
  const std::size_t leg_size = static_cast<std::size_t>(ring) * static_cast<std::size_t>(l.leg_rows);
  const std::size_t total = leg_base + 2 * leg_size;

  Points pos(static_cast<Eigen::Index>(total), 3);
  pos.topRows(static_cast<Eigen::Index>(n_up)) = g.positions;
  for (int j = 1; j <= m; ++j) {
    const double t = static_cast<double>(j) / (m + 1);
    pos.row(static_cast<Eigen::Index>(seam_base + static_cast<std::size_t>(j - 1))) << 0.0, y_ct, z_b + t * (z_f - z_b);
  }
  // Crotch ring vertex of leg `side` (0 left, 1 right) at ring position p.
  const auto crotch_index = [&](int side, int p) -> Index {
    const int half = n / 2;
    if (p <= half) return static_cast<Index>(side == 0 ? p : (half + p) % n);
    const int j = p - half;  // 1..m
    return static_cast<Index>(seam_base + static_cast<std::size_t>(side == 0 ? j - 1 : m - j));
  };

  const auto top_sec = body.leg(y_ct);
  for (int side = 0; side < 2; ++side) {
    const double sx = side == 0 ? 1.0 : -1.0;
    const double cx0 = sx * top_sec.xc, cz0 = top_sec.zc;
    const std::size_t base = leg_base + static_cast<std::size_t>(side) * leg_size;
    parallel_for(0, static_cast<std::size_t>(l.leg_rows), 8, [&](std::size_t r0, std::size_t r1) {
      for (std::size_t i = r0; i < r1; ++i) {
        const double y = y_a + leg_len * static_cast<double>(i) / l.leg_rows;
        const auto sec = body.leg(y);
        const double w = smoothstep((y_ct - y) / blend);
        const double cx = (1 - w) * cx0 + w * sx * sec.xc, cz = (1 - w) * cz0 + w * sec.zc;
        for (int p = 0; p < ring; ++p) {
          const Index ci = crotch_index(side, p);
          const double dx0 = pos(ci, 0) - cx0, dz0 = pos(ci, 2) - cz0;
          const double rho_c = std::hypot(dx0, dz0), dx = dx0 / rho_c, dz = dz0 / rho_c;
          const double rho_e = 1.0 / std::sqrt((dx / sec.rx) * (dx / sec.rx) + (dz / sec.rz) * (dz / sec.rz)) + e;
          const double rho = (1 - w) * rho_c + w * rho_e;
          const auto vi = static_cast<Eigen::Index>(base + i * static_cast<std::size_t>(ring) + static_cast<std::size_t>(p));
          pos(vi, 0) = cx + rho * dx;
          pos(vi, 1) = y;
          pos(vi, 2) = cz + rho * dz;
        }
      }
    });
    for (int i = 0; i < l.leg_rows; ++i)
      for (int p = 0; p < ring; ++p) {
        const int q = (p + 1) % ring;
        const auto at = [&](int row, int pp) {
          return static_cast<Index>(base + static_cast<std::size_t>(row) * static_cast<std::size_t>(ring) +
                                    static_cast<std::size_t>(pp));
        };
        const Index up_p = i + 1 < l.leg_rows ? at(i + 1, p) : crotch_index(side, p);
        const Index up_q = i + 1 < l.leg_rows ? at(i + 1, q) : crotch_index(side, q);
        const std::array<Index, 4> quad{at(i, p), at(i, q), up_q, up_p};
        g.faces.push_row(quad);
      }
  }
  g.positions = std::move(pos);
  return g;
}

// ---------------------------------------------------------------- assembly

void append(Garment& a, const Garment& b) {
  const auto off = static_cast<Index>(a.positions.rows());
  Points p(a.positions.rows() + b.positions.rows(), 3);
  p << a.positions, b.positions;
  a.positions = std::move(p);
  const auto merge = [off](Csr& x, const Csr& y) {
    const Index base = static_cast<Index>(x.indices.size());
    for (std::size_t r = 1; r < y.offsets.size(); ++r) x.offsets.push_back(base + y.offsets[r]);
    for (Index i : y.indices) x.indices.push_back(i + off);
  };
  merge(a.faces, b.faces);
  merge(a.lines, b.lines);
  merge(a.points, b.points);
}

Vec3 face_centroid(const Garment& g, std::size_t f) {
  Vec3 c = Vec3::Zero();
  for (Index i : g.faces.row(f)) c += row3(g.positions, i);
  return c / static_cast<double>(g.faces.row_size(f));
}

Index add_vertex(std::vector<Vec3>& extra, Index base, const Vec3& p) {
  extra.push_back(p);
  return base + static_cast<Index>(extra.size() - 1);
}

/// Turns a manifold quad garment into messy CAD data with the same surface.
void make_soup(Garment& g, double spacing) {
  const std::size_t nf = g.faces.rows();
  const Index nv = static_cast<Index>(g.positions.rows());
  std::vector<Vec3> extra;
  const Eigen::Vector3d lo = g.positions.colwise().minCoeff(), hi = g.positions.colwise().maxCoeff();

  // 1. Two patches split by a vertical plane through the axis: the faces on its
  // negative side get their own copies of the seam vertices.
  const Vec3 cut_normal = Vec3(1, 0, 0.45).normalized();
  std::vector<std::uint8_t> side(nf), used_pos(static_cast<std::size_t>(nv), 0), used_neg(static_cast<std::size_t>(nv), 0);
  for (std::size_t f = 0; f < nf; ++f) {
    side[f] = face_centroid(g, f).dot(cut_normal) < 0;
    for (Index i : g.faces.row(f)) (side[f] ? used_neg : used_pos)[i] = 1;
  }
  std::vector<Index> copy_of(static_cast<std::size_t>(nv), 0);
  for (Index i = 0; i < nv; ++i)
    if (used_pos[i] && used_neg[i]) copy_of[i] = add_vertex(extra, nv, row3(g.positions, i));
  for (std::size_t f = 0; f < nf; ++f)
    if (side[f])
      for (Index k = g.faces.offsets[f]; k < g.faces.offsets[f + 1]; ++k) {
        Index& i = g.faces.indices[k];
        if (used_pos[i] && used_neg[i]) i = copy_of[i];
      }

  // 2. The faces near the top edge on the front left become independent
  // triangles (each original vertex kept by the first triangle that meets it).
  const double top_y = hi.y();
  Vec3 anchor(0, top_y, 0);
  {
    double best = -1e300;
    for (Index i = 0; i < nv; ++i) {
      const Vec3 p = row3(g.positions, i);
      if (p.y() < top_y - 1e-9) continue;
      const double score = p.x() * 0.5 + p.z() * 0.866;  // towards phi = 60 degrees
      if (score > best) {
        best = score;
        anchor = p;
      }
    }
  }
  // Seam faces now use the copies of step 1, which are not in g.positions yet.
  const auto position = [&](Index i) { return i < nv ? row3(g.positions, i) : extra[i - nv]; };
  const auto centroid = [&](std::span<const Index> row) {
    Vec3 c = Vec3::Zero();
    for (Index i : row) c += position(i);
    return Vec3(c / static_cast<double>(row.size()));
  };
  Csr faces;
  std::vector<std::uint8_t> kept(g.positions.rows() + static_cast<Eigen::Index>(extra.size()), 0);
  const double soup_radius = 3.0 * spacing;
  for (std::size_t f = 0; f < nf; ++f) {
    const auto row = g.faces.row(f);
    if ((centroid(row) - anchor).norm() > soup_radius || row.size() != 4) {
      faces.push_row(row);
      continue;
    }
    for (const std::array<Index, 3> tri : {std::array<Index, 3>{row[0], row[1], row[2]}, std::array<Index, 3>{row[0], row[2], row[3]}}) {
      std::array<Index, 3> t{};
      for (int c = 0; c < 3; ++c) {
        const Index i = tri[static_cast<std::size_t>(c)];
        if (!kept[i]) {
          kept[i] = 1;
          t[static_cast<std::size_t>(c)] = i;
        } else {
          const Vec3 p = i < nv ? row3(g.positions, i) : extra[i - nv];
          t[static_cast<std::size_t>(c)] = add_vertex(extra, nv, p);
        }
      }
      faces.push_row(t);
    }
  }
  g.faces = std::move(faces);

  // 3. A flap glued on an interior edge on the back right, half way up (away
  // from the planes x = 0 and z = 0 of the dress's profiles): three faces on
  // that edge.
  {
    const Vec3 target(0.7 * lo.x(), 0.5 * (lo.y() + hi.y()), 0.7 * lo.z());
    std::vector<std::pair<double, std::size_t>> order;
    for (std::size_t f = 0; f < g.faces.rows(); ++f) order.push_back({(centroid(g.faces.row(f)) - target).squaredNorm(), f});
    std::partial_sort(order.begin(), order.begin() + std::min<std::size_t>(order.size(), 16), order.end());
    bool glued = false;
    for (std::size_t o = 0; o < std::min<std::size_t>(order.size(), 16) && !glued; ++o) {
      const auto row = g.faces.row(order[o].second);
      for (std::size_t e = 0; e < row.size() && !glued; ++e) {
        const Index a = row[e], b = row[(e + 1) % row.size()];
        std::size_t uses = 0;
        for (std::size_t f = 0; f < g.faces.rows(); ++f) {
          const auto r = g.faces.row(f);
          uses += std::find(r.begin(), r.end(), a) != r.end() && std::find(r.begin(), r.end(), b) != r.end();
        }
        if (uses != 2) continue;
        const Vec3 pa = position(a), pb = position(b), mid = 0.5 * (pa + pb);
        // Faces are outward, so the face normal points away from the body.
        const Vec3 pc = position(row[(e + 2) % row.size()]);
        const Vec3 out = (pb - pa).cross(pc - pa).normalized();
        const Index w = add_vertex(extra, nv, mid + 0.8 * (pb - pa).norm() * out);
        g.faces.push_row(std::array<Index, 3>{a, b, w});
        glued = true;
      }
    }
  }

  // 4. Two drawstrings hanging from the lowest row, on the left and right sides.
  {
    Index left = 0, right = 0;
    double lx = -1e300, rx = 1e300;
    for (Index i = 0; i < nv; ++i) {
      const Vec3 p = row3(g.positions, i);
      if (p.y() > lo.y() + 1e-9) continue;
      if (p.x() > lx) lx = p.x(), left = i;
      if (p.x() < rx) rx = p.x(), right = i;
    }
    const double len = 0.07 * (hi.y() - lo.y()) + 5.0;
    for (const auto& [start, sx] : {std::pair<Index, double>{left, 1.0}, std::pair<Index, double>{right, -1.0}}) {
      const Vec3 dir = Vec3(0.5 * sx, -1, 0).normalized();
      std::vector<Index> line{start};
      for (int k = 1; k < 8; ++k) line.push_back(add_vertex(extra, nv, position(start) + len * k / 7.0 * dir));
      g.lines.push_row(line);
    }
  }

  // 5. Five buttons on the front centre, at face centres (on the surface).
  for (int b = 0; b < 5; ++b) {
    const double y = lo.y() + (hi.y() - lo.y()) * (0.55 + 0.08 * b);
    double best = 1e300;
    Vec3 at = Vec3::Zero();
    for (std::size_t f = 0; f < g.faces.rows(); ++f) {
      Vec3 c = Vec3::Zero();
      for (Index i : g.faces.row(f)) c += position(i);
      c /= static_cast<double>(g.faces.row_size(f));
      if (c.z() <= 0) continue;
      const double d = c.x() * c.x() + (c.y() - y) * (c.y() - y);
      if (d < best) best = d, at = c;
    }
    g.points.push_row(std::array<Index, 1>{add_vertex(extra, nv, at)});
  }

  // 6. One vertex used by nothing (a copy of vertex 0, so it is on the surface).
  add_vertex(extra, nv, row3(g.positions, 0));

  Points p(g.positions.rows() + static_cast<Eigen::Index>(extra.size()), 3);
  p.topRows(g.positions.rows()) = g.positions;
  for (std::size_t i = 0; i < extra.size(); ++i) p.row(nv + static_cast<Eigen::Index>(i)) = extra[i].transpose();
  g.positions = std::move(p);
}

Garment make_layer(const BodyShape& body, GarmentParams::Kind kind, double ease, std::size_t target) {
  switch (kind) {
    case GarmentParams::Kind::Dress: return make_dress(body, ease, target);
    case GarmentParams::Kind::Top: return make_top(body, ease, target);
    case GarmentParams::Kind::Trousers: return make_trousers(body, ease, target);
  }
  throw Error("mannequin: unknown garment kind");
}

void check_garment_params(const GarmentParams& g) {
  if (g.target_vertices < 500 || g.target_vertices > 50'000'000)
    throw input_error("mannequin", "target_vertices = " + std::to_string(g.target_vertices) + " is outside 500 .. 50000000");
  if (!std::isfinite(g.ease) || g.ease < -0.5 || g.ease > 20)
    throw input_error("mannequin", "garment ease = " + std::to_string(g.ease) + " is outside -0.5 .. 20");
}

std::string fmt3(const Vec3& p) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "[%.10f, %.10f, %.10f]", p.x(), p.y(), p.z());
  return buf;
}

}  // namespace

Garment make_garment(const BodyParams& body, const GarmentParams& g) {
  check_garment_params(g);
  const BodyShape shape(body);
  Garment out;
  const std::size_t per_layer = g.two_layers ? g.target_vertices / 2 : g.target_vertices;
  if (g.two_layers) {
    // The dress gets a slip underneath; top and trousers get a layer over them.
    const bool dress = g.kind == GarmentParams::Kind::Dress;
    out = make_layer(shape, g.kind, dress ? g.ease - 1.0 : g.ease, per_layer);
    append(out, make_layer(shape, g.kind, dress ? g.ease : g.ease + 1.0, per_layer));
  } else {
    out = make_layer(shape, g.kind, g.ease, per_layer);
  }
  if (g.soup) {
    // Spacing of the grid, from its area and vertex count (for the soup patch size).
    double area = 0;
    for (std::size_t f = 0; f < out.faces.rows(); ++f) {
      const auto r = out.faces.row(f);
      const Vec3 a = row3(out.positions, r[0]);
      for (std::size_t k = 1; k + 1 < r.size(); ++k)
        area += 0.5 * (row3(out.positions, r[k]) - a).cross(row3(out.positions, r[k + 1]) - a).norm();
    }
    make_soup(out, std::sqrt(area / static_cast<double>(out.vertex_count())));
  }
  return out;
}

std::string dress_features_json(const BodyParams& body, const GarmentParams& g) {
  if (g.kind != GarmentParams::Kind::Dress) throw input_error("mannequin", "dress_features_json needs a dress");
  check_garment_params(g);
  const BodyShape shape(body);
  const DressPlan d(shape, g.ease);
  const double y_mid = 0.5 * (d.y_w + d.y_h);
  // The hem comes first: curves are processed in file order and a later curve
  // keeps its crossings where an earlier one put them, so each profile is then
  // held at both ends (the hem below, the body at the waist), which fixes its
  // scale; the other order lets four profiles pull the hem apart.
  std::string out = "{\n  \"units\": \"cm\",\n  \"features\": [\n";
  out += "    { \"name\": \"hem\", \"curve\": { \"kind\": \"boundary\", \"near\": " +
         fmt3(Vec3(0, d.y_h, d.r(d.y_h, 0, 1))) + " }, \"samples\": 120 },\n";
  struct Side {
    const char* name;
    double c, s;
  };
  const Side sides[4] = {{"left-profile", 1, 0}, {"right-profile", -1, 0}, {"front-profile", 0, 1}, {"back-profile", 0, -1}};
  for (const Side& sd : sides) {
    const auto at = [&](double y) {
      const double r = d.r(y, sd.c, sd.s);
      return Vec3(r * sd.c, y, r * sd.s);
    };
    // Left and right lie in the plane z = 0, front and back in x = 0.
    const Vec3 normal = sd.s == 0 ? Vec3(0, 0, 1) : Vec3(1, 0, 0);
    out += "    { \"name\": \"" + std::string(sd.name) + "\", \"plane\": { \"point\": " + fmt3(Vec3(0, y_mid, 0)) +
           ", \"normal\": " + fmt3(normal) + " },\n      \"curve\": { \"kind\": \"slice\", \"near\": " + fmt3(at(y_mid)) +
           ", \"from\": " + fmt3(at(d.y_w)) + ", \"to\": " + fmt3(at(d.y_h)) +
           ", \"control_points\": 12 }, \"samples\": 80 }" + (&sd == &sides[3] ? "\n" : ",\n");
  }
  out += "  ]\n}\n";
  return out;
}

}  // namespace refit::mannequin
