// The surface step's fine solve (eq. 13 with eqs. 14-15) on the pipeline's real
// agent system, against Eigen's solvers, in one run:
//
//     build/release/bench/surface_bench [--agents 10000 100000 1000000] [--vertices 1000000] [--repeat 3]
//                                       [--threads 2] [--limit-s 120]
//
// The system: the procedural dress (tools/mannequin, as `refit generate
// --vertices N`) on body A, warped (step 1) to body B of bench/scalability.py;
// feature targets as in tests/surface/surface_dress_test.cpp (each original
// profile moved onto its warped one by the best similarity: no step 2), bound
// with SurfaceBinding at each agent budget and applied with body B's distances;
// the fine system of apply's last solve (free agents after the clearance
// rounds, the coarse-to-fine start) is what every solver gets.
//
// Solvers: the shipped one (BiCGSTAB preconditioned by one V-cycle), the bare
// V-cycles it replaced, 500 plain Gauss-Seidel sweeps, Eigen's SparseLU on
// A x = b (the direct reference), SimplicialLDLT and ConjugateGradient on the
// normal equations A^T A x = A^T b (eq. 13 is not symmetric), and BiCGSTAB on
// A itself (Jacobi and IncompleteLUT preconditioners). The Eigen iterative
// solvers stop at a relative residual of 1e-10 or when the time limit would be
// passed (iteration cap from a short probe). A direct solver is skipped where
// its time at the previous size, grown like n^1.5, predicts more than the time
// limit; an iterative one (capped anyway) where it predicts 4 times that.
//
// Memory: peak resident set above the baseline while the solver runs (VmHWM
// after resetting it through /proc/self/clear_refs, baseline VmRSS after
// malloc_trim), so it includes the solver's own setup (assembly, factor,
// multigrid hierarchy) but not the bound system.
#include <refit/body/body_surface.hpp>
#include <refit/core/parallel.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/surface/surface.hpp>
#include <refit/warp/warp.hpp>

#include <mannequin/mannequin.hpp>

#include <Eigen/Geometry>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>

#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace refit;
namespace mq = refit::mannequin;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

long status_kb(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind(key, 0) == 0) return std::atol(line.c_str() + std::strlen(key));
  return 0;
}
// Peak resident memory (MB) above the baseline while f runs.
template <class F>
double peak_mb(F&& f) {
  malloc_trim(0);
  { std::ofstream("/proc/self/clear_refs") << "5"; }
  const long base = status_kb("VmRSS:");
  f();
  return double(status_kb("VmHWM:") - base) / 1024.0;
}

struct Args {
  std::vector<std::size_t> agents{10000, 100000, 1000000};
  std::size_t vertices = 1000000;
  int repeat = 3, threads = 2;
  double limit_s = 120.0;
  bool ours_only = false;  // no Eigen solvers (no direct reference either): for profiling
};

// Eq. 13 on the free agents as A x = b (fixed agents moved to b).
struct Assembled {
  Eigen::SparseMatrix<double> a;
  Eigen::MatrixXd b;
  std::vector<Eigen::Index> var;  // agent -> unknown (-1 fixed)
};
Assembled assemble(const AgentRows& rows, const SurfaceSystem& sys) {
  Assembled out;
  const std::size_t n = rows.size();
  out.var.assign(n, -1);
  Eigen::Index m = 0;
  for (std::size_t a = 0; a < n; ++a)
    if (sys.free[a]) out.var[a] = m++;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(rows.ring.indices.size() + std::size_t(m));
  out.b = Eigen::MatrixXd::Zero(m, 3);
  for (std::size_t a = 0; a < n; ++a) {
    if (out.var[a] < 0) continue;
    const Eigen::Index r = out.var[a];
    t.emplace_back(r, r, rows.diag[a]);
    out.b.row(r) = sys.h.row(Eigen::Index(a));
    for (Index k = rows.ring.offsets[a]; k < rows.ring.offsets[a + 1]; ++k) {
      const Index j = rows.ring.indices[k];
      if (out.var[j] >= 0) t.emplace_back(r, out.var[j], -rows.weight[k]);
      else out.b.row(r) += rows.weight[k] * sys.start.row(Eigen::Index(j));
    }
  }
  out.a.resize(m, m);
  out.a.setFromTriplets(t.begin(), t.end());
  return out;
}
Eigen::MatrixXd free_rows(const Assembled& as, const Points& x) {
  Eigen::MatrixXd out(as.a.rows(), 3);
  for (std::size_t k = 0; k < as.var.size(); ++k)
    if (as.var[k] >= 0) out.row(as.var[k]) = x.row(Eigen::Index(k));
  return out;
}

