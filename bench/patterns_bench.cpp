// Flattening one large pattern piece (engine/refit/patterns/flatten.hpp), the
// speed target of issue 16: a 100k-face panel in at most 1 s with 2 threads.
//
//     build/release/bench/patterns_bench [--repeat 5] [--threads 1 2] [--faces 100000]
//     build/release/bench/patterns_bench --garment G.obj [--seam-tolerance 0.001] [--repeat 5] [--threads 1 2]
//
// The piece: a quarter-wide strip of a cylinder (radius 20 cm, 80 cm tall,
// 180 degrees around) with smooth bumps of 1 cm (wavelength 20 cm), so it is not
// developable and ARAP has work to do, like cloth over a body. Two meshings of
// about --faces faces: triangles (a regular grid, each cell split in two) and
// quads (the grid's cells; the flattener fans them into two triangles each).
// Per case and thread count: the median over --repeat runs of the wall time,
// of the process's CPU time (user + system, all threads) and of the three
// parts (factorisation, conformal start, ARAP iterations), the iterations and
// the stretch reached (95th percentile of per-triangle |log s|).
//
// With --garment, a real garment instead (e.g. the shared skirt densified by
// ../shared/data/make_dense.py): cut into its panels and flattened as `refit
// flatten` does (flatten_pattern: plain ARAP, then again with the seams held
// where they came out apart); per panel of 1000 faces or more, the medians of
// its flattening time (the report's flatten_ms) and whether its seams were held.
#include <refit/core/parallel.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/patterns/flatten.hpp>
#include <refit/patterns/pattern.hpp>

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

namespace {

using namespace refit;

struct Piece {
  Points xyz;
  std::vector<Triangle> triangles;
  std::size_t faces = 0;
};

Piece bumpy_cylinder(std::size_t target_faces, bool quads) {
  // n x n vertices: (n-1)^2 cells, two triangles each unless quads.
  const double cells = quads ? static_cast<double>(target_faces) : 0.5 * static_cast<double>(target_faces);
  const std::size_t n = static_cast<std::size_t>(std::ceil(std::sqrt(cells))) + 1;
  Piece p;
  p.xyz.resize(static_cast<Eigen::Index>(n * n), 3);
  const double pi = std::numbers::pi;
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t i = 0; i < n; ++i) {
      const double a = pi * static_cast<double>(i) / static_cast<double>(n - 1);
      const double y = 80.0 * static_cast<double>(j) / static_cast<double>(n - 1);
      const double arc = 20.0 * a;  // cm along the circumference
      const double r = 20.0 + std::sin(2 * pi * arc / 20.0) * std::sin(2 * pi * y / 20.0);
      p.xyz.row(static_cast<Eigen::Index>(j * n + i)) << r * std::cos(a), y, r * std::sin(a);
    }
  for (std::size_t j = 0; j + 1 < n; ++j)
    for (std::size_t i = 0; i + 1 < n; ++i) {
      const Index a = static_cast<Index>(j * n + i), b = a + 1, c = a + static_cast<Index>(n) + 1, d = a + static_cast<Index>(n);
      p.triangles.push_back({a, b, c});
      p.triangles.push_back({a, c, d});
    }
  p.faces = quads ? (n - 1) * (n - 1) : p.triangles.size();
  return p;
}

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

double stretch_p95(const Piece& p, const Points2& uv) {
  std::vector<double> s;
  for (const Triangle& t : p.triangles) {
    const Vec3 e1 = row3(p.xyz, t[1]) - row3(p.xyz, t[0]), e2 = row3(p.xyz, t[2]) - row3(p.xyz, t[0]);
    const double l1 = e1.norm();
    Eigen::Matrix2d X, U;
    X << l1, e2.dot(e1) / l1, 0, e1.cross(e2).norm() / l1;
    U << (uv.row(t[1]) - uv.row(t[0])).transpose(), (uv.row(t[2]) - uv.row(t[0])).transpose();
    const Eigen::JacobiSVD<Eigen::Matrix2d> svd(U * X.inverse());
    s.push_back(std::max(std::abs(std::log(svd.singularValues()(0))), std::abs(std::log(svd.singularValues()(1)))));
  }
  std::sort(s.begin(), s.end());
  return s[s.size() * 95 / 100];
}

