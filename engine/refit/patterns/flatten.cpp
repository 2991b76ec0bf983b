// ARAP flattening with a conformal start; see flatten.hpp. Notation: corner i
// of a triangle faces edge (j, k) = (i+1, i+2); x are the triangle's corners in
// its own isometric 2D frame, u their images in the plane.
#include <refit/patterns/flatten.hpp>

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <tuple>

namespace refit {
namespace {

using Vec2 = Eigen::Vector2d;
using Vector = Eigen::VectorXd;
using SparseMatrix = Eigen::SparseMatrix<double>;

constexpr std::size_t kGrain = 2048;

// Each triangle in its own plane: corner 0 at the origin, corner 1 on +x.
// Per corner i, the weights of the edge it faces in the energy
// 1/2 (cot |e'|^2 - 2 rest e'.R e + rest2 |e|^2): all three are the cotangent of
// the angle at i, plus w, w s and w s^2 where the edge is held at s times its
// 3D length with weight w (a sewn edge).
struct Geometry {
  std::vector<std::array<Vec2, 3>> local;
  std::vector<std::array<double, 3>> cot, rest, rest2;
};

Geometry triangle_geometry(const Points& xyz, std::span<const Triangle> tris) {
  Geometry g;
  g.local.resize(tris.size());
  g.cot.resize(tris.size());
  parallel_for(0, tris.size(), kGrain, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      const Vec3 p0 = row3(xyz, tris[t][0]), p1 = row3(xyz, tris[t][1]), p2 = row3(xyz, tris[t][2]);
      const Vec3 e1 = p1 - p0, e2 = p2 - p0;
      const double l1 = e1.norm();
      const double twice_area = e1.cross(e2).norm();
      const double scale = std::max({e1.squaredNorm(), e2.squaredNorm(), (p2 - p1).squaredNorm()});
      if (!(l1 > 0) || !(twice_area > 1e-12 * scale)) {
        // Degenerate: a weak spring on each edge keeps the Laplacian definite.
        g.local[t] = {Vec2(0, 0), Vec2(l1, 0), Vec2(e2.dot(e1) / std::max(l1, 1e-300), 0)};
        g.cot[t] = {1e-4, 1e-4, 1e-4};
        continue;
      }
      g.local[t] = {Vec2(0, 0), Vec2(l1, 0), Vec2(e2.dot(e1) / l1, twice_area / l1)};
      for (int i = 0; i < 3; ++i) {
        const Vec2& a = g.local[t][i];
        const Vec2 ej = g.local[t][(i + 1) % 3] - a, ek = g.local[t][(i + 2) % 3] - a;
        g.cot[t][i] = ej.dot(ek) / twice_area;
      }
    }
  });
  g.rest = g.cot;
  g.rest2 = g.cot;
  return g;
}

// The cotangent Laplacian (u' L u is the Dirichlet energy of the piecewise
// linear u) without the row and column of the pinned vertex, whose column is
// kept apart (rows of the other vertices, in the reduced numbering).
struct PinnedLaplacian {
  SparseMatrix L;                                  // (n-1) x (n-1)
  std::vector<std::pair<Index, double>> pin_column;
  Index pin = 0;
  Index reduced(Index v) const { return v < pin ? v : v - 1; }
};

// The held edges' weights added to the corners facing them; returns them as
// (j, k, w) so that the conformal start can take them out again.
std::vector<std::tuple<Index, Index, double>> hold_edges(std::span<const Triangle> tris, std::span<const HeldEdge> held,
                                                         double weight, Geometry& g) {
  std::vector<std::tuple<Index, Index, double>> added;
  if (held.empty() || !(weight > 0)) return added;
  std::vector<std::tuple<Index, Index, double>> sorted;  // (min, max, length)
  for (const HeldEdge& h : held) sorted.emplace_back(std::min(h.a, h.b), std::max(h.a, h.b), h.length);
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int i = 0; i < 3; ++i) {
      const Index j = tris[t][(i + 1) % 3], k = tris[t][(i + 2) % 3];
      const auto it = std::lower_bound(sorted.begin(), sorted.end(), std::make_tuple(std::min(j, k), std::max(j, k), -1.0));
      if (it == sorted.end() || std::get<0>(*it) != std::min(j, k) || std::get<1>(*it) != std::max(j, k)) continue;
      const double rest = (g.local[t][(i + 1) % 3] - g.local[t][(i + 2) % 3]).norm();
      const double s = rest > 0 ? std::get<2>(*it) / rest : 1.0;
      g.cot[t][i] += weight;
      g.rest[t][i] += weight * s;
      g.rest2[t][i] += weight * s * s;
      added.emplace_back(j, k, weight);
    }
  return added;
}

