// The fold smoothing alone on a real garment (issue 14): the garment as given
// (the original, where the folds are judged from) and positions with folds in
// them, such as its warp to a thinner body (`refit resize ... --stage warp --out
// W.obj`: the 1M dress on F_thinner folds some 29 thousand faces at the waist).
// Prints the smoothing's wall and CPU time (medians of the runs) and its figures.
//   folds_dense GARMENT.obj FOLDED.obj [runs] [threads]
#include <refit/core/parallel.hpp>
#include <refit/core/topology.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/surface/folds.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: folds_dense GARMENT.obj FOLDED.obj [runs] [threads]\n";
    return 2;
  }
  try {
    const int runs = argc > 3 ? std::stoi(argv[3]) : 3;
    const refit::ThreadLimit limit(argc > 4 ? std::stoul(argv[4]) : 0);
    const refit::Garment g = refit::read_garment_obj(argv[1]);
    const refit::Garment folded = refit::read_garment_obj(argv[2]);
    if (folded.positions.rows() != g.positions.rows()) throw std::runtime_error("the two garments differ in vertices");
    const refit::FoldBinding binding = refit::bind_folds(g);
    const refit::Csr adjacency = refit::vertex_adjacency(g);
    std::vector<double> ms, cpu_ms;
    refit::FoldReport r;
    for (int k = 0; k < runs; ++k) {
      refit::Points p = folded.positions;
      const auto t0 = std::chrono::steady_clock::now();
      const std::clock_t c0 = std::clock();
      r = refit::smooth_out_folds(g, binding, p, adjacency, nullptr, {});
      ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      cpu_ms.push_back(1000.0 * double(std::clock() - c0) / CLOCKS_PER_SEC);
    }
    std::sort(ms.begin(), ms.end());
    std::sort(cpu_ms.begin(), cpu_ms.end());
    std::printf("fold smoothing %.0f ms wall, %.0f ms CPU (medians of %d): folded %zu, left %zu, smoothed %zu, rounds %d\n",
                ms[ms.size() / 2], cpu_ms[ms.size() / 2], runs, r.folded_before, r.folded_after, r.smoothed, r.rounds);
  } catch (const std::exception& e) {
    std::cerr << "folds_dense: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
