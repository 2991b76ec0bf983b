// The solvers of eq. 13 on the fine agents: the paper's Gauss-Seidel sweeps,
// and beyond it V-cycles over the coarse levels, alone or as the preconditioner
// of BiCGSTAB (the default; measured in bench/README.md).
#include <refit/core/error.hpp>
#include <refit/surface/surface.hpp>

#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

namespace refit {

namespace {

using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

// Eq. 13's matrix on the free agents (rows and columns of fixed agents empty:
// their correction is zero).
RowMatrix free_matrix(const AgentRows& rows, const std::vector<std::uint8_t>& free) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(rows.ring.indices.size() + rows.size());
  for (std::size_t a = 0; a < rows.size(); ++a) {
    if (!free[a]) continue;
    t.emplace_back(Eigen::Index(a), Eigen::Index(a), rows.diag[a]);
    auto r = rows.ring.row(a);
    for (std::size_t i = 0; i < r.size(); ++i)
      if (free[r[i]]) t.emplace_back(Eigen::Index(a), Eigen::Index(r[i]), -rows.weight[rows.ring.offsets[a] + i]);
  }
  RowMatrix m(Eigen::Index(rows.size()), Eigen::Index(rows.size()));
  m.setFromTriplets(t.begin(), t.end());
  return m;
}

// A sparse matrix back in row form (diagonal, neighbours, weights = minus the
// off-diagonal entries); free where the diagonal is positive.
AgentRows matrix_rows(const RowMatrix& m, std::vector<std::uint8_t>& free) {
  AgentRows rows;
  const std::size_t n = std::size_t(m.rows());
  rows.diag.assign(n, 0.0);
  free.assign(n, 0);
  rows.ring.offsets.reserve(n + 1);
  for (std::size_t a = 0; a < n; ++a) {
    for (RowMatrix::InnerIterator it(m, Eigen::Index(a)); it; ++it) {
      if (std::size_t(it.col()) == a) {
        rows.diag[a] = it.value();
      } else if (it.value() != 0.0) {
        rows.ring.indices.push_back(Index(it.col()));
        rows.weight.push_back(-it.value());
      }
    }
    rows.ring.offsets.push_back(Index(rows.ring.indices.size()));
    free[a] = rows.diag[a] > 0.0;
  }
  rows.h = Points::Zero(Eigen::Index(n), 3);
  return rows;
}

}  // namespace