PinnedLaplacian pinned_laplacian(std::size_t n, std::span<const Triangle> tris, const Geometry& g, Index pin) {
  PinnedLaplacian out;
  out.pin = pin;
  std::vector<Eigen::Triplet<double>> entries, column;
  entries.reserve(tris.size() * 12);
  const auto add = [&](Index r, Index c, double w) {
    if (c == pin && r != pin) column.emplace_back(out.reduced(r), 0, w);
    else if (r != pin && c != pin) entries.emplace_back(out.reduced(r), out.reduced(c), w);
  };
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int i = 0; i < 3; ++i) {
      const Index j = tris[t][(i + 1) % 3], k = tris[t][(i + 2) % 3];
      const double w = 0.5 * g.cot[t][i];
      add(j, k, -w), add(k, j, -w), add(j, j, w), add(k, k, w);
    }
  const auto m = static_cast<Eigen::Index>(n - 1);
  out.L.resize(m, m);
  out.L.setFromTriplets(entries.begin(), entries.end());
  SparseMatrix col(m, 1);
  col.setFromTriplets(column.begin(), column.end());
  for (SparseMatrix::InnerIterator it(col, 0); it; ++it) out.pin_column.emplace_back(static_cast<Index>(it.row()), it.value());
  return out;
}

// Boundary half-edges (used by one triangle only), as (from, to) in winding order.
std::vector<std::array<Index, 2>> boundary_half_edges(std::span<const Triangle> tris) {
  std::vector<std::array<Index, 3>> half;  // (min, max, direction)
  half.reserve(tris.size() * 3);
  for (const Triangle& t : tris)
    for (int i = 0; i < 3; ++i) {
      const Index a = t[i], b = t[(i + 1) % 3];
      half.push_back({std::min(a, b), std::max(a, b), a < b ? 0u : 1u});
    }
  std::sort(half.begin(), half.end());
  std::vector<std::array<Index, 2>> out;
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j][0] == half[i][0] && half[j][1] == half[i][1]) ++j;
    if (j - i == 1) out.push_back(half[i][2] == 0 ? std::array<Index, 2>{half[i][0], half[i][1]}
                                                  : std::array<Index, 2>{half[i][1], half[i][0]});
    i = j;
  }
  return out;
}

// Two boundary vertices far apart (farthest from a boundary vertex, then from that).
std::array<Index, 2> pins(const Points& xyz, const std::vector<std::array<Index, 2>>& boundary) {
  const auto farthest = [&](Index from) {
    Index best = boundary[0][0];
    double d = -1;
    for (const auto& e : boundary) {
      const double di = (xyz.row(e[0]) - xyz.row(from)).squaredNorm();
      if (di > d) d = di, best = e[0];
    }
    return best;
  };
  const Index p0 = farthest(boundary[0][0]);
  return {p0, farthest(p0)};
}

// Solves the (n-1) system of L without `pin` for the u and v columns of `rhs`
// (full length, entry `pin` ignored), in parallel; returns full length with 0 at `pin`.
template <class Solver>
Eigen::MatrixX2d solve_pinned(const Solver& solver, const Eigen::MatrixX2d& rhs, Index pin) {
  const Eigen::Index n = rhs.rows();
  Eigen::MatrixX2d out(n, 2);
  parallel_for(0, 2, 1, [&](std::size_t b, std::size_t e) {
    for (std::size_t c = b; c < e; ++c) {
      const auto col = static_cast<Eigen::Index>(c);
      Vector r(n - 1);
      r.head(pin) = rhs.col(col).head(pin);
      r.tail(n - 1 - pin) = rhs.col(col).tail(n - 1 - pin);
      const Vector x = solver.solve(r);
      out.col(col).head(pin) = x.head(pin);
      out(pin, col) = 0.0;
      out.col(col).tail(n - 1 - pin) = x.tail(n - 1 - pin);
    }
  });
  return out;
}

