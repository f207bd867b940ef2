// `adamesh extract`: volume or implicit input → surfel complex → connectivity graph → disk and
// Voronoi covering → base mesh → 4-8 refinement hierarchy (extract_refine.cpp).
#include <malloc.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "adamesh/atomic_file.h"
#include "adamesh/error.h"
#include "adamesh/graph.h"
#include "adamesh/improve.h"
#include "adamesh/input.h"
#include "adamesh/io.h"
#include "adamesh/metrics.h"
#include "adamesh/simplify.h"
#include "adamesh/stats.h"
#include "adamesh/surfels.h"
#include "args.h"
#include "cli_util.h"
#include "commands.h"
#include "extract_refine.h"

namespace adamesh::cli {

namespace {

std::vector<OptionSpec> extract_specs() {
  std::vector<OptionSpec> s = {
      {"--iso", true, "iso-value (default: the input's default, 0 for shape:/expr:)"},
      {"--base", true, "write the base mesh M0 here (.ply .obj .off .stl)"},
      {"--rmax", true, "largest disk radius, world units (default sqrt(area/1000))"},
      {"--rmin", true, "smallest disk radius, world units (default 2 voxels)"},
      {"--voxels", false, "--rmax/--rmin are in voxel edge lengths instead of world units"},
      {"--min-component", true, "drop components with fewer surfels (default 0: keep all)"},
      {"--threads", true, "worker threads (default: all cores); output does not depend on it"},
      {"--report", true, "write a JSON report (sizes, topology, timings, peak memory)"},
      {"--validate", false, "run the covering validator (slow) and add it to the report"},
      {"--attributes", false, "write per-vertex border/component attributes (PLY)"},
      {"--ascii", false, "ASCII PLY instead of binary"},
      {"--quiet", false, "no progress or summary output"},
  };
  for (auto& o : refine_option_specs()) s.push_back(o);
  for (auto& o : input_option_specs()) s.push_back(o);
  return s;
}

nlohmann::json topology_json(const TopologyReport& t) {
  return {{"vertices", t.vertices},           {"triangles", t.triangles},
          {"euler", t.euler},                 {"components", t.components},
          {"boundary_loops", t.boundary_loops}, {"nonmanifold_edges", t.nonmanifold_edges},
          {"oriented", t.oriented}};
}

/// "the base mesh needs at least M triangles for its K components (...): --min-component S
/// reaches N" — which components keep a budget N out of reach, and the smallest surfel count
/// whose --min-component would bring it in.
std::string unreachable_budget_note(const BaseMesh& base, const ConnectivityGraph& g, std::size_t n) {
  std::vector<std::size_t> surfels(g.num_components, 0), tris(g.num_components, 0);
  for (std::size_t v = 0; v < g.num_vertices(); ++v) ++surfels[g.component[v]];
  for (std::size_t t = 0; t < base.mesh.num_triangles(); ++t)
    ++tris[base.component[base.mesh.triangles[3 * t]]];
  std::vector<std::uint32_t> comps;
  for (std::uint32_t c = 0; c < g.num_components; ++c)
    if (tris[c] > 0) comps.push_back(c);
  std::sort(comps.begin(), comps.end(), [&](auto a, auto b) { return surfels[a] < surfels[b]; });
  std::ostringstream s;
  s << "--triangles " << n << " is out of reach: the " << comps.size()
    << " surface components need at least " << base.mesh.num_triangles()
    << " triangles with this topology (the output has that many and more)";
  // Drop the smallest components until the rest fits.
  std::size_t total = base.mesh.num_triangles(), dropped = 0, i = 0;
  while (i < comps.size() && total > n) {
    const std::size_t size = surfels[comps[i]];
    while (i < comps.size() && surfels[comps[i]] == size) {
      total -= tris[comps[i]];
      ++dropped;
      ++i;
    }
  }
  if (total <= n && i < comps.size())
    s << "; " << dropped << " of them have fewer than " << surfels[comps[i]]
      << " surfels: --min-component " << surfels[comps[i]] << " reaches it";
  else
    s << "; larger --rmax gives a coarser base mesh";
  return s.str();
}

}  // namespace

int cmd_extract(const Argv& argv) {
  const Args args("extract", argv, extract_specs());
  if (args.help_requested()) {
    std::cout << args.usage("INPUT [--iso V] [-o mesh.ply] [--levels K | --max-error E | "
                            "--triangles N] [--hierarchy h.amh] [--base base.ply] [options]");
    return 0;
  }
  args.expect_positionals(1, 1, "INPUT");
  const std::string spec = args.positionals()[0];
  const bool quiet = args.has("--quiet");
  if (!args.has("--base") && !args.has("--report") && !args.has("-o") && !args.has("--hierarchy"))
    fail(Status::usage, "adamesh extract: nothing to write: give -o FILE, --hierarchy FILE, "
                        "--base FILE or --report FILE");
  const int budgets = args.has("--levels") + args.has("--max-error") + args.has("--triangles");
  if (budgets > 1)
    fail(Status::usage, "adamesh extract: give at most one of --levels, --max-error, --triangles");
  const bool refining = args.has("-o") || args.has("--hierarchy") || budgets > 0;

  std::unique_ptr<tbb::global_control> threads;
  int nthreads = 0;
  if (auto t = args.get_int("--threads")) {
    if (*t < 1 || *t > 1024) fail(Status::usage, "adamesh extract: --threads must be 1..1024");
    nthreads = static_cast<int>(*t);
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    static_cast<std::size_t>(*t));
  }

