// The agent system of paper section 5 (eq. 13) at 10k, 100k and 1M agents:
// the parallel block Gauss-Seidel against Eigen's SimplicialLDLT and
// ConjugateGradient, and the Gauss-Seidel sweep throughput.
//
// The system: agents on a wavy sheet (jittered grid), one-rings and encoding on
// that "original" shape; the start ("warped") shape has a bump; the border and a
// middle line are fixed (body and feature constraints), the rest solve eq. 13.
// Eq. 13 is not symmetric, so the Eigen solvers get the normal equations
// A^T A x = A^T b (what a symmetric solver needs); the reported difference is
// the largest |x_GS - x_Eigen| over agents.
#include <refit/core/parallel.hpp>
#include <refit/surface/agent_system.hpp>
#include <refit/surface/agents.hpp>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>

namespace {

using namespace refit;

struct System {
  AgentRows rows;
  BlockSchedule schedule;
  std::vector<std::uint8_t> free;
  Points start;
};

std::shared_ptr<const System> make_system(std::size_t n) {
  static std::map<std::size_t, std::shared_ptr<const System>> cache;
  if (auto it = cache.find(n); it != cache.end()) return it->second;
  const int side = static_cast<int>(std::sqrt(double(n)));
  Points p(side * side, 3);
  std::vector<std::uint64_t> morton(p.rows());
  for (int i = 0; i < side; ++i)
    for (int k = 0; k < side; ++k) {
      const double jx = 0.2 * std::sin(12.9898 * i + 78.233 * k), jz = 0.2 * std::cos(39.3467 * i + 11.135 * k);
      const double x = i + jx, z = k + jz;
      p.row(i * side + k) << x, 2.0 * std::sin(0.05 * x) * std::cos(0.07 * z), z;
      morton[i * side + k] = VoxelGrid::morton({std::uint32_t(i), std::uint32_t(k), 0});
    }
  Csr ring0 = build_one_rings(p, 3.0);
  const double width = std::max(longest_edge(p, ring0) * (1 + 1e-6), 8.0);
  const auto order = make_block_order(p, morton, width);
  std::vector<Index> slot(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) slot[order[k]] = Index(k);
  Points q(p.rows(), 3);
  Csr ring;
  for (std::size_t k = 0; k < order.size(); ++k) {
    q.row(Eigen::Index(k)) = p.row(order[k]);
    std::vector<Index> r(ring0.row(order[k]).begin(), ring0.row(order[k]).end());
    for (Index& v : r) v = slot[v];
    ring.push_row(r);
  }
  auto s = std::make_shared<System>();
  s->rows = encode_agents(q, std::move(ring));
  s->schedule = make_schedule(q, s->rows.ring, width);
  s->free.assign(q.rows(), 1);
  s->start = q;
  const double c = side / 2.0;
  for (Eigen::Index a = 0; a < q.rows(); ++a) {
    const double dx = q(a, 0) - c, dz = q(a, 2) - c;
    if (std::min({q(a, 0), q(a, 2), side - 1 - q(a, 0), side - 1 - q(a, 2)}) < 1.0 || std::abs(dx) < 0.5)
      s->free[a] = 0;  // border (body) and a middle line (feature)
    s->start(a, 1) += 0.1 * side * std::exp(-(dx * dx + dz * dz) / (0.1 * side * side));
  }
  cache[n] = s;
  return s;
}

// x with eq. 13 solved by Gauss-Seidel, for the comparisons.
Points gs_solution(const System& s, int iterations) {
  Points x = s.start;
  gauss_seidel(s.rows, s.schedule, s.free, x, {iterations, 1e-5});
  return x;
}

void BM_GaussSeidel(benchmark::State& state) {
  const auto s = make_system(std::size_t(state.range(0)));
  const int iterations = int(state.range(1));
  SolveReport rep;
  for (auto _ : state) {
    Points x = s->start;
    rep = gauss_seidel(s->rows, s->schedule, s->free, x, {iterations, 1e-5});
    benchmark::DoNotOptimize(x.data());
  }
  const double updates = double(s->rows.size()) * rep.iterations;
  state.counters["agents"] = double(s->rows.size());
  state.counters["iterations"] = rep.iterations;
  state.counters["final_update"] = rep.final_update;
  state.counters["converged"] = rep.converged;
  state.counters["updates_per_s"] = benchmark::Counter(updates * double(state.iterations()), benchmark::Counter::kIsRate);
  // Per update: row (diag 8, h 24, ring offsets 4) + per neighbour (index 4, weight 8,
  // position 24 mostly cached) + own position read/write 48 bytes.
  const double deg = double(s->rows.ring.indices.size()) / double(s->rows.size());
  state.counters["bytes_per_update"] = 8 + 24 + 4 + deg * 12 + 48;
}

// Eq. 13 for the free agents as A x = b (fixed agents moved to b), one coordinate at a time.
struct Assembled {
  Eigen::SparseMatrix<double> a;
  Eigen::MatrixXd b;
  std::vector<Eigen::Index> var;  // agent -> unknown (-1 fixed)
};
Assembled assemble(const System& s) {
  Assembled out;
  const std::size_t n = s.rows.size();
  out.var.assign(n, -1);
  Eigen::Index m = 0;
  for (std::size_t a = 0; a < n; ++a)
    if (s.free[a]) out.var[a] = m++;
  std::vector<Eigen::Triplet<double>> t;
  out.b = Eigen::MatrixXd::Zero(m, 3);
  for (std::size_t a = 0; a < n; ++a) {
    if (out.var[a] < 0) continue;
    const Eigen::Index r = out.var[a];
    t.emplace_back(r, r, s.rows.diag[a]);
    out.b.row(r) = s.rows.h.row(Eigen::Index(a));
    for (Index k = s.rows.ring.offsets[a]; k < s.rows.ring.offsets[a + 1]; ++k) {
      const Index j = s.rows.ring.indices[k];
      if (out.var[j] >= 0) t.emplace_back(r, out.var[j], -s.rows.weight[k]);
      else out.b.row(r) += s.rows.weight[k] * s.start.row(Eigen::Index(j));
    }
  }
  out.a.resize(m, m);
  out.a.setFromTriplets(t.begin(), t.end());
  return out;
}
double difference(const System& s, const Assembled& as, const Eigen::MatrixXd& x, const Points& gs) {
  double worst = 0.0;
  for (std::size_t a = 0; a < s.rows.size(); ++a)
    if (as.var[a] >= 0) worst = std::max(worst, (x.row(as.var[a]) - gs.row(Eigen::Index(a))).cwiseAbs().maxCoeff());
  return worst;
}

template <class Solver>
void eigen_bench(benchmark::State& state, Solver& solver) {
  const auto s = make_system(std::size_t(state.range(0)));
  const Assembled as = assemble(*s);
  const Eigen::SparseMatrix<double> normal = as.a.transpose() * as.a;
  const Eigen::MatrixXd rhs = as.a.transpose() * as.b;
  Eigen::MatrixXd x;
  for (auto _ : state) {
    solver.compute(normal);
    x = solver.solve(rhs);
    benchmark::DoNotOptimize(x.data());
  }
  state.counters["agents"] = double(s->rows.size());
  state.counters["max_diff_vs_gs500"] = difference(*s, as, x, gs_solution(*s, 500));
  state.counters["max_diff_vs_gs5000"] = difference(*s, as, x, gs_solution(*s, 5000));
}

void BM_EigenLDLT(benchmark::State& state) {
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  eigen_bench(state, solver);
}
void BM_EigenCG(benchmark::State& state) {
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> solver;
  solver.setTolerance(1e-10);
  eigen_bench(state, solver);
}

BENCHMARK(BM_GaussSeidel)->Args({10000, 500})->Args({100000, 500})->Args({1000000, 500})->Args({1000000, 10})
    ->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_EigenLDLT)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_EigenCG)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
