// Penetration test and resolution, and rendering, on a 1M-vertex garment
// (targets: under 0.5 s and under 1 s with 2 threads); a body B's query structures.
#include <refit/collision/collision.hpp>
#include <refit/metrics/metrics.hpp>
#include <refit/metrics/render.hpp>

#include <mannequin/mannequin.hpp>

#include <benchmark/benchmark.h>

#include <cmath>

namespace {

struct Fixture {
  refit::BodyMesh body;
  refit::Garment garment;  // the top, with a patch at the front pushed into the body
  Fixture() {
    refit::mannequin::BodyParams bp;
    body = refit::mannequin::make_body(bp);
    refit::mannequin::GarmentParams gp;
    gp.kind = refit::mannequin::GarmentParams::Kind::Top;
    gp.target_vertices = 1000000;
    garment = refit::mannequin::make_garment(bp, gp);
    const auto lm = refit::mannequin::landmarks(bp);
    for (Eigen::Index i = 0; i < garment.positions.rows(); ++i) {
      const double y = garment.positions(i, 1), z = garment.positions(i, 2);
      if (y > lm.waist && y < lm.waist + 6.0 && z > 0.0) {
        const double w = std::sin(M_PI * (y - lm.waist) / 6.0), f = std::clamp(z / 10.0, 0.0, 1.0);
        garment.positions(i, 2) -= 2.0 * w * f * f * (3.0 - 2.0 * f);
      }
    }
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

void BM_PenetrationTest(benchmark::State& state) {
  const Fixture& f = fixture();
  const refit::BodySurface body(f.body);
  for (auto _ : state) {
    const auto m = refit::measure_penetration(f.garment.positions, body);
    state.counters["inside"] = static_cast<double>(m.inside);
  }
  state.counters["vertices"] = static_cast<double>(f.garment.vertex_count());
}
BENCHMARK(BM_PenetrationTest)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ResolvePenetrations(benchmark::State& state) {
  const Fixture& f = fixture();
  const refit::BodySurface body(f.body);
  for (auto _ : state) {
    state.PauseTiming();
    refit::Points p = f.garment.positions;
    state.ResumeTiming();
    const auto r = refit::resolve_penetrations(f.garment, p, body);
    state.counters["too_close"] = static_cast<double>(r.too_close);
    state.counters["moved"] = static_cast<double>(r.moved);
    state.counters["inside_after"] = static_cast<double>(r.inside_after);
  }
}
BENCHMARK(BM_ResolvePenetrations)->Unit(benchmark::kMillisecond)->UseRealTime();

// What every body B costs before any garment query: the Embree scene, the
// pseudonormals and the inside test's grid (paid once per body, also on small garments).
void BM_BodySurfaceWithInsideGrid(benchmark::State& state) {
  const Fixture& f = fixture();
  for (auto _ : state) {
    const refit::BodySurface body(f.body);
    body.prepare_inside_test();
    benchmark::DoNotOptimize(&body);
  }
  state.counters["triangles"] = static_cast<double>(f.body.triangles.size());
}
BENCHMARK(BM_BodySurfaceWithInsideGrid)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Render800x1000(benchmark::State& state) {
  const Fixture& f = fixture();
  refit::RenderOptions o;
  for (auto _ : state) benchmark::DoNotOptimize(refit::render(f.body, f.garment, nullptr, {}, o).rgb.data());
}
BENCHMARK(BM_Render800x1000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