  // Memory (docs/SIMPLIFICATION.md): blocks of 1 MiB and more get their own mappings, returned
  // to the system when freed. glibc otherwise raises this threshold as large blocks are freed
  // and serves them from the heap, where the stages' freed arrays fragment and stay resident.
  mallopt(M_MMAP_THRESHOLD, 1 << 20);

  Progress progress(quiet);
  Stopwatch clock;
  nlohmann::json timings;

  progress.stage("read");
  const Input in = load_input(spec, input_options_from(args));
  double iso = 0;
  if (auto v = args.get_double("--iso")) iso = *v;
  else if (in.default_iso) iso = *in.default_iso;
  else fail(Status::usage, "adamesh extract: " + spec + ": --iso is required for volume files");
  if (!std::isfinite(iso)) fail(Status::usage, "adamesh extract: --iso must be finite");
  {
    const VolumeStats st = compute_stats(*in.volume);
    if (!(iso > st.min && iso <= st.max) && !(iso >= st.min && iso < st.max))
      fail_input(spec, "iso-value " + std::to_string(iso) + " is outside the value range [" +
                           std::to_string(st.min) + ", " + std::to_string(st.max) +
                           "]: the surface would be empty");
  }
  progress.finish();
  timings["read"] = clock.lap();
  nlohmann::json rss;  // peak RSS (MiB) at the end of each stage: where the memory goes
  rss["read"] = peak_rss_mb();

  progress.stage("surfels");
  SurfelOptions so;
  so.threads = nthreads;
  SurfelComplex sc = build_surfels(*in.volume, iso, in.inside_sign, so);
  progress.finish();
  timings["surfels"] = clock.lap();
  rss["surfels"] = peak_rss_mb();
  malloc_trim(0);  // memory: the worker threads' arenas keep their freed slab buffers otherwise
  if (sc.num_surfels() == 0) fail_input(spec, "no surface at iso-value " + std::to_string(iso));

  progress.stage("graph");
  ConnectivityGraph g = build_graph(sc);
  const nlohmann::json graph_info = {{"cvertices", g.num_vertices()},
                                     {"edges", g.num_edges()},
                                     {"components", g.num_components},
                                     {"compact_columns", g.col.empty()}};
  // Memory (docs/SIMPLIFICATION.md): nothing downstream reads the surfels' voxel indices.
  std::vector<std::uint64_t>().swap(sc.surfel_voxel);
  progress.finish();
  timings["graph"] = clock.lap();
  rss["graph"] = peak_rss_mb();
  malloc_trim(0);

