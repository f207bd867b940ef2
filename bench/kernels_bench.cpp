// Micro-benchmarks of the hot kernels behind the covering and the refinement, on the surfel
// complex of a built-in shape (torus, 128³ unless stated):
//   - Dijkstra on the connectivity graph: a geodesic disk of radius r (voxel units) around a
//     fixed sequence of sources, as the disk cover grows them (src/graph/shortest_paths.h);
//   - A* on the graph between c-vertices a fixed geodesic distance apart, as the refinement
//     finds the geodesic midpoint of an edge;
//   - project_to_iso (field.h): safeguarded Newton projection of points displaced off the
//     surface, on the trilinear volume field and on the analytic field.
//   kernels_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <cstdint>
#include <map>
#include <memory>

#include "adamesh/field.h"
#include "adamesh/graph.h"
#include "adamesh/input.h"
#include "adamesh/surfels.h"
#include "graph/shortest_paths.h"

using namespace adamesh;

namespace {

struct Scene {
  Input in;
  SurfelComplex sc;
  ConnectivityGraph g;
  std::shared_ptr<const ScalarField> volume_field;
  double h = 1;
};

const Scene& scene(int res) {
  static std::map<int, std::unique_ptr<Scene>> cache;
  auto& s = cache[res];
  if (!s) {
    s = std::make_unique<Scene>();
    InputOptions o;
    o.resolution = res;
    s->in = load_input("shape:torus", o);
    s->sc = build_surfels(*s->in.volume, 0.0, s->in.inside_sign);
    s->g = build_graph(s->sc);
    s->volume_field = make_volume_field(s->in.volume);
    s->h = s->in.volume->grid.min_spacing();
  }
  return *s;
}

/// Deterministic spread of vertex ids (golden-ratio stride).
std::uint32_t pick(std::size_t k, std::size_t n) {
  return static_cast<std::uint32_t>((k * 2654435761ull) % n);
}

void BM_DijkstraDisk(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  const double radius = static_cast<double>(state.range(1)) * s.h;
  detail::PathWorkspace ws(s.g.num_vertices());
  std::size_t k = 0, settled = 0;
  for (auto _ : state) {
    const std::uint32_t src = pick(k++, s.g.num_vertices());
    std::size_t n = 0;
    detail::dijkstra(s.g, ws, src, radius, [&](std::uint32_t, double) {
      ++n;
      return detail::Visit::expand;
    });
    settled += n;
    benchmark::DoNotOptimize(n);
  }
  state.counters["vertices/search"] =
      static_cast<double>(settled) / static_cast<double>(std::max<std::size_t>(1, k));
  state.counters["settled/s"] =
      benchmark::Counter(static_cast<double>(settled), benchmark::Counter::kIsRate);
}

void BM_AStarPath(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  const double span = static_cast<double>(state.range(1)) * s.h;
  // Pairs (source, target) at geodesic distance ≈ span: the vertex settled last by a Dijkstra of
  // radius span. Built once, outside the timed loop.
  detail::PathWorkspace ws(s.g.num_vertices());
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (std::size_t k = 0; k < 256; ++k) {
    const std::uint32_t src = pick(k, s.g.num_vertices());
    std::uint32_t last = src;
    detail::dijkstra(s.g, ws, src, span, [&](std::uint32_t v, double) {
      last = v;
      return detail::Visit::expand;
    });
    if (last != src) pairs.emplace_back(src, last);
  }
  std::size_t k = 0, path_vertices = 0;
  for (auto _ : state) {
    const auto& [a, b] = pairs[k++ % pairs.size()];
    double length = 0;
    const auto path = detail::astar(s.g, s.sc, ws, a, b, length, [](std::uint32_t) { return true; });
    path_vertices += path.size();
    benchmark::DoNotOptimize(length);
  }
  state.counters["path vertices"] =
      static_cast<double>(path_vertices) / static_cast<double>(std::max<std::size_t>(1, k));
}

void BM_ProjectToIso(benchmark::State& state, bool analytic) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  const ScalarField& f = analytic ? *s.in.field : *s.volume_field;
  // Start points: c-vertices pushed off the surface by up to one voxel along a fixed direction.
  std::vector<Vec3> starts;
  for (std::size_t k = 0; k < 4096; ++k) {
    const Vec3 c = s.sc.cvertex_position(pick(k, s.sc.num_surfels()));
    const double t = (static_cast<double>(k % 17) / 8.0 - 1.0) * s.h;
    starts.push_back(c + Vec3{t, 0.5 * t, -0.25 * t});
  }
  ProjectOptions opt;
  opt.tolerance = 1e-3 * s.h;
  std::size_t k = 0, steps = 0;
  for (auto _ : state) {
    const ProjectResult r = project_to_iso(f, 0.0, starts[k++ % starts.size()], opt);
    steps += static_cast<std::size_t>(r.steps);
    benchmark::DoNotOptimize(r.point);
  }
  state.counters["steps"] = static_cast<double>(steps) / static_cast<double>(std::max<std::size_t>(1, k));
}

}  // namespace

BENCHMARK(BM_DijkstraDisk)->ArgsProduct({{128}, {4, 16}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_AStarPath)->ArgsProduct({{128}, {8, 32}})->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_ProjectToIso, volume, false)->Arg(128)->Unit(benchmark::kNanosecond);
BENCHMARK_CAPTURE(BM_ProjectToIso, analytic, true)->Arg(128)->Unit(benchmark::kNanosecond);

BENCHMARK_MAIN();
