// The garment locator on a real garment (issue 14): its build (the element
// tree over the garment's faces, lines and points) and the attachment of every
// vertex's mirror image, as the symmetry binding does. Prints each part's wall
// and CPU time (medians of the runs).
//   locator_dense GARMENT.obj BODY_A.obj [runs] [threads]
#include <refit/attach/attachment.hpp>
#include <refit/core/parallel.hpp>
#include <refit/features/symmetry.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <string>
#include <vector>

namespace {

struct Clock {
  std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
  std::clock_t cpu = std::clock();
  void lap(std::vector<double>& wall_ms, std::vector<double>& cpu_ms) {
    const auto w = std::chrono::steady_clock::now();
    const std::clock_t c = std::clock();
    wall_ms.push_back(std::chrono::duration<double, std::milli>(w - wall).count());
    cpu_ms.push_back(1000.0 * double(c - cpu) / CLOCKS_PER_SEC);
    wall = w, cpu = c;
  }
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: locator_dense GARMENT.obj BODY_A.obj [runs] [threads]\n";
    return 2;
  }
  try {
    const int runs = argc > 3 ? std::stoi(argv[3]) : 3;
    const refit::ThreadLimit limit(argc > 4 ? std::stoul(argv[4]) : 0);
    const refit::Garment g = refit::read_garment_obj(argv[1]);
    const refit::BodyMesh body = refit::read_body(argv[2]);
    const refit::Points mirrored = refit::mirror_x(g.positions, refit::mirror_plane_x(body.vertices));
    std::vector<double> build_ms, build_cpu, attach_ms, attach_cpu;
    double checksum = 0.0;
    for (int k = 0; k < runs; ++k) {
      Clock clock;
      const refit::GarmentLocator locator(g);
      clock.lap(build_ms, build_cpu);
      const refit::SurfaceAttachment at = locator.attach(mirrored);
      clock.lap(attach_ms, attach_cpu);
      checksum = 0.0;
      for (double d : refit::offset_lengths(at)) checksum += d;
    }
    std::printf("vertices %zu, runs %d (medians)\nbuild  %6.0f ms wall %6.0f ms CPU\nattach %6.0f ms wall %6.0f ms CPU\n"
                "mean mirror distance %.9g\n",
                g.vertex_count(), runs, median(build_ms), median(build_cpu), median(attach_ms), median(attach_cpu),
                checksum / double(g.vertex_count()));
  } catch (const std::exception& e) {
    std::cerr << "locator_dense: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
