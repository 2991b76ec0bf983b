// Warp throughput: bind (body A k-d tree queries, eq. 2 sets) and apply (eq. 4
// blend on body B) separately, for 10k to 4M-vertex procedural dresses around
// a ~26k-triangle mannequin, with 1 and 2 threads, at the default cap
// (WarpOptions::max_triangles).
//   build/release/bench/warp_bench --benchmark_counters_tabular=true
// Peak memory of a whole warp run: bench/scalability.py --stage warp.
#include "mannequin/mannequin.hpp"

#include <refit/core/parallel.hpp>
#include <refit/warp/warp.hpp>

#include <benchmark/benchmark.h>

#include <map>

namespace {

using namespace refit;

struct Fixture {
  BodyMesh a, b;
  Garment garment;
};

const Fixture& fixture(std::size_t vertices) {
  static std::map<std::size_t, Fixture> cache;
  auto it = cache.find(vertices);
  if (it != cache.end()) return it->second;
  mannequin::BodyParams pa, pb;
  pb.belly = 6;
  pb.hip = 104;
  pb.waist = 76;
  mannequin::GarmentParams g;
  g.target_vertices = vertices;
  Fixture f{mannequin::make_body(pa), mannequin::make_body(pb), mannequin::make_garment(pa, g)};
  return cache.emplace(vertices, std::move(f)).first->second;
}

void BM_Bind(benchmark::State& state) {
  const Fixture& f = fixture(static_cast<std::size_t>(state.range(0)));
  ThreadLimit limit(static_cast<std::size_t>(state.range(1)));
  const ReferenceBody ref(f.a);
  std::size_t pairs = 0;
  for (auto _ : state) {
    const WarpBinding b = ref.bind(f.garment.positions);
    pairs = b.triangles.indices.size();
    benchmark::DoNotOptimize(b.triangles.indices.data());
  }
  state.counters["vertices"] = static_cast<double>(f.garment.vertex_count());
  state.counters["triangles_per_vertex"] = static_cast<double>(pairs) / static_cast<double>(f.garment.vertex_count());
  state.counters["triangles"] = static_cast<double>(f.a.triangles.size());
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(f.garment.vertex_count()));
}

void BM_Apply(benchmark::State& state) {
  const Fixture& f = fixture(static_cast<std::size_t>(state.range(0)));
  ThreadLimit limit(static_cast<std::size_t>(state.range(1)));
  const ReferenceBody ref(f.a);
  const WarpBinding binding = ref.bind(f.garment.positions);
  for (auto _ : state) {
    const TriangleFrames frames = compute_frames(f.b);
    benchmark::DoNotOptimize(binding.apply(frames));
  }
  state.counters["vertices"] = static_cast<double>(f.garment.vertex_count());
  state.counters["triangles_per_vertex"] =
      static_cast<double>(binding.triangles.indices.size()) / static_cast<double>(binding.size());
  state.counters["binding_bytes_per_vertex"] =
      static_cast<double>(binding.triangles.indices.size() * sizeof(Index) + binding.triangles.offsets.size() * sizeof(Index) +
                          static_cast<std::size_t>(binding.points.size()) * sizeof(double)) /
      static_cast<double>(binding.size());
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(f.garment.vertex_count()));
}

void sizes(benchmark::internal::Benchmark* b) {
  for (int64_t n : {10'000, 100'000, 1'000'000, 4'000'000})
    for (int64_t t : {1, 2}) b->Args({n, t});
  b->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(0.5);
}

BENCHMARK(BM_Bind)->Apply(sizes);
BENCHMARK(BM_Apply)->Apply(sizes);

}  // namespace

BENCHMARK_MAIN();
