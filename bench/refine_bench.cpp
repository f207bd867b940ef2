// Micro-benchmarks of the refinement (include/adamesh/refine.h) on the base mesh of a built-in
// shape (torus, 128³):
//   - Bisection: replaying every split of a uniform hierarchy through the newest-vertex bisection
//     forest and cutting the finest mesh (extract_all) — the conforming 4-8 bisection alone,
//     no vertex placement;
//   - Refine: the whole uniform refinement to K levels (block matching, bisection, geodesic
//     vertex placement with A*, tangential smoothing, projection), at 1 and 2 threads.
//   refine_bench [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "adamesh/context.h"
#include "adamesh/graph.h"
#include "adamesh/input.h"
#include "adamesh/refine.h"
#include "adamesh/simplify.h"
#include "adamesh/surfels.h"

using namespace adamesh;

namespace {

struct Scene {
  Input in;
  SurfelComplex sc;
  ConnectivityGraph g;
  BaseMesh base;
  std::map<int, Hierarchy> uniform;  ///< by levels
};

Scene& scene() {
  static std::unique_ptr<Scene> s;
  if (!s) {
    s = std::make_unique<Scene>();
    InputOptions o;
    o.resolution = 128;
    s->in = load_input("shape:torus", o);
    s->sc = build_surfels(*s->in.volume, 0.0, s->in.inside_sign);
    s->g = build_graph(s->sc);
    s->base = simplify(s->sc, s->in.field.get());
  }
  return *s;
}

const Hierarchy& uniform_hierarchy(int levels) {
  Scene& s = scene();
  auto it = s.uniform.find(levels);
  if (it == s.uniform.end()) {
    RefineOptions opt;
    opt.mode = RefineMode::uniform;
    opt.levels = levels;
    it = s.uniform.emplace(levels, refine(s.sc, s.base, *s.in.field, opt, &s.g).hierarchy).first;
  }
  return it->second;
}

void BM_Bisection(benchmark::State& state) {
  const Hierarchy& h = uniform_hierarchy(static_cast<int>(state.range(0)));
  std::size_t triangles = 0;
  for (auto _ : state) {
    const CutMesh m = extract_all(h);
    triangles = m.mesh.num_triangles();
    benchmark::DoNotOptimize(m.mesh.triangles.data());
  }
  state.counters["splits/s"] = benchmark::Counter(static_cast<double>(h.splits.size()),
                                                  benchmark::Counter::kIsIterationInvariantRate);
  state.counters["triangles"] = static_cast<double>(triangles);
}

void BM_RefineUniform(benchmark::State& state) {
  Scene& s = scene();
  RefineOptions opt;
  opt.mode = RefineMode::uniform;
  opt.levels = static_cast<int>(state.range(0));
  ExecutionContext ctx;
  ctx.threads = static_cast<int>(state.range(1));
  std::size_t splits = 0;
  for (auto _ : state) {
    const RefineResult r = refine(s.sc, s.base, *s.in.field, opt, &s.g, ctx);
    splits = r.hierarchy.splits.size();
    benchmark::DoNotOptimize(r.hierarchy.splits.data());
  }
  state.counters["splits/s"] = benchmark::Counter(static_cast<double>(splits),
                                                  benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace

BENCHMARK(BM_Bisection)->Arg(2)->Arg(4)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RefineUniform)->ArgsProduct({{2}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
