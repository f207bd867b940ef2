// extract(): the pipeline as named steps (ALGORITHM.md 2.2–2.10), with the memory released
// between them (docs/SIMPLIFICATION.md, "Memory"):
//   1. check    the iso-value against the value range (an empty surface is an error)
//   2. surfels  surfel complex of the volume; the worker arenas' freed slabs go back
//   3. graph    connectivity graph; the surfels' voxel indices go (nothing downstream reads them)
//   4. covering disk + Voronoi covering, run without the nodes' keys and positions (20 B/node)
//   5. dual     the graph's adjacency goes, the node geometry comes back; base mesh M0
//   5b. shape   M0's shape improved (and M0 decimated below a small triangle budget), improve.h
//   6. refine   the graph again (deterministic), 4-8 refinement, the budget's cut, its shape
//               improved (adaptive budgets), per-level figures for the report
//   7. report   the complex and the graph go before M0's topology is measured
#include <malloc.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <utility>

#include "adamesh/error.h"
#include "adamesh/extract.h"
#include "adamesh/graph.h"
#include "adamesh/improve.h"
#include "adamesh/stats.h"
#include "adamesh/surfels.h"

namespace adamesh {

namespace {

/// Returns the freed memory of all malloc arenas to the system: the stages free large arrays
/// and the worker threads' arenas keep their freed slab buffers otherwise.
void release_freed_memory() { malloc_trim(0); }

/// Blocks of 1 MiB and more get their own mappings, returned to the system when freed. glibc
/// otherwise raises this threshold as large blocks are freed and serves them from the heap,
/// where the stages' freed arrays fragment and stay resident. Process-wide, set once.
void tune_malloc() {
  static const bool once = [] { return mallopt(M_MMAP_THRESHOLD, 1 << 20) != 0; }();
  (void)once;
}

void check_options(const ExtractOptions& o) {
  if (o.context.threads < 0 || o.context.threads > 1024)
    fail(Status::usage, "extract: threads must be 0..1024");
  if (o.r_max < 0 || o.r_min < 0 || !std::isfinite(o.r_max) || !std::isfinite(o.r_min))
    fail(Status::usage, "extract: radii must be positive");
  switch (o.budget) {
    case Budget::levels:
      if (o.levels < 0 || o.levels > 30) fail(Status::usage, "extract: levels must be 0..30");
      break;
    case Budget::max_error:
      if (!(o.max_error > 0) || !std::isfinite(o.max_error))
        fail(Status::usage, "extract: max_error must be > 0");
      break;
    case Budget::triangles:
      if (o.triangles < 1) fail(Status::usage, "extract: triangles must be >= 1");
      break;
    case Budget::none:
    case Budget::automatic: break;
  }
  if (!(o.max_handle >= 0) || !std::isfinite(o.max_handle))
    fail(Status::usage, "extract: max_handle must be a length >= 0 (voxels)");
}

/// The iso-value to use; fails when it is missing, not finite or gives an empty surface.
double checked_iso(const Input& in, const ExtractOptions& o) {
  double iso = 0;
  if (o.iso) iso = *o.iso;
  else if (in.default_iso) iso = *in.default_iso;
  else fail(Status::usage, in.spec + ": an iso-value is required for volume files");
  if (!std::isfinite(iso)) fail(Status::usage, in.spec + ": the iso-value must be finite");
  const VolumeStats st = compute_stats(*in.volume);
  if (!(iso > st.min && iso <= st.max) && !(iso >= st.min && iso < st.max))
    fail_input(in.spec, "iso-value " + std::to_string(iso) + " is outside the value range [" +
                            std::to_string(st.min) + ", " + std::to_string(st.max) +
                            "]: the surface would be empty");
  return iso;
}

LevelReport measure(const Mesh& mesh, const Input& in, double iso, const ExecutionContext& ctx) {
  LevelReport l;
  FieldErrorOptions fo;
  fo.inside_sign = in.inside_sign;
  l.error = field_error(mesh, *in.field, iso, fo, ctx);
  l.quality = quality(mesh, ctx);
  l.triangles = mesh.num_triangles();
  l.vertices = mesh.num_vertices();
  return l;
}

/// Refine options for the budget; `chosen` describes it in the CLI's words for the report.
RefineOptions refine_options(const ExtractOptions& o, const SurfelComplex& sc, std::string& chosen) {
  const double h = sc.grid.min_spacing();
  RefineOptions ro;
  std::ostringstream s;
  switch (o.budget) {
    case Budget::levels:
      ro.mode = RefineMode::uniform;
      ro.levels = o.levels;
      s << "--levels " << o.levels;
      break;
    case Budget::triangles:
      ro.mode = RefineMode::budget;
      ro.max_triangles = o.triangles;
      s << "--triangles " << o.triangles;
      break;
    case Budget::max_error:
      ro.mode = RefineMode::max_error;
      ro.max_error = o.max_error;
      s << "--max-error " << o.max_error << " (" << o.max_error / h << " voxel)";
      break;
    case Budget::automatic:
    case Budget::none:
      // The default never gives more triangles than marching cubes would (noisy or label
      // volumes: the frog reached 4.7M triangles at 0.25 voxel, three times marching cubes).
      ro.mode = RefineMode::max_error;
      ro.max_error = kDefaultMaxErrorVoxels * h;
      ro.max_triangles = marching_cubes_triangles(sc);
      s << "--max-error " << ro.max_error << " (" << kDefaultMaxErrorVoxels
        << " voxel, the default), at most " << ro.max_triangles
        << " triangles (marching cubes' count)";
      break;
  }
  chosen = s.str();
  return ro;
}

/// Which components keep a triangle budget `n` out of reach, and the smallest --min-component
/// (surfels) that would bring it in: one line for the warnings.
std::string unreachable_budget_note(const BaseMesh& base, const ConnectivityGraph& g, std::size_t n) {
  std::vector<std::size_t> surfels(g.num_components, 0), tris(g.num_components, 0);
  for (std::size_t v = 0; v < g.num_vertices(); ++v) ++surfels[g.component[v]];
  for (std::size_t t = 0; t < base.mesh.num_triangles(); ++t)
    ++tris[base.component[base.mesh.triangles[3 * t]]];
  std::vector<std::uint32_t> comps;
  for (std::uint32_t c = 0; c < g.num_components; ++c)
    if (tris[c] > 0) comps.push_back(c);
  std::stable_sort(comps.begin(), comps.end(),
                   [&](auto a, auto b) { return surfels[a] < surfels[b]; });
  const TopologyReport topo = topology(base.mesh);
  std::ostringstream s;
  s << "--triangles " << n << " is out of reach: the " << comps.size()
    << " surface components (χ " << topo.euler << ", " << topo.boundary_loops
    << " boundary loops) need at least " << base.mesh.num_triangles()
    << " triangles with this topology, and the output has that many";
  // Drop the smallest components (whole size classes) until the rest fits.
  std::size_t total = base.mesh.num_triangles(), dropped = 0, i = 0;
  while (i < comps.size() && total > n) {
    const std::size_t size = surfels[comps[i]];
    for (; i < comps.size() && surfels[comps[i]] == size; ++i, ++dropped) total -= tris[comps[i]];
  }
  if (total <= n && i < comps.size())
    s << "; " << dropped << " of them have fewer than " << surfels[comps[i]]
      << " surfels: --min-component " << surfels[comps[i]] << " reaches it";
  else if (topo.genus > 0 || topo.euler < 0)
    s << "; the largest alone has " << tris[comps.back()] << " and the surfaces have "
      << topo.genus << " handles: --max-handle L cuts handles and tunnels shorter than L "
      << "voxels, --min-component S drops components of fewer than S surfels, --min-cavity V "
         "fills cavities of fewer than V voxels";
  else
    s << "; a larger --rmax gives a coarser base mesh";
  return s.str();
}

/// A triangle budget below M0 decimates M0 to 3/4 of the budget first (the refinement needs room;
/// further costs accuracy and shape the refinement does not win back: skull 1150.5 at 5k, RMS /
/// < 20°: to N/4 3.18 / 4.4 %, N/2 2.65 / 3.8 %, 3N/4 2.10 / 2.1 %, 0.9N 2.06 / 2.1 %).
std::size_t decimation_target(std::size_t budget) { return std::max<std::size_t>(3 * budget / 4, 1); }
/// The smallest budget whose decimation_target is at least `triangles`.
std::size_t budget_decimating_to(std::size_t triangles) { return (4 * triangles + 2) / 3; }

/// A budget met by decimating M0 below the shape floor, with more than 1 % of the output under
/// 20°: says so, and from which budget the decimation keeps its floor (M0 is decimated to 3/4 of
/// the budget; frog label 13: 5,000 → 12.4 % under 20°, 8,222 → 1.8 %, 20,000 → 0.07 %).
std::string shape_budget_note(const ExtractReport& rep, std::size_t n, std::size_t stuck) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << "--triangles " << n
    << " is met by collapsing the base mesh's edges below the " << kDecimateShapeFloorDeg
    << "° shape floor (that floor stopped at " << stuck << " triangles; the collapses went down to "
    << rep.base_improve.decimate_floor_deg << "°): " << rep.improve.pct_below_20_after
    << " % of the output's triangles are under 20°, the smallest " << rep.improve.min_angle_after_deg
    << "°; --triangles " << budget_decimating_to(stuck)
    << " or more keeps the decimation above that floor, and fewer components or handles leave "
       "more triangles to the rest (--min-component, --max-handle, --min-cavity)";
  return s.str();
}

ExtractResult run_pipeline(const Input& input, const ExtractOptions& o, double read_s) {
  const ExecutionContext& ctx = o.context;
  ExtractResult res;
  ExtractReport& rep = res.report;
  auto& timings = rep.timings_s;
  auto& rss = rep.peak_rss_after_mb;
  Stopwatch clock;

  // 1. check; topology control in the volume (handles cut, cavities filled, on a copy)
  const double iso = checked_iso(input, o);
  // A label map meshed at an iso-value: the note says which --label set gives one clean surface.
  const std::string label_note =
      input.volume ? label_map_iso_note(*input.volume, iso, input.inside_sign) : std::string();
  timings["read"] = read_s + clock.lap();
  // Handles first: plugging a tube at both ends makes a cavity.
  Input controlled;
  if (o.max_handle > 0) {
    ctx.report("handles", 0);
    controlled = remove_handles(input, iso, o.max_handle, rep.handles);
    ctx.report("handles", 1);
  }
  if (o.min_cavity > 0) {
    ctx.report("cavities", 0);
    controlled = fill_cavities(o.max_handle > 0 ? controlled : input, iso, o.min_cavity,
                               rep.cavities);
    ctx.report("cavities", 1);
  }
  const Input& in = o.max_handle > 0 || o.min_cavity > 0 ? controlled : input;
  rep.input = in.spec;
  rep.iso = iso;
  if (o.max_handle > 0 || o.min_cavity > 0) timings["topology_control"] = clock.lap();
  rss["read"] = peak_rss_mb();

  // 2. surfels
  ctx.report("surfels", 0);
  SurfelComplex sc = build_surfels(*in.volume, iso, in.inside_sign, ctx);
  ctx.report("surfels", 1);
  timings["surfels"] = clock.lap();
  rss["surfels"] = peak_rss_mb();
  release_freed_memory();
  if (sc.num_surfels() == 0) fail_input(in.spec, "no surface at iso-value " + std::to_string(iso));

  // 3. graph
  ctx.report("graph", 0);
  ConnectivityGraph g = build_graph(sc);
  rep.graph = {g.num_vertices(), g.num_edges(), g.num_components, g.col.empty()};
  std::vector<std::uint64_t>().swap(sc.surfel_voxel);  // nothing downstream reads them
  ctx.report("graph", 1);
  timings["graph"] = clock.lap();
  rss["graph"] = peak_rss_mb();
  release_freed_memory();

  // 4. covering, without the node keys and positions: they are recomputed from the volume after.
  SimplifyOptions opt;
  opt.r_max = o.r_max;
  opt.r_min = o.r_min;
  opt.unit = o.unit;
  opt.min_component_surfels = o.min_component;
  if (opt.r_max <= 0) opt.surface_area = active_surface_area(sc, g, opt);
  release_node_geometry(sc);
  ctx.report("disk cover", 0);
  SimplifyStats stats;
  Covering cov = build_covering(sc, g, opt, stats, ctx);  // reports "disk cover" 1, "voronoi" 0
  ctx.report("voronoi", 1);
  if (o.validate) stats.validation = validate_covering(sc, g, cov);
  clock.lap();
  timings["disk_cover"] = stats.time_disk_cover_s;
  timings["voronoi"] = stats.time_voronoi_s;
  rss["covering"] = peak_rss_mb();

  // 5. dual: it reads the graph's components and border flags, not its adjacency, which goes
  // while the node geometry comes back; the refinement rebuilds it. The dual takes the covering.
  ctx.report("dual", 0);
  g.release_adjacency();
  release_freed_memory();  // the covering's freed small blocks
  restore_node_geometry(*in.volume, sc, ctx);
  res.base = build_base_mesh(sc, g, std::move(cov), in.field.get(), opt, std::move(stats), ctx);
  if (!label_note.empty())
    res.base.stats.warnings.insert(res.base.stats.warnings.begin(), label_note);
  ctx.report("dual", 1);
  timings["dual"] = clock.lap();
  rss["dual"] = peak_rss_mb();

  // 5b. shape of M0: level 0 is free to change until the blocks are built, and its slivers
  // would be bisected into more (docs/QUALITY.md). A triangle budget below M0's size decimates
  // it first so that the refinement has room.
  if (o.improve) {
    ctx.report("improve M0", 0);
    ImproveOptions io;
    io.voxel = sc.grid.min_spacing();
    io.box = in.field->domain();
    io.faces = oblique_faces(sc.grid);
    std::size_t decimate_to = 0;
    if (o.budget == Budget::triangles && res.base.mesh.num_triangles() > decimation_target(o.triangles))
      decimate_to = decimation_target(o.triangles);
    rep.base_improve = improve_base_mesh(res.base, in.field.get(), iso, io, decimate_to, ctx);
    ctx.report("improve M0", 1);
    timings["improve_base"] = clock.lap();
  }
  if (o.budget == Budget::triangles && res.base.mesh.num_triangles() > o.triangles)
    res.base.stats.warnings.push_back(unreachable_budget_note(res.base, g, o.triangles));

  // 6. refine
  if (o.budget != Budget::none) {
    g = build_graph(sc);  // the same graph again (deterministic), adjacency included
    timings["graph"] += clock.lap();
    RefineOptions ro = refine_options(o, sc, rep.chosen);
    if (ro.mode == RefineMode::max_error) rep.triangle_cap = ro.max_triangles;
    if (o.budget == Budget::max_error) rep.max_error = o.max_error;
    ctx.report("refine", 0);
    RefineResult r = refine(sc, res.base, *in.field, ro, &g, ctx);
    CutMesh cut = extract_all(r.hierarchy);
    ctx.report("refine", 1);
    timings["refine"] = clock.lap();
    // Shape of the output: adaptive cuts keep their triangle count and an explicit error bound;
    // uniform levels stay as the hierarchy has them (semi-regular, nested).
    if (o.improve && ro.mode != RefineMode::uniform) {
      ctx.report("improve", 0);
      ImproveOptions io;
      io.voxel = sc.grid.min_spacing();
      io.box = in.field->domain();
      io.faces = oblique_faces(sc.grid);
      io.target_triangles = cut.mesh.num_triangles();
      io.untangle = true;
      io.rescue_below_deg = 20;
      // An explicit --max-error E: flips, collapses and moves keep the surface within min(E,
      // ¼ voxel) of where it was, as for the default. The per-triangle bound at seven points
      // (ImproveOptions::max_error) is not set: its first-order distance estimate on noisy data
      // blocked most untangling and rescue moves (MRI head at E = 1 voxel: 4,374 crossing pairs
      // and 2.2 % of the triangles under 20° against 720 and 0.3 % without it, p99 1.95 and 1.98
      // against E = 4; docs/QUALITY.md "An explicit --max-error"), and the bound a user checks
      // is the measured p99, which the report gives.
      if (ro.mode == RefineMode::max_error && ro.max_triangles == 0)
        io.max_deviation = std::min(ro.max_error, 0.25 * io.voxel);
      std::vector<std::uint32_t> map;
      rep.improve = improve_mesh(cut.mesh, cut.vertex_border, in.field.get(), iso, io, &map, ctx);
      // The fit keeps the border vertices: their flags follow the renumbering.
      cut.vertex_border = remap_vertex_flags(cut.vertex_border, map, cut.mesh.num_vertices());
      ctx.report("improve", 1);
      timings["improve"] = clock.lap();
      if (const std::size_t stuck = rep.base_improve.decimate_stuck_at;
          stuck > 0 && rep.improve.pct_below_20_after > 1)
        res.base.stats.warnings.push_back(shape_budget_note(rep, o.triangles, stuck));
    }
    const bool fit = o.fit == ExtractOptions::Fit::l2 ||
                     (o.fit == ExtractOptions::Fit::automatic && o.improve &&
                      ro.mode != RefineMode::uniform);
    if (fit) {
      ctx.report("fit", 0);
      FitOptions fo;
      fo.max_step = 0.25 * sc.grid.min_spacing();
      fo.box = in.field->domain();
      fo.faces = oblique_faces(sc.grid);
      rep.fit = fit_least_squares(cut.mesh, cut.vertex_border, *in.field, iso, fo, ctx);
      ctx.report("fit", 1);
      timings["fit"] = clock.lap();
    }
    // Last, the crossings the untangling left (shallow ones) are pushed apart: no later step
    // moves a vertex.
    if (o.improve && ro.mode != RefineMode::uniform) {
      ctx.report("separate", 0);
      SeparateOptions so;
      so.voxel = sc.grid.min_spacing();
      so.box = in.field->domain();
      so.faces = oblique_faces(sc.grid);
      // An explicit bound: a push may not take a vertex farther than half of it.
      if (o.budget == Budget::max_error && o.max_error > 0)
        so.max_move = std::min(so.max_move, 0.5 * o.max_error / so.voxel);
      rep.separate = separate_crossings(cut.mesh, cut.vertex_border, so, ctx);
      ctx.report("separate", 1);
      timings["separate"] = clock.lap();
    }
    rep.refined = true;
    rep.refine = std::move(r.stats);
    rep.triangles = cut.mesh.num_triangles();
    rep.vertices = cut.mesh.num_vertices();
    rep.depth = cut.max_level;
    res.mesh = std::move(cut.mesh);
    cut = CutMesh{};
    res.hierarchy = std::move(r.hierarchy);
    if (o.measure_levels) {
      ctx.report("measure", 0);
      const int last = ro.mode == RefineMode::uniform ? ro.levels : 0;
      for (int j = 0; j <= last; ++j) {
        LevelReport l = measure(extract_level(*res.hierarchy, j).mesh, in, iso, ctx);
        l.level = j;
        rep.levels.push_back(std::move(l));
        ctx.report("measure", static_cast<double>(j + 1) / (last + 2));
      }
      if (ro.mode != RefineMode::uniform) {
        LevelReport l = measure(res.mesh, in, iso, ctx);
        l.level = -1;
        l.depth = rep.depth;
        rep.levels.push_back(std::move(l));
      }
      ctx.report("measure", 1);
    } else if (o.budget == Budget::max_error) {
      // An explicit bound is checked, not claimed: the written mesh is measured (the summary
      // gives the measured p99 and maximum).
      ctx.report("measure", 0);
      LevelReport l = measure(res.mesh, in, iso, ctx);
      l.level = -1;
      l.depth = rep.depth;
      rep.levels.push_back(std::move(l));
      ctx.report("measure", 1);
    }
    clock.lap();
    rss["refine"] = peak_rss_mb();
  }

  // 7. report: the complex and the graph are done with; the topology report needs room.
  rep.surfels = sc.num_surfels();
  sc = SurfelComplex{};
  g = ConnectivityGraph{};
  release_freed_memory();
  rep.base_topology = topology(res.base.mesh, ctx);
  rep.base_q_mean = quality(res.base.mesh, ctx).q_mean;
  rep.covering = res.base.stats;
  rep.peak_rss_mb = peak_rss_mb();
  return res;
}

/// Runs `f` with at most `threads` worker threads (0: the caller's arena).
template <class F>
auto with_threads(int threads, F&& f) {
  if (threads <= 0) return f();
  tbb::task_arena arena(threads);
  return arena.execute(std::forward<F>(f));
}

}  // namespace

