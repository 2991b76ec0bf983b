// libFuzzer target: a whole resize (warp, surface, collision) of a tiny garment
// read from arbitrary bytes, around a small closed sphere body (A) to the same
// sphere widened (B). The body is small so that a run takes milliseconds even
// with the fuzzer's instrumentation (the mannequin's 26k-triangle inside-test
// grid alone took 30 s there); the seeds are garments around it.
#include <refit/core/error.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/resize.hpp>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <string_view>

namespace {

// Latitude-longitude sphere of radius 30 around (0, 100, 0), x scaled by `widen`.
refit::BodyMesh sphere(double widen) {
  constexpr int rings = 12, segments = 24;
  refit::BodyMesh b;
  b.vertices.resize(2 + (rings - 1) * segments, 3);
  b.vertices.row(0) << 0, 130, 0;
  b.vertices.row(1) << 0, 70, 0;
  for (int r = 1; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double t = std::numbers::pi * r / rings, p = 2 * std::numbers::pi * s / segments;
      b.vertices.row(2 + (r - 1) * segments + s) << widen * 30 * std::sin(t) * std::cos(p), 100 + 30 * std::cos(t),
          30 * std::sin(t) * std::sin(p);
    }
  auto at = [](int r, int s) { return refit::Index(2 + (r - 1) * segments + (s % segments)); };
  for (int s = 0; s < segments; ++s) {
    b.triangles.push_back({0, at(1, s + 1), at(1, s)});
    b.triangles.push_back({1, at(rings - 1, s), at(rings - 1, s + 1)});
    for (int r = 1; r + 1 < rings; ++r) {
      b.triangles.push_back({at(r, s), at(r, s + 1), at(r + 1, s + 1)});
      b.triangles.push_back({at(r, s), at(r + 1, s + 1), at(r + 1, s)});
    }
  }
  b.name = widen == 1.0 ? "sphere" : "wide_sphere";
  return b;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const refit::BodyMesh body_a = sphere(1.0), body_b = sphere(1.15);
  try {
    auto garment = std::make_shared<const refit::Garment>(
        refit::parse_garment_obj(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.obj"));
    if (garment->positions.rows() > 2000) return 0;  // tiny garments: many runs per second
    const refit::GarmentBinding binding(garment, body_a, {}, {}, refit::Progress(false));
    const refit::ResizeResult r = binding.resize(body_b, refit::Progress(false));
    if (r.positions.rows() != garment->positions.rows() || !r.positions.allFinite()) std::abort();
  } catch (const refit::Error&) {
  }
  return 0;
}