// The least-squares conformal map with p0 at (0, 0) and p1 at (d, 0): conjugate
// gradients on E_D - A (Dirichlet energy minus signed area), preconditioned by
// the Dirichlet part (the factor of L without p0, restricted to the free set).
template <class Solver>
Eigen::MatrixX2d conformal_map(const Points& xyz, const PinnedLaplacian& lap,
                               const std::vector<std::tuple<Index, Index, double>>& held,
                               const Solver& solver, const std::vector<std::array<Index, 2>>& boundary,
                               std::array<Index, 2> pin, int max_iterations, int& iterations) {
  const Eigen::Index n = lap.L.rows() + 1, p0 = pin[0];
  // Q x: [L 0; 0 L] x minus the area form (1/2 sum over boundary half-edges i->j
  // of u_i v_j - u_j v_i), for x zero at p0 (its row is masked anyway).
  const auto apply = [&](const Eigen::MatrixX2d& x) {
    Eigen::MatrixX2d reduced(n - 1, 2);
    reduced.topRows(p0) = x.topRows(p0);
    reduced.bottomRows(n - 1 - p0) = x.bottomRows(n - 1 - p0);
    const Eigen::MatrixX2d lx = lap.L * reduced;
    Eigen::MatrixX2d y(n, 2);
    y.topRows(p0) = lx.topRows(p0);
    y.row(p0).setZero();
    y.bottomRows(n - 1 - p0) = lx.bottomRows(n - 1 - p0);
    for (const auto& [i, j, w] : held) {  // the held edges are not part of the conformal energy
      const Eigen::RowVector2d d = 0.5 * w * (x.row(i) - x.row(j));
      y.row(i) -= d;
      y.row(j) += d;
    }
    for (const auto& e : boundary) {
      const Index i = e[0], j = e[1];
      y(i, 0) -= 0.5 * x(j, 1);
      y(j, 1) -= 0.5 * x(i, 0);
      y(j, 0) += 0.5 * x(i, 1);
      y(i, 1) += 0.5 * x(j, 0);
    }
    return y;
  };
  const auto mask = [&](Eigen::MatrixX2d& x) { x.row(pin[0]).setZero(), x.row(pin[1]).setZero(); };
  Eigen::MatrixX2d fixed = Eigen::MatrixX2d::Zero(n, 2);
  fixed(pin[1], 0) = (xyz.row(pin[1]) - xyz.row(pin[0])).norm();
  Eigen::MatrixX2d r = -apply(fixed);
  mask(r);
  Eigen::MatrixX2d x = Eigen::MatrixX2d::Zero(n, 2);
  const auto precondition = [&](const Eigen::MatrixX2d& res) {
    Eigen::MatrixX2d z = solve_pinned(solver, res, pin[0]);
    mask(z);
    return z;
  };
  Eigen::MatrixX2d z = precondition(r), p = z;
  double rz = (r.array() * z.array()).sum();
  const double r0 = r.norm();
  iterations = 0;
  while (iterations < max_iterations && r.norm() > 1e-8 * r0 && r0 > 0) {
    ++iterations;
    Eigen::MatrixX2d q = apply(p);
    mask(q);
    const double pq = (p.array() * q.array()).sum();
    if (!(pq > 0)) break;
    const double alpha = rz / pq;
    x += alpha * p;
    r -= alpha * q;
    z = precondition(r);
    const double rz_next = (r.array() * z.array()).sum();
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return x + fixed;
}

// The rotation R maximising trace(R S): its cosine and sine are proportional to
// S00 + S11 and S01 - S10 (no angle needed).
Eigen::Matrix2d closest_rotation(const Eigen::Matrix2d& s) {
  const double c = s(0, 0) + s(1, 1), d = s(0, 1) - s(1, 0), norm = std::hypot(c, d);
  Eigen::Matrix2d r;
  if (!(norm > 0)) return Eigen::Matrix2d::Identity();
  r << c / norm, -d / norm, d / norm, c / norm;
  return r;
}

// The two steps of ARAP on one piece: local (each triangle's best rotation, the
// energy and the right-hand side) and global (the pinned Laplacian solve).
class ArapSteps {
 public:
  ArapSteps(const Points& xyz, std::span<const Triangle> tris, const Geometry& geo, const PinnedLaplacian& lap,
            const Eigen::SimplicialLDLT<SparseMatrix>& solver, Index pin)
      : tris_(tris), geo_(geo), lap_(lap), solver_(solver), pin_(pin), n_(static_cast<std::size_t>(xyz.rows())),
        corner_rhs_(tris.size() * 3), energy_(tris.size()) {
    // Per vertex, its (triangle, corner) slots in triangle order: the right-hand
    // side is gathered per vertex, so the sums do not depend on the threads.
    offsets_.assign(n_ + 1, 0);
    slots_.resize(tris.size() * 3);
    for (const Triangle& t : tris)
      for (Index v : t) ++offsets_[v + 1];
    for (std::size_t v = 0; v < n_; ++v) offsets_[v + 1] += offsets_[v];
    std::vector<Index> fill(offsets_.begin(), offsets_.end() - 1);
    for (std::size_t t = 0; t < tris.size(); ++t)
      for (int i = 0; i < 3; ++i) slots_[fill[tris[t][i]]++] = static_cast<Index>(t * 3 + i);
    for (std::size_t t = 0; t < tris.size(); ++t)
      for (int i = 0; i < 3; ++i)
        scale_ += std::abs(geo.cot[t][i]) * (geo.local[t][(i + 1) % 3] - geo.local[t][(i + 2) % 3]).squaredNorm();
  }

  // The energy's scale: the piece's area (times its mean cotangent weight).
  double scale() const { return scale_; }

  // Energy of `uv` with each triangle's best rotation; keeps the right-hand side.
  double local(const Eigen::MatrixX2d& uv) const {
    parallel_for(0, tris_.size(), kGrain, [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t) {
        const auto& x = geo_.local[t];
        const auto& c = geo_.cot[t];
        const auto& r = geo_.rest[t];
        const auto& r2 = geo_.rest2[t];
        Vec2 u[3];
        for (int i = 0; i < 3; ++i) u[i] = uv.row(tris_[t][i]).transpose();
        Eigen::Matrix2d s = Eigen::Matrix2d::Zero();
        for (int i = 0; i < 3; ++i) {
          const int j = (i + 1) % 3, k = (i + 2) % 3;
          s += r[i] * (x[j] - x[k]) * (u[j] - u[k]).transpose();
        }
        const Eigen::Matrix2d R = closest_rotation(s);
        double energy = 0;
        for (int i = 0; i < 3; ++i) {
          const int j = (i + 1) % 3, k = (i + 2) % 3;
          const Vec2 e = x[j] - x[k], ue = u[j] - u[k];
          energy += 0.5 * (c[i] * ue.squaredNorm() - 2 * r[i] * ue.dot(R * e) + r2[i] * e.squaredNorm());
          // Corner j's share: rest_i R (x_j - x_k) + rest_k R (x_j - x_i).
          corner_rhs_[t * 3 + j] = r[i] * (R * e) + r[k] * (R * (x[j] - x[i]));
        }
        energy_[t] = energy;
      }
    });
    return deterministic_sum(0, tris_.size(), kGrain, 0.0, [&](std::size_t t) { return energy_[t]; });
  }

  // L u = b / 2 for the last local step's rotations, the pinned vertex where it is in `uv`.
  Eigen::MatrixX2d global(const Eigen::MatrixX2d& uv) const {
    Eigen::MatrixX2d rhs(static_cast<Eigen::Index>(n_), 2);
    parallel_for(0, n_, kGrain, [&](std::size_t b, std::size_t e) {
      for (std::size_t v = b; v < e; ++v) {
        Vec2 sum(0, 0);
        for (Index k = offsets_[v]; k < offsets_[v + 1]; ++k) sum += corner_rhs_[slots_[k]];
        rhs.row(static_cast<Eigen::Index>(v)) = 0.5 * sum.transpose();
      }
    });
    const Vec2 anchor = uv.row(pin_).transpose();
    // Moving the pinned vertex's known value to the right-hand side: - L(:, pin) * anchor.
    for (const auto& [row, value] : lap_.pin_column) rhs.row(row < pin_ ? row : row + 1) -= value * anchor.transpose();
    Eigen::MatrixX2d out = solve_pinned(solver_, rhs, pin_);
    out.row(pin_) = anchor.transpose();
    return out;
  }

 private:
  std::span<const Triangle> tris_;
  const Geometry& geo_;
  const PinnedLaplacian& lap_;
  const Eigen::SimplicialLDLT<SparseMatrix>& solver_;
  Index pin_;
  std::size_t n_;
  double scale_ = 0;
  std::vector<Index> offsets_, slots_;
  mutable std::vector<Vec2> corner_rhs_;
  mutable std::vector<double> energy_;
};

}  // namespace