std::size_t marching_cubes_triangles(const SurfelComplex& sc) {
  std::size_t n = 0;
  for (std::size_t s = 0; s < sc.num_surfels(); ++s)
    n += sc.surfel_offset[s + 1] - sc.surfel_offset[s] - 2;
  return n;
}

ExtractResult extract(const Input& input, const ExtractOptions& options) {
  check_options(options);
  if (!input.volume || !input.field) fail(Status::usage, input.spec + ": input has no volume");
  tune_malloc();
  return with_threads(options.context.threads, [&] { return run_pipeline(input, options, 0.0); });
}

ExtractResult extract(const std::string& spec, const ExtractOptions& options,
                      const InputOptions& input_options) {
  check_options(options);
  tune_malloc();
  return with_threads(options.context.threads, [&] {
    Stopwatch clock;
    options.context.report("read", 0);
    const Input in = load_input(spec, input_options);
    options.context.report("read", 1);
    return run_pipeline(in, options, clock.lap());
  });
}

FitStats fit_cut_to_finest(CutMesh& cut, const Hierarchy& h, const ExecutionContext& context) {
  if (cut.mesh.num_triangles() == 0) return {};
  const std::unique_ptr<ScalarField> surface =
      make_mesh_distance_field(extract_all(h).mesh, h.bounds);
  FitOptions fo;
  fo.max_step = 0.25 * h.voxel;  // as extract's fit
  fo.box = h.bounds;
  return fit_least_squares(cut.mesh, cut.vertex_border, *surface, 0.0, fo, context);
}

}  // namespace adamesh