// The --garment mode (see the top).
void bench_garment(const std::string& file, const std::vector<std::size_t>& threads, int repeat, double seam_tolerance,
                   const FlattenOptions& flatten) {
  const Garment g = read_garment_obj(file);
  const PatternCut cut = cut_pattern(g, {}, file);
  PatternOptions options;
  options.skip_unflattenable = true;
  options.seam_tolerance = seam_tolerance;
  options.flatten = flatten;
  std::printf("| panel | faces | threads | flatten ms | seams held | iterations | stretch p95 | whole pattern wall ms |\n"
              "|---|---:|---:|---:|---|---:|---:|---:|\n");
  for (std::size_t t : threads) {
    const ThreadLimit limit(t);
    std::vector<std::vector<double>> ms(cut.panels.panels.size());
    std::vector<double> wall;
    Pattern last;
    for (int r = 0; r < repeat; ++r) {
      const auto w0 = std::chrono::steady_clock::now();
      last = flatten_pattern(g, cut, g.positions, options);
      wall.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - w0).count());
      for (std::size_t k = 0; k < ms.size(); ++k) ms[k].push_back(last.pieces[k].flatten_ms);
    }
    for (std::size_t k = 0; k < ms.size(); ++k) {
      const Panel& panel = cut.panels.panels[k];
      if (panel.faces.size() < 1000 || !last.pieces[k].flattened) continue;
      std::printf("| %s | %zu | %zu | %.0f | %s | %d | %.4f | %.0f |\n", panel.name.c_str(), panel.faces.size(), t,
                  median(ms[k]), last.pieces[k].seams_held ? "yes" : "no", last.pieces[k].iterations,
                  last.pieces[k].measures.stretch_p95, median(wall));
    }
    std::fflush(stdout);
  }
}

}  // namespace

int main(int argc, char** argv) {
  int repeat = 5;
  std::size_t faces = 100000;
  std::vector<std::size_t> threads = {1, 2};
  FlattenOptions options;
  std::string garment;
  double seam_tolerance = PatternOptions{}.seam_tolerance;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--faces") && i + 1 < argc) faces = std::strtoul(argv[++i], nullptr, 10);
    else if (!std::strcmp(argv[i], "--conformal-iterations") && i + 1 < argc)
      options.conformal_iterations = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--garment") && i + 1 < argc) garment = argv[++i];
    else if (!std::strcmp(argv[i], "--seam-tolerance") && i + 1 < argc) seam_tolerance = std::atof(argv[++i]);
    else if (!std::strcmp(argv[i], "--threads")) {
      threads.clear();
      while (i + 1 < argc && argv[i + 1][0] != '-') threads.push_back(std::strtoul(argv[++i], nullptr, 10));
    } else {
      std::fprintf(stderr, "usage: patterns_bench [--repeat N] [--faces N] [--threads T...] [--conformal-iterations N]\n"
                           "       patterns_bench --garment G.obj [--seam-tolerance X] [--repeat N] [--threads T...] [--conformal-iterations N]\n");
      return 2;
    }
  }
  if (!garment.empty()) {
    bench_garment(garment, threads, repeat, seam_tolerance, options);
    return 0;
  }
  std::printf("| mesh | faces | triangles | threads | wall ms | CPU ms | factor ms | conformal ms (iterations) | "
              "ARAP ms (iterations) | stretch p95 |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (bool quads : {false, true}) {
    const Piece piece = bumpy_cylinder(faces, quads);
    for (std::size_t t : threads) {
      const ThreadLimit limit(t);
      std::vector<double> wall, cpu, factor, conformal, arap;
      Flattening last;
      for (int r = 0; r < repeat; ++r) {
        const double c0 = cpu_seconds();
        const auto w0 = std::chrono::steady_clock::now();
        last = flatten_piece(piece.xyz, piece.triangles, options);
        wall.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - w0).count());
        cpu.push_back(1e3 * (cpu_seconds() - c0));
        factor.push_back(last.factor_ms);
        conformal.push_back(last.conformal_ms);
        arap.push_back(last.arap_ms);
      }
      std::printf("| %s | %zu | %zu | %zu | %.0f | %.0f | %.0f | %.0f (%d) | %.0f (%d) | %.4f |\n",
                  quads ? "quads" : "triangles", piece.faces, piece.triangles.size(), t, median(wall), median(cpu),
                  median(factor), median(conformal), last.conformal_iterations, median(arap), last.iterations,
                  stretch_p95(piece, last.uv));
      std::fflush(stdout);
    }
  }
  return 0;
}