Flattening flatten_piece(const Points& xyz, std::span<const Triangle> tris, const FlattenOptions& options,
                         std::span<const HeldEdge> held, const Points2* start_uv) {
  using Clock = std::chrono::steady_clock;
  const auto ms_since = [](Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); };
  auto start = Clock::now();
  const std::size_t n = static_cast<std::size_t>(xyz.rows());
  if (n < 3 || tris.empty()) throw Error("flatten: a piece needs at least 3 vertices and one triangle");
  for (const Triangle& t : tris)
    for (Index v : t)
      if (v >= n) throw Error("flatten: triangle vertex " + std::to_string(v) + " out of range");
  const std::vector<std::array<Index, 2>> boundary = boundary_half_edges(tris);
  if (boundary.empty()) throw Error("flatten: the piece is closed (it has no boundary)");

  Flattening out;
  Geometry geo = triangle_geometry(xyz, tris);
  const std::array<Index, 2> pin = pins(xyz, boundary);
  for (const HeldEdge& h : held)
    if (h.a >= n || h.b >= n || !(h.length >= 0)) throw Error("flatten: held edge out of range or of no length");
  const auto added = hold_edges(tris, held, options.boundary_weight, geo);
  const PinnedLaplacian lap = pinned_laplacian(n, tris, geo, pin[0]);
  const Eigen::SimplicialLDLT<SparseMatrix> solver(lap.L);
  if (solver.info() != Eigen::Success) throw Error("flatten: the piece's Laplacian could not be factorised");
  out.factor_ms = ms_since(start);
  start = Clock::now();
  if (start_uv && start_uv->rows() != static_cast<Eigen::Index>(n)) throw Error("flatten: start has the wrong size");
  Eigen::MatrixX2d uv = start_uv ? Eigen::MatrixX2d(*start_uv)
                                 : conformal_map(xyz, lap, added, solver, boundary, pin, options.conformal_iterations,
                                                 out.conformal_iterations);
  out.conformal_ms = ms_since(start);
  start = Clock::now();
  if (!options.arap) {
    out.uv = uv;
    return out;
  }
  const ArapSteps steps(xyz, tris, geo, lap, solver, pin[0]);
  // Local/global iterations, Anderson-accelerated (Peng et al. 2018, window
  // kWindow): a step that would raise the energy falls back to the plain one.
  constexpr int kWindow = 5;
  const Eigen::Index size = 2 * static_cast<Eigen::Index>(n);
  Eigen::MatrixXd dF(size, kWindow), dG(size, kWindow);
  int stored = 0, next = 0;
  Eigen::MatrixX2d g_prev, f_prev, plain;
  double previous = std::numeric_limits<double>::infinity();
  for (int it = 0; it < options.max_iterations; ++it) {
    double energy = steps.local(uv);
    if (energy > previous && plain.size() > 0) {  // the accelerated step went uphill
      uv = plain;
      energy = steps.local(uv);
      stored = 0, next = 0;
      g_prev.resize(0, 2);
    }
    out.energy = energy;
    out.iterations = it;
    // Converged: the energy stopped falling, or the piece is isometric to rounding.
    if ((it > 0 && previous - energy <= options.tolerance * previous) || energy <= 1e-20 * steps.scale()) {
      out.converged = true;
      break;
    }
    previous = energy;
    const Eigen::MatrixX2d g = steps.global(uv);
    const Eigen::MatrixX2d f = g - uv;
    plain = g;
    if (g_prev.size() > 0) {
      const Eigen::MatrixX2d df = f - f_prev, dg = g - g_prev;
      dF.col(next) = Eigen::Map<const Eigen::VectorXd>(df.data(), size);
      dG.col(next) = Eigen::Map<const Eigen::VectorXd>(dg.data(), size);
      next = (next + 1) % kWindow;
      stored = std::min(stored + 1, kWindow);
    }
    g_prev = g, f_prev = f;
    if (stored == 0) {
      uv = g;
      continue;
    }
    // gamma = argmin |f - dF gamma| by the normal equations (a few columns).
    const auto F = dF.leftCols(stored);
    Eigen::MatrixXd normal = F.transpose() * F;
    normal.diagonal().array() += 1e-12 * normal.trace() + 1e-300;
    const Eigen::VectorXd gamma = normal.ldlt().solve(F.transpose() * Eigen::Map<const Eigen::VectorXd>(f.data(), size));
    Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(g.data(), size) - dG.leftCols(stored) * gamma;
    uv = Eigen::Map<Eigen::MatrixX2d>(x.data(), static_cast<Eigen::Index>(n), 2);
  }
  if (!out.converged) out.iterations = options.max_iterations;
  out.uv = uv;
  out.arap_ms = ms_since(start);
  return out;
}

}  // namespace refit
