// Surfel extraction and reference marching cubes throughput (voxels per second) on analytic
// fields sampled into float32 volumes: a smooth gyroid (many surface voxels) and a sphere.
// MarchingCubes = build_surfels + marching_cubes(complex); MarchingCubesDirect =
// marching_cubes(volume), the same mesh without the complex (`adamesh mc`).
//   surfels_bench [--benchmark_filter=...]    arguments: resolution, threads
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>

#include "adamesh/context.h"
#include "adamesh/surfels.h"

using namespace adamesh;

namespace {

const Volume& field(int kind, std::int64_t n) {
  static std::map<std::pair<int, std::int64_t>, std::unique_ptr<Volume>> cache;
  auto& slot = cache[{kind, n}];
  if (!slot) {
    Grid g;
    g.dims = {n, n, n};
    slot = std::make_unique<Volume>(allocate_volume(g, ScalarType::f32, "bench"));
    float* s = slot->samples<float>();
    const double w = 2 * M_PI * 4 / static_cast<double>(n);  // gyroid: 4 periods per side
    for (std::int64_t k = 0; k < n; ++k)
      for (std::int64_t j = 0; j < n; ++j)
        for (std::int64_t i = 0; i < n; ++i) {
          double v;
          if (kind == 0) {
            v = std::sin(i * w) * std::cos(j * w) + std::sin(j * w) * std::cos(k * w) +
                std::sin(k * w) * std::cos(i * w);
          } else {
            const double c = (n - 1) / 2.0;
            v = 0.4 * n - std::sqrt((i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c));
          }
          s[g.linear_index(i, j, k)] = static_cast<float>(v);
        }
  }
  return *slot;
}

void report(benchmark::State& state, const Volume& v, const SurfelComplex& cx) {
  const auto& d = v.grid.dims;
  const double voxels = double(d[0] - 1) * double(d[1] - 1) * double(d[2] - 1);
  state.counters["voxels/s"] =
      benchmark::Counter(voxels, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["surfels"] = static_cast<double>(cx.num_surfels());
  const double bytes = cx.node_key.size() * 8.0 + cx.node_pos.size() * 4.0 +
                       cx.node_fan.size() * 16.0 + cx.surfel_offset.size() * 4.0 +
                       cx.surfel_nodes.size() * 8.0 + cx.surfel_voxel.size() * 8.0 +
                       cx.cvertex.size() * 4.0;
  state.counters["bytes/surfel"] = bytes / static_cast<double>(std::max<std::size_t>(1, cx.num_surfels()));
}

void BM_BuildSurfels(benchmark::State& state, int kind) {
  const Volume& v = field(kind, state.range(0));
  SurfelComplex cx;
  for (auto _ : state) {
    cx = build_surfels(v, 0, 1, {static_cast<int>(state.range(1))});
    benchmark::DoNotOptimize(cx.surfel_nodes.data());
  }
  report(state, v, cx);
}

void BM_MarchingCubes(benchmark::State& state, int kind) {
  const Volume& v = field(kind, state.range(0));
  SurfelComplex cx;
  for (auto _ : state) {
    cx = build_surfels(v, 0, 1, {static_cast<int>(state.range(1))});
    const Mesh m = marching_cubes(cx);
    benchmark::DoNotOptimize(m.triangles.data());
  }
  report(state, v, cx);
}

/// The same mesh straight from the volume (what `adamesh mc` runs): no complex.
void BM_MarchingCubesDirect(benchmark::State& state, int kind) {
  const Volume& v = field(kind, state.range(0));
  for (auto _ : state) {
    const Mesh m = marching_cubes(v, 0, 1, {static_cast<int>(state.range(1))});
    benchmark::DoNotOptimize(m.triangles.data());
  }
  report(state, v, build_surfels(v, 0, 1, {static_cast<int>(state.range(1))}));
}

}  // namespace

BENCHMARK_CAPTURE(BM_BuildSurfels, gyroid, 0)->ArgsProduct({{128, 256}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_BuildSurfels, sphere, 1)->ArgsProduct({{256}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_MarchingCubes, gyroid, 0)->ArgsProduct({{256}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_MarchingCubesDirect, gyroid, 0)->ArgsProduct({{256}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_MarchingCubesDirect, sphere, 1)->ArgsProduct({{256}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