struct Row {
  explicit Row(std::string s) : solver(std::move(s)) {}
  std::string solver, note;
  double ms = NAN, mb = NAN, diff = NAN;
  std::optional<bool> converged;
};

void print_row(std::size_t agents, const Row& r) {
  std::printf("| %zu | %s | %s | %s | %s | %s | %s |\n", agents, r.solver.c_str(),
              std::isnan(r.ms) ? "-" : (std::to_string(long(std::lround(r.ms)))).c_str(),
              std::isnan(r.mb) ? "-" : (std::to_string(long(std::lround(r.mb)))).c_str(),
              !r.converged ? "-" : (*r.converged ? "yes" : "no"),
              std::isnan(r.diff) ? "-" : [&] {
                static char b[32];
                std::snprintf(b, sizeof b, "%.1e", r.diff);
                return b;
              }(),
              r.note.c_str());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (k == "--agents") {
      args.agents.clear();
      while (i + 1 < argc && argv[i + 1][0] != '-') args.agents.push_back(std::stoul(argv[++i]));
    } else if (k == "--vertices") {
      args.vertices = std::stoul(next());
    } else if (k == "--repeat") {
      args.repeat = std::stoi(next());
    } else if (k == "--threads") {
      args.threads = std::stoi(next());
    } else if (k == "--limit-s") {
      args.limit_s = std::stod(next());
    } else if (k == "--ours-only") {
      args.ours_only = true;
    } else {
      std::fprintf(stderr, "usage: surface_bench [--agents N...] [--vertices N] [--repeat R] [--threads T] [--limit-s S] [--ours-only]\n");
      return 2;
    }
  }
  const ThreadLimit limit(std::size_t(args.threads));

  // Bodies as bench/scalability.py (`refit generate` and `--belly 6 --hip 104 --waist 76 --bust 92`).
  const mq::BodyParams pa{};
  mq::BodyParams pb = pa;
  pb.belly = 6;
  pb.hip = 104;
  pb.waist = 76;
  pb.bust = 92;
  mq::GarmentParams gp;
  gp.kind = mq::GarmentParams::Kind::Dress;
  gp.target_vertices = args.vertices;
  auto t0 = Clock::now();
  const Garment dress = mq::make_garment(pa, gp);
  const ReferenceBody ref(mq::make_body(pa));
  const BodyMesh body_b = mq::make_body(pb);
  const TriangleFrames frames_b = compute_frames(body_b);
  const BodySurface surface_b(body_b);
  const Points warped = ref.bind(dress.positions).apply(frames_b);
  const auto specs = parse_feature_json(mq::dress_features_json(pa, gp), "dress_features.json", "cm");
  const auto curves = build_feature_curves(dress, specs);
  std::size_t m = 0;
  for (const auto& fc : curves) m += std::size_t(fc.samples.rows());
  Points samples(Eigen::Index(m), 3), targets(Eigen::Index(m), 3);
  Eigen::Index row = 0;
  for (const auto& fc : curves) {
    samples.middleRows(row, fc.samples.rows()) = fc.samples;
    row += fc.samples.rows();
  }
  const Points fwarped = ref.bind(samples).apply(frames_b);
  row = 0;
  for (const auto& fc : curves) {
    const Eigen::Index k = fc.samples.rows();
    const Eigen::Matrix3Xd src = fc.samples.transpose(), dst = fwarped.middleRows(row, k).transpose();
    const Eigen::Matrix4d t = Eigen::umeyama(src, dst, true);
    targets.middleRows(row, k) = ((t.topLeftCorner<3, 3>() * src).colwise() + t.topRightCorner<3, 1>()).transpose();
    row += k;
  }
  std::printf("procedural dress: %zu vertices, %zu feature samples, %d threads; inputs built in %.1f s\n\n",
              dress.vertex_count(), m, args.threads, seconds_since(t0));

  std::printf("| agents | solver | ms | MB | converged | max diff to direct | notes |\n|---:|---|---:|---:|---|---:|---|\n");
  std::vector<std::string> throughput;
  // Time per solver at the previous size, to predict the next one.
  std::map<std::string, std::pair<std::size_t, double>> last;
  auto predicted_s = [&](const std::string& name, std::size_t n, double exponent) {
    auto it = last.find(name);
    if (it == last.end()) return 0.0;
    return it->second.second * std::pow(double(n) / double(it->second.first), exponent) / 1000.0;
  };

  for (const std::size_t budget : args.agents) {
    SurfaceOptions so;
    so.agent_budget = budget;
    t0 = Clock::now();
    const SurfaceBinding sb = SurfaceBinding::bind(dress, samples, so);
    const double bind_s = seconds_since(t0);
    SurfaceSystem sys;
    const SurfaceResult res = sb.apply(warped, targets, surface_b, &fwarped, &sys);
    const std::size_t n = sb.agent_count();
    const AgentRows& rows = sb.rows();
    const auto nfree = std::count(sys.free.begin(), sys.free.end(), std::uint8_t{1});
    std::fprintf(stderr, "%zu agents (%td free), bind %.1f s; pipeline solve %d sweeps, %d BiCGSTAB iterations, %.0f ms\n",
                 n, nfree, bind_s, res.stats.iterations, res.stats.krylov_iterations, res.stats.ms.solve);

    // The direct reference.
    const Assembled as = assemble(rows, sys);
    Eigen::MatrixXd direct;
    Row lu{"Eigen SparseLU (A, direct reference)"};
    if (args.ours_only) {
      lu.note = "skipped (--ours-only)";
    } else if (predicted_s("lu", n, 1.5) > args.limit_s) {
      lu.note = "skipped: predicted " + std::to_string(int(predicted_s("lu", n, 1.5))) + " s";
    } else {
      Eigen::SparseLU<Eigen::SparseMatrix<double>> solver;
      t0 = Clock::now();
      lu.mb = peak_mb([&] {
        solver.compute(as.a);
        direct = solver.solve(as.b);
      });
      lu.ms = seconds_since(t0) * 1000;
      lu.converged = solver.info() == Eigen::Success;
      lu.diff = 0.0;
      last["lu"] = {n, lu.ms};
    }
    auto diff = [&](const Eigen::MatrixXd& x) {
      return direct.rows() == x.rows() ? (x - direct).cwiseAbs().maxCoeff() : NAN;
    };
    auto diff_points = [&](const Points& x) { return diff(free_rows(as, x)); };

    // Ours: median of `repeat` runs from the same start.
    auto ours = [&](const std::string& name, FineSolver which, int repeat) {
      Row r{name};
      std::vector<double> ms;
      Points x;
      SolveReport rep;
      int krylov = 0;
      for (int k = 0; k < repeat; ++k) {
        x = sys.start;
        krylov = 0;
        const auto t = Clock::now();
        const double mb = peak_mb([&] { rep = sb.solve(sys.h, sys.free, x, {500, 1e-5, 1.0}, which, &krylov); });
        ms.push_back(seconds_since(t) * 1000);
        r.mb = k == 0 ? mb : std::max(r.mb, mb);
      }
      std::sort(ms.begin(), ms.end());
      r.ms = ms[ms.size() / 2];
      r.converged = rep.converged;
      r.diff = diff_points(x);
      char b[160];
      std::snprintf(b, sizeof b, "%d fine sweeps%s, update %.1e; runs ms %.0f..%.0f", rep.iterations,
                    which == FineSolver::krylov ? (", " + std::to_string(krylov) + " BiCGSTAB it.").c_str() : "",
                    rep.final_update, ms.front(), ms.back());
      r.note = b;
      return r;
    };
    print_row(n, ours("shipped: BiCGSTAB + V-cycle", FineSolver::krylov, args.repeat));
    print_row(n, ours("bare V-cycles (before)", FineSolver::v_cycles, std::max(1, args.repeat / 2)));
    print_row(n, ours("Gauss-Seidel, 500 sweeps", FineSolver::sweeps, 1));
    print_row(n, lu);

    // Sweep throughput: 50 sweeps, no stopping; bytes per update from the layout:
    // row (diag 8, h 3 x 8, ring offset 4, free and sequential flags 2) + per
    // neighbour (index 4, weight 8; its position mostly cached) + own position
    // read and written (2 x 24).
    {
      Points x = sys.start;
      std::vector<double> ms;
      for (int k = 0; k < std::max(3, args.repeat); ++k) {
        x = sys.start;
        const auto t = Clock::now();
        gauss_seidel(rows, sys.h, sb.schedule(), sys.free, x, {50, 0.0, 1.0});
        ms.push_back(seconds_since(t) * 1000);
      }
      std::sort(ms.begin(), ms.end());
      const double med = ms[ms.size() / 2];
      const double ups = 50.0 * double(n) / (med / 1000.0);
      const double deg = double(rows.ring.indices.size()) / double(n);
      const double bytes = 8 + 24 + 4 + 2 + deg * 12 + 48;
      char b[256];
      std::snprintf(b, sizeof b,
                    "| %zu | %.2f | %.0f | %.1f | %.0f | %.1f | %.0f%%-%.0f%% |", n, med / 50.0, ups / 1e6, deg, bytes,
                    ups * bytes / 1e9, 100.0 * ups * bytes / 28e9, 100.0 * ups * bytes / 25e9);
      throughput.push_back(b);
    }

    if (args.ours_only) continue;
    // Eigen iterative solvers: relative residual 1e-10, capped by time.
    auto iterative = [&](const std::string& name, const std::string& key, auto& solver,
                         const Eigen::SparseMatrix<double>& a, const Eigen::MatrixXd& b, double exponent) {
      Row r{name};
      if (predicted_s(key, n, exponent) > 4 * args.limit_s) {
        r.note = "skipped: predicted " + std::to_string(int(predicted_s(key, n, exponent))) + " s";
        print_row(n, r);
        return;
      }
      Eigen::MatrixXd x;
      t0 = Clock::now();
      r.mb = peak_mb([&] {
        solver.setTolerance(1e-10);
        solver.compute(a);
        // Probe: 20 iterations on one coordinate give the time per iteration.
        const auto tp = Clock::now();
        solver.setMaxIterations(20);
        const Eigen::VectorXd probe = solver.solve(b.col(0));
        (void)probe;
        const double per_it = seconds_since(tp) / std::max<Eigen::Index>(1, solver.iterations());
        const Eigen::Index cap = std::max<Eigen::Index>(20, Eigen::Index(args.limit_s / 3 / std::max(per_it, 1e-9)));
        solver.setMaxIterations(cap);
        x.resize(b.rows(), 3);
        bool ok = true;
        Eigen::Index its = 0;
        for (int c = 0; c < 3; ++c) {
          x.col(c) = solver.solve(b.col(c));
          ok = ok && solver.info() == Eigen::Success;
          its = std::max(its, solver.iterations());
        }
        r.converged = ok;
        r.note = "at most " + std::to_string(its) + " iterations per coordinate (cap " + std::to_string(cap) + ")";
      });
      r.ms = seconds_since(t0) * 1000;
      r.diff = diff(x);
      last[key] = {n, r.ms};
      print_row(n, r);
    };
    // Normal equations for the symmetric solvers.
    const Eigen::SparseMatrix<double> at = as.a.transpose();
    const Eigen::SparseMatrix<double> normal = at * as.a;
    const Eigen::MatrixXd rhs = at * as.b;
    {
      Row r{"Eigen SimplicialLDLT (A^T A)"};
      if (predicted_s("ldlt", n, 1.5) > args.limit_s) {
        r.note = "skipped: predicted " + std::to_string(int(predicted_s("ldlt", n, 1.5))) + " s";
      } else {
        Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
        Eigen::MatrixXd x;
        t0 = Clock::now();
        r.mb = peak_mb([&] {
          solver.compute(normal);
          x = solver.solve(rhs);
        });
        r.ms = seconds_since(t0) * 1000;
        r.converged = solver.info() == Eigen::Success;
        r.diff = diff(x);
        last["ldlt"] = {n, r.ms};
      }
      print_row(n, r);
    }
    {
      Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg;
      iterative("Eigen ConjugateGradient (A^T A, Jacobi)", "cg", cg, normal, rhs, 1.5);
    }
    {
      Eigen::BiCGSTAB<Eigen::SparseMatrix<double>> bicg;
      iterative("Eigen BiCGSTAB (A, Jacobi)", "bicgstab", bicg, as.a, as.b, 1.5);
    }
    {
      Eigen::BiCGSTAB<Eigen::SparseMatrix<double>, Eigen::IncompleteLUT<double>> ilu;
      iterative("Eigen BiCGSTAB (A, IncompleteLUT)", "ilut", ilu, as.a, as.b, 1.5);
    }

  }
  std::printf("\nGauss-Seidel sweep throughput (median of the runs, 50 sweeps each):\n\n");
  std::printf("| agents | ms per sweep | M updates/s | ring degree | bytes/update | GB/s | of 25-28 GB/s |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& l : throughput) std::printf("%s\n", l.c_str());
  return 0;
}