  SimplifyOptions opt;
  opt.threads = nthreads;
  if (auto r = args.get_double("--rmax")) opt.r_max = *r;
  if (auto r = args.get_double("--rmin")) opt.r_min = *r;
  if (opt.r_max < 0 || opt.r_min < 0) fail(Status::usage, "adamesh extract: radii must be positive");
  if (args.has("--voxels")) opt.unit = LengthUnit::voxels;
  if (auto m = args.get_int("--min-component")) {
    if (*m < 0) fail(Status::usage, "adamesh extract: --min-component must be >= 0");
    opt.min_component_surfels = static_cast<std::size_t>(*m);
  }
  opt.progress = [&](const char*, double f) { progress.fraction(f); };

  // Memory (docs/SIMPLIFICATION.md): the covering reads no node keys or positions. Release them
  // (20 B per node) while it runs and recompute them from the volume afterwards.
  if (opt.r_max <= 0) opt.surface_area = active_surface_area(sc, g, opt);
  release_node_geometry(sc);

  progress.stage("disk cover");
  SimplifyStats stats;
  Covering cov = build_covering(sc, g, opt, stats);
  progress.finish();
  if (args.has("--validate")) stats.validation = validate_covering(sc, g, cov);
  clock.lap();
  timings["disk_cover"] = stats.time_disk_cover_s;
  timings["voronoi"] = stats.time_voronoi_s;
  rss["covering"] = peak_rss_mb();

  progress.stage("dual");
  // Memory (docs/SIMPLIFICATION.md): the dual reads the graph's components and border flags, not
  // its adjacency, which goes while the node geometry comes back; refinement rebuilds it.
  g.release_adjacency();
  malloc_trim(0);  // the covering's freed small blocks
  restore_node_geometry(*in.volume, sc, so);
  // Refinement needs the complex, the graph and the base mesh only: the dual takes the covering.
  BaseMesh base = build_base_mesh(sc, g, std::move(cov), in.field.get(), opt, std::move(stats));
  progress.finish();
  timings["dual"] = clock.lap();
  rss["dual"] = peak_rss_mb();

  // Level 0 is free to change until the blocks are built (docs/QUALITY.md): its slivers would be
  // bisected into more.
  ImproveStats base_improve;
  if (!args.has("--no-improve")) {
    progress.stage("improve M0");
    ImproveOptions io;
    io.voxel = sc.grid.min_spacing();
    io.box = in.field->domain();
    // A triangle budget below M0's size: decimate M0 first so that the refinement has room.
    std::size_t decimate_to = 0;
    if (auto n = args.get_int("--triangles"); n && *n > 0 &&
        base.mesh.num_triangles() > static_cast<std::size_t>(*n) / 2)
      decimate_to = std::max<std::size_t>(static_cast<std::size_t>(*n) / 4, 1);
    base_improve = improve_base_mesh(base, in.field.get(), iso, io, decimate_to);
    progress.finish();
    timings["improve_base"] = clock.lap();
  }

  // A budget the topology cannot reach: say so, and what would reach it.
  if (auto n = args.get_int("--triangles"); n && *n > 0 &&
      base.mesh.num_triangles() > static_cast<std::size_t>(*n))
    base.stats.warnings.push_back(unreachable_budget_note(base, g, static_cast<std::size_t>(*n)));

  progress.stage("write");
  if (auto path = args.get("--base")) {
    if (args.has("--attributes")) {
      VertexAttribute border{"border", {}, {}}, comp{"component", {}, {}};
      for (auto b : base.border) border.i32.push_back(b);
      for (auto c : base.component) comp.i32.push_back(static_cast<std::int32_t>(c));
      base.mesh.attributes.push_back(std::move(border));
      base.mesh.attributes.push_back(std::move(comp));
    }
    MeshWriteOptions wo;
    wo.ascii = args.has("--ascii");
    write_mesh(base.mesh, *path, wo);
  }
  progress.finish();
  timings["write"] = clock.lap();