SolveReport SurfaceBinding::solve_multigrid(const AgentRows& rows, const Points& h, const std::vector<std::uint8_t>& free,
                                            Points& x, const SolveOptions& solve, bool krylov,
                                            int* krylov_iterations) const {
  // Beyond the paper: V-cycles. Gauss-Seidel removes the error at the agent
  // spacing in a few sweeps but its smooth part only over thousands (the 40k
  // demo dress needed 7,600 sweeps to reach the 1e-5 update); the coarser agent
  // subsets remove that part. Their operators are Galerkin products P^T A P of
  // this body's free system (P: the levels' interpolation), so the coarse
  // correction has the right scale whatever eq. 13's weights do across scales
  // (the levels' own encodings over-correct by 2-4x and diverge). The fixed
  // point is the same; the stopping rule is the paper's, on the fine sweeps.
  struct Galerkin {
    RowMatrix p;  // finer level's agents x this level's
    AgentRows rows;
    std::vector<std::uint8_t> free;
    BlockSchedule schedule;
  };
  std::vector<Galerkin> g(levels_.size());
  RowMatrix a = free_matrix(rows, free);
  const std::vector<std::uint8_t>* finer_free = &free;
  for (std::size_t l = 0; l < levels_.size(); ++l) {
    const CoarseLevel& lv = levels_[l];
    // Aggregation: each agent of the finer level belongs to its nearest agent of
    // this level (P has one 1 per row). P^T A P of eq. 13's M-matrix (weights
    // lambda (1 - cos theta) >= 0, diagonal their sum) is again weakly diagonally
    // dominant with non-negative weights, so Gauss-Seidel is as safe on it as on
    // the fine rows; the levels' smooth 4-agent interpolation gives coarse rows
    // far from dominant (measured: off-diagonal up to 27x the diagonal) on which
    // the sweeps diverge.
    std::vector<Eigen::Triplet<double>> t;
    for (std::size_t r = 0; r < lv.up.rows(); ++r) {
      if (!(*finer_free)[r]) continue;
      auto up = lv.up.row(r);
      if (!up.empty()) t.emplace_back(Eigen::Index(r), Eigen::Index(up[0]), 1.0);
    }
    g[l].p.resize(Eigen::Index(lv.up.rows()), Eigen::Index(lv.agent.size()));
    g[l].p.setFromTriplets(t.begin(), t.end());
    const RowMatrix pt = g[l].p.transpose();
    RowMatrix coarse = pt * a * g[l].p;
    coarse.prune(0.0);
    g[l].rows = matrix_rows(coarse, g[l].free);
    // The level's storage order is blocked for its own rings; the wider Galerkin
    // stencil only adds agents swept alone (make_schedule finds them).
    Points pos(Eigen::Index(lv.agent.size()), 3);
    for (std::size_t i = 0; i < lv.agent.size(); ++i) pos.row(Eigen::Index(i)) = original_agents_.row(lv.agent[i]);
    g[l].schedule = make_schedule(pos, g[l].rows.ring, lv.schedule.block_width);
    a = std::move(coarse);
    finer_free = &g[l].free;
  }

  const int nu = std::max(1, options_.multigrid_sweeps);
  const SolveOptions smooth{nu, 0.0, options_.relaxation};
  // Correction on the level finer than l for its residual r.
  std::function<Points(std::size_t, const Points&)> correction = [&](std::size_t l, const Points& r) -> Points {
    const Galerkin& gl = g[l];
    const Points rc = gl.p.transpose() * r;
    Points e = Points::Zero(rc.rows(), 3);
    if (l + 1 == g.size()) {
      gauss_seidel(gl.rows, rc, gl.schedule, gl.free, e, {options_.coarsest_sweeps, 0.0, options_.relaxation});
    } else {
      gauss_seidel(gl.rows, rc, gl.schedule, gl.free, e, smooth);
      e += options_.multigrid_overcorrection * correction(l + 1, row_residual(gl.rows, rc, gl.free, e));
      gauss_seidel(gl.rows, rc, gl.schedule, gl.free, e, smooth);
    }
    return gl.p * e;
  };
  // BiCGSTAB (right-preconditioned, van der Vorst) on the free rows, each
  // coordinate with its own scalars but one shared sweep: Eigen's BiCGSTAB takes
  // one vector, and three separate solves would read the rows three times.
  // Measured (bench/README.md): the bare V-cycles reduce the residual by 0.80 per
  // cycle at 10k agents and 0.97 at 95k, even with an exact coarsest solve and
  // W-cycles (0.93-0.95): a few slow modes spread over large free regions (the
  // bodice between clearance-held and feature agents). A Krylov method removes
  // such isolated modes in a few iterations; the V-cycle removes the rest.
  auto krylov_solve = [&]() -> SolveReport {
    using Col = Eigen::Array<double, 1, 3>;
    const int kn = options_.krylov_cycle_sweeps;
    const SolveOptions cycle_sweeps{kn, 0.0, options_.relaxation};
    SolveReport rep;
    const Points zero = Points::Zero(x.rows(), 3);
    auto dot = [](const Points& a, const Points& b) -> Col { return (a.array() * b.array()).colwise().sum(); };
    auto ratio = [](const Col& num, const Col& den) -> Col { return (den != 0.0).select(num / den, 0.0); };
    // One V-cycle from zero for A e = r: a fixed linear map, as BiCGSTAB needs.
    auto precondition = [&](const Points& r) -> Points {
      Points e = Points::Zero(r.rows(), 3);
      gauss_seidel(rows, r, schedule_, free, e, cycle_sweeps);
      if (!g.empty()) e += options_.multigrid_overcorrection * correction(0, row_residual(rows, r, free, e));
      gauss_seidel(rows, r, schedule_, free, e, cycle_sweeps);
      rep.iterations += 2 * kn;
      return e;
    };
    auto product = [&](const Points& v) -> Points { return -row_residual(rows, zero, free, v); };
    // The update a Jacobi sweep would make: the sweeps' own measure of the residual.
    auto jacobi_update = [&](const Points& r) {
      double t = 0.0;
      for (std::size_t a = 0; a < rows.size(); ++a)
        if (free[a]) t += r.row(Eigen::Index(a)).squaredNorm() / (rows.diag[a] * rows.diag[a]);
      return std::sqrt(t);
    };
    bool krylov = true;
    while (rep.iterations < solve.max_iterations) {
      if (krylov) {
        // A (re)start: BiCGSTAB until the residual's Jacobi update is below the
        // tolerance, the budget is spent, or it breaks down (then plain sweeps).
        Points r = row_residual(rows, h, free, x), rhat = r, p = zero, v = zero;
        Col rho_old = Col::Ones(), alpha = Col::Ones(), omega = Col::Ones();
        const Points x_start = x;
        const double r_start = r.norm();
        int its = 0;
        while (rep.iterations < solve.max_iterations && jacobi_update(r) >= solve.tolerance) {
          const Col rho = dot(rhat, r);
          const Col beta = ratio(rho, rho_old) * ratio(alpha, omega);
          rho_old = rho;
          for (int c = 0; c < 3; ++c) p.col(c) = r.col(c) + beta[c] * (p.col(c) - omega[c] * v.col(c));
          const Points ph = precondition(p);
          v = product(ph);
          alpha = ratio(rho, dot(rhat, v));
          Points s = r;
          for (int c = 0; c < 3; ++c) s.col(c) -= alpha[c] * v.col(c);
          const Points sh = precondition(s);
          const Points t = product(sh);
          omega = ratio(dot(t, s), dot(t, t));
          for (int c = 0; c < 3; ++c) {
            x.col(c) += alpha[c] * ph.col(c) + omega[c] * sh.col(c);
            r.col(c) = s.col(c) - omega[c] * t.col(c);
          }
          if (krylov_iterations) ++*krylov_iterations;
          rep.reduction = std::pow(r.norm() / r_start, 1.0 / ++its);
          if (!x.allFinite() || !r.allFinite()) {
            x = x_start;
            krylov = false;
            break;
          }
          // A breakdown (rho or omega zero while that coordinate still has a
          // residual) makes no further progress: restart. A coordinate already
          // solved has zero scalars (ratio) and stays put.
          const Col unsolved = dot(r, r);
          if (((rho == 0.0 || omega == 0.0) && unsolved > 0.0).any()) break;
        }
      }
      // The paper's stopping rule, on real sweeps: the result is only called
      // converged when a fine sweep's update is below the tolerance.
      const int left = solve.max_iterations - rep.iterations;
      if (left <= 0) break;
      const SolveReport r1 =
          gauss_seidel(rows, h, schedule_, free, x, {krylov ? std::min(left, 2) : left, solve.tolerance, solve.relaxation});
      rep.iterations += r1.iterations;
      rep.final_update = r1.final_update;
      if (r1.converged || !krylov) break;
    }
    rep.converged = rep.final_update < solve.tolerance && rep.iterations > 0;
    return rep;
  };

  if (krylov) return krylov_solve();

  SolveReport rep;
  bool cycles = true;
  double last_residual = std::numeric_limits<double>::infinity();
  Points x_before;  // the state before the last correction
  while (rep.iterations < solve.max_iterations) {
    SolveOptions pre = smooth;
    pre.max_iterations = std::min(nu, solve.max_iterations - rep.iterations);
    if (!cycles) pre = {solve.max_iterations - rep.iterations, solve.tolerance, solve.relaxation};
    const SolveReport r1 = gauss_seidel(rows, h, schedule_, free, x, pre);
    rep.iterations += r1.iterations;
    rep.final_update = r1.final_update;
    if (r1.final_update < solve.tolerance || rep.iterations >= solve.max_iterations || !cycles) break;
    const Points r = row_residual(rows, h, free, x);
    // Safety net: a cycle that did not reduce the residual is undone and ends the
    // cycles; plain sweeps (the paper's solver) finish the job.
    const double norm = r.norm();
    if (!(norm < last_residual)) {
      x = x_before;
      cycles = false;
      continue;
    }
    if (std::isfinite(last_residual)) rep.reduction = norm / last_residual;
    last_residual = norm;
    x_before = x;
    x += options_.multigrid_overcorrection * correction(0, r);
  }
  rep.converged = rep.final_update < solve.tolerance;
  return rep;
}

SolveReport SurfaceBinding::solve(const Points& h, const std::vector<std::uint8_t>& free, Points& x,
                                  const SolveOptions& o, FineSolver solver, int* krylov_iterations) const {
  if (h.rows() != x.rows() || std::size_t(x.rows()) != agent_count() || free.size() != agent_count())
    throw Error("surface: solve needs one row of h, x and free per agent");
  if (levels_.empty() || solver == FineSolver::sweeps) return gauss_seidel(rows_, h, schedule_, free, x, o);
  return solve_multigrid(rows_, h, free, x, o, solver == FineSolver::krylov, krylov_iterations);
}

}  // namespace refit
