// Feature curves: shape matching time per curve size, and slicing a 1M-vertex dress.
#include <refit/core/parallel.hpp>
#include <refit/features/bspline.hpp>
#include <refit/features/shape_matching.hpp>
#include <refit/features/slice.hpp>

#include <benchmark/benchmark.h>

#include <cmath>

#include "mannequin/mannequin.hpp"

using namespace refit;

namespace {

Vec3 bend(const Vec3& p) {
  return Vec3(p.x() + 0.002 * p.y() * p.y(), p.y() + 0.8 * std::sin(0.05 * p.x()), p.z() + 0.001 * p.x() * p.x());
}

void BM_OptimiseCurve(benchmark::State& state) {
  const std::size_t m = static_cast<std::size_t>(state.range(0));
  Points s(static_cast<Eigen::Index>(m), 3);
  for (std::size_t i = 0; i < m; ++i) {
    const double t = 100.0 * static_cast<double>(i) / static_cast<double>(m - 1);
    s.row(static_cast<Eigen::Index>(i)) << t, 3.0 * std::sin(0.3 * t), 0.0;
  }
  const FeatureCurve c = make_feature_curve("c", s, false, FeaturePlane::from_point_normal(Vec3::Zero(), Vec3::UnitZ()));
  const ShapeModel model = prepare_shape_model({c});
  auto map = [](const Points& p) {
    Points o(p.rows(), 3);
    for (Eigen::Index i = 0; i < p.rows(); ++i) o.row(i) = bend(row3(p, static_cast<Index>(i))).transpose();
    return o;
  };
  const std::vector<Points> ws{map(c.samples)}, wa{map(c.aux)};
  double err = 0;
  for (auto _ : state) {
    const FeatureResult r = match_shapes(model, ws, wa, [](const Vec3& p) { return std::abs(p.y() + 5.0); });
    err = r.curves[0].shape_error_result;
    benchmark::DoNotOptimize(r);
  }
  state.counters["shape_error"] = err;
}
BENCHMARK(BM_OptimiseCurve)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond);

void BM_SliceDress1M(benchmark::State& state) {
  static const Garment dress = [] {
    mannequin::GarmentParams gp;
    gp.target_vertices = 1000000;
    return mannequin::make_garment(mannequin::BodyParams{}, gp);
  }();
  const ThreadLimit limit(static_cast<std::size_t>(state.range(0)));
  const FeaturePlane plane = FeaturePlane::from_point_normal(Vec3(0, 80, 0.3), Vec3::UnitZ());
  std::size_t pieces = 0;
  for (auto _ : state) {
    const SliceResult r = slice_garment(dress, plane);
    pieces = r.pieces.size();
    benchmark::DoNotOptimize(r);
  }
  state.counters["vertices"] = static_cast<double>(dress.vertex_count());
  state.counters["pieces"] = static_cast<double>(pieces);
}
BENCHMARK(BM_SliceDress1M)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