  std::optional<RefineStage> refined;
  if (refining) {
    Stopwatch rebuild;
    g = build_graph(sc);  // the same graph again (deterministic), adjacency included
    timings["graph"] = timings["graph"].get<double>() + rebuild.lap();
    refined = run_refine_stage(args, in, iso, sc, g, base, nthreads, progress,
                               args.has("--report"));
    timings["refine"] = refined->refine_s;
    timings["improve"] = refined->improve_s;
    timings["write"] = timings["write"].get<double>() + refined->write_s;
    clock.lap();
    rss["refine"] = peak_rss_mb();
  }

  // Memory: the complex and the graph are done with; the topology report below needs room.
  const std::size_t num_surfels = sc.num_surfels();
  sc = SurfelComplex{};
  g = ConnectivityGraph{};
  malloc_trim(0);
  const TopologyReport topo = topology(base.mesh);
  const auto& st = base.stats;
  if (auto path = args.get("--report")) {
    nlohmann::json r;
    r["input"] = spec;
    r["iso"] = iso;
    r["graph"] = graph_info;
    r["surfels"] = num_surfels;
    r["base"] = topology_json(topo);
    r["base"]["quality"] = {{"q_mean", quality(base.mesh).q_mean}};
    r["base"]["improve"] = {{"flips", base_improve.flips},
                            {"decimation_collapses", base_improve.decimated},
                            {"moves", base_improve.moves},
                            {"collapses", base_improve.collapses},
                            {"pct_below_20_before", base_improve.pct_below_20_before},
                            {"pct_below_20_after", base_improve.pct_below_20_after},
                            {"min_angle_before", base_improve.min_angle_before_deg},
                            {"min_angle_after", base_improve.min_angle_after_deg}};
    r["fallback_components"] = st.fallback_components;
    r["dropped_components"] = st.dropped_components;
    r["covering"] = {{"r_max", st.r_max},
                     {"r_min", st.r_min},
                     {"disks", st.disks},
                     {"disks_grown", st.disks_grown},
                     {"events", st.events},
                     {"halvings", st.halvings},
                     {"floor_conflicts", st.floor_conflicts},
                     {"repair_rounds", st.repair_rounds},
                     {"violated_cells_repaired", st.violated_cells_repaired},
                     {"regularized", st.regularized},
                     {"split_cells", st.split_cells},
                     {"cone_cells", st.cone_cells},
                     {"violations_by_kind", st.violations_by_kind}};
    if (st.validation.ran)
      r["validation"] = {{"ok", st.validation.ok()},
                         {"uncovered", st.validation.uncovered},
                         {"independence", st.validation.independence},
                         {"grading", st.validation.grading},
                         {"non_disks", st.validation.non_disks},
                         {"violated_cells", st.validation.violated_cells}};
    if (refined) {
      r["refine"] = refined->info;
      r["levels"] = refined->levels;
    }
    r["warnings"] = st.warnings;
    r["timings_s"] = timings;
    r["peak_rss_mb"] = peak_rss_mb();
    r["peak_rss_after_mb"] = rss;
    write_file_atomically(
        *path, [&](std::ostream& o) { o << std::setw(2) << r << "\n"; }, false);
  }
  if (!quiet) {
    std::cout << "surfels " << num_surfels << " -> base mesh " << topo.vertices
              << " vertices, " << topo.triangles << " triangles (χ " << topo.euler << ", "
              << topo.components << " components, " << topo.boundary_loops
              << " boundary loops)";
    if (st.fallback_components)
      std::cout << "; " << st.fallback_components << " components meshed from surfels";
    std::cout << "\n";
    if (refined) std::cout << refined->summary << "\n";
    for (const auto& w : st.warnings) std::cerr << "adamesh: warning: " << w << "\n";
  }
  return 0;
}

}  // namespace adamesh::cli
