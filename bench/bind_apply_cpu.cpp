// CPU time of binding a garment and applying the binding to one body, from C++:
// the reference bench/python_overhead.py compares the Python module with.
//   bind_apply_cpu GARMENT A B FEATURES REPEATS THREADS
// prints one JSON line {"bind_s": [...], "apply_s": [...]} (process CPU seconds).
#include <refit/core/parallel.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/resize.hpp>

#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

namespace {
double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 7) {
    std::fprintf(stderr, "usage: bind_apply_cpu GARMENT A B FEATURES REPEATS THREADS\n");
    return 2;
  }
  using namespace refit;
  const int repeats = std::atoi(argv[5]);
  const ThreadLimit limit(std::strtoul(argv[6], nullptr, 10));
  auto garment = std::make_shared<const Garment>(read_garment_obj(argv[1]));
  const BodyMesh a = read_body(argv[2]), b = read_body(argv[3]);
  const std::vector<FeatureSpec> features = read_feature_file(argv[4], "cm");
  std::string bind = "[", apply = "[";
  for (int k = 0; k < repeats; ++k) {
    double t = cpu_seconds();
    const GarmentBinding binding(garment, a, {}, features, Progress(true));
    if (k) bind += ", ";  // appends: GCC 12's false -Wrestrict on "" + string (bug 105329)
    bind += std::to_string(cpu_seconds() - t);
    t = cpu_seconds();
    const ResizeResult r = binding.resize(b, Progress(true));
    if (k) apply += ", ";
    apply += std::to_string(cpu_seconds() - t);
    if (r.positions.rows() == 0) return 1;
  }
  std::printf("{\"bind_s\": %s], \"apply_s\": %s]}\n", bind.c_str(), apply.c_str());
  return 0;
}
