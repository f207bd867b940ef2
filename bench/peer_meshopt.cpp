// Benchmark peer: reference marching cubes (the mesh of `adamesh mc`, by its direct path)
// followed by meshoptimizer's quadric-error edge collapse (meshopt_simplify, Kapoulkine), the
// fast "marching cubes + decimation" route. One simplification from the full marching cubes
// mesh per budget; each budget's time is MC + simplify, in memory, without file I/O.
//
//   peer_meshopt INPUT [--iso V] [--res N] --out DIR --budgets 5000,20000,100000 [--threads N]
//
// Writes DIR/meshopt_<budget>.ply and prints the JSON line described in peer_common.h.
#include <meshoptimizer.h>
#include <tbb/global_control.h>

#include <cfloat>
#include <memory>

#include "adamesh/context.h"
#include "adamesh/surfels.h"
#include "peer_common.h"

int main(int argc, char** argv) {
  peer::Options opt = peer::parse(argc, argv);
  return peer::run_main(argv[0], [&] {
    std::unique_ptr<tbb::global_control> limit;
    if (opt.threads > 0)
      limit = std::make_unique<tbb::global_control>(
          tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(opt.threads));
    const adamesh::Input in = peer::load(opt);

    const peer::Stopwatch mc_clock;
    // The fastest route to the same mesh (`adamesh mc`'s direct path, no surfel complex).
    adamesh::ExecutionContext ctx;
    ctx.threads = opt.threads;
    const adamesh::Mesh mc = adamesh::marching_cubes(*in.volume, opt.iso, in.inside_sign, ctx);
    const double mc_s = mc_clock.seconds();

    nlohmann::json out;
    out["method"] = "mc+meshopt_simplify";
    out["meshoptimizer_version"] = MESHOPTIMIZER_VERSION;
    out["threads"] = opt.threads;
    out["extract_s"] = mc_s;
    out["extract_triangles"] = mc.num_triangles();
    out["meshes"] = nlohmann::json::array();
    std::vector<std::uint32_t> dest(mc.triangles.size());
    for (std::size_t budget : opt.budgets) {
      if (budget >= mc.num_triangles()) continue;
      const peer::Stopwatch clock;
      // Error bound 1 (= the mesh extent): the triangle budget alone stops the collapses.
      float result_error = 0;
      const std::size_t n = meshopt_simplify(dest.data(), mc.triangles.data(), mc.triangles.size(),
                                             mc.positions.data(), mc.num_vertices(),
                                             3 * sizeof(float), 3 * budget, 1.0f, 0, &result_error);
      const double simplify_s = clock.seconds();
      const adamesh::Mesh m =
          peer::compact(mc.positions, std::vector<std::uint32_t>(dest.begin(), dest.begin() + n));
      const std::string path = opt.out_dir + "/meshopt_" + std::to_string(budget) + ".ply";
      adamesh::write_mesh(m, path);
      out["meshes"].push_back({{"budget", budget},
                               {"triangles", m.num_triangles()},
                               {"time_s", mc_s + simplify_s},
                               {"simplify_s", simplify_s},
                               {"result_error_rel", result_error},
                               {"path", path}});
    }
    out["peak_rss_mb"] = peer::peak_rss_mb();
    std::cout << out.dump() << "\n";
  });
}
