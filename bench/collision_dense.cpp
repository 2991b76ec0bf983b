// The collision step alone on a real garment (issue 14): the garment as the
// pipeline leaves it before the step (`refit resize ... --no-collision --out G.obj`)
// and body B. Prints the step's wall and CPU time (medians of the runs) and its report.
//   collision_dense G.obj BODY_B.obj [runs] [threads] [out.obj]
#include <refit/collision/collision.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: collision_dense GARMENT.obj BODY_B.obj [runs] [threads] [out.obj]\n";
    return 2;
  }
  try {
    const int runs = argc > 3 ? std::stoi(argv[3]) : 3;
    const refit::ThreadLimit limit(argc > 4 ? std::stoul(argv[4]) : 0);
    const refit::Garment g = refit::read_garment_obj(argv[1]);
    const refit::BodySurface body(refit::read_body(argv[2]));
    body.prepare_inside_test();
    std::vector<double> ms, cpu_ms;
    refit::Points out;
    refit::CollisionReport r;
    for (int k = 0; k < runs; ++k) {
      out = g.positions;
      const auto t0 = std::chrono::steady_clock::now();
      const std::clock_t c0 = std::clock();
      r = refit::resolve_penetrations(g, out, body);
      ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      cpu_ms.push_back(1000.0 * double(std::clock() - c0) / CLOCKS_PER_SEC);
    }
    std::sort(ms.begin(), ms.end());
    std::sort(cpu_ms.begin(), cpu_ms.end());
    std::printf("collision %.0f ms wall, %.0f ms CPU (medians of %d)\n%s\n", ms[ms.size() / 2], cpu_ms[ms.size() / 2], runs,
                r.to_json().dump().c_str());
    if (argc > 5) refit::write_garment_obj(argv[5], g, out);
  } catch (const std::exception& e) {
    std::cerr << "collision_dense: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
