// The refinement stage of `adamesh extract`: 4-8 refinement of the base mesh (docs/HIERARCHY.md),
// the refined mesh (-o), the hierarchy file (--hierarchy) and per-level figures for the report.
#include "extract_refine.h"

#include <cmath>
#include <sstream>

#include "adamesh/error.h"
#include "adamesh/improve.h"
#include "adamesh/io.h"
#include "adamesh/metrics.h"
#include "adamesh/refine.h"

namespace adamesh::cli {

namespace {

constexpr double kDefaultMaxError = 0.25;  // voxels

nlohmann::json measure(const Mesh& mesh, const Input& in, double iso, int threads) {
  FieldErrorOptions fo;
  fo.inside_sign = in.inside_sign;
  fo.threads = threads;
  const FieldErrorReport e = field_error(mesh, *in.field, iso, fo);
  MetricsOptions mo;
  mo.threads = threads;
  const QualityReport q = quality(mesh, mo);
  return {{"triangles", mesh.num_triangles()},
          {"vertices", mesh.num_vertices()},
          {"eps_e", e.eps_e},
          {"eps_n", e.eps_n},
          {"rms", e.distance.rms},
          {"max", e.distance.max},
          {"p99", e.distance.p99},
          {"unconverged", e.unconverged},
          {"min_angle", {{"min", q.min_angle.min}, {"p5", q.min_angle.p5},
                         {"median", q.min_angle.median}}},
          {"pct_min_angle_below_20", q.pct_min_angle_below[1]},
          {"q_mean", q.q_mean}};
}

/// Triangles of the marching cubes mesh of `sc` (each surfel polygon as a fan).
std::size_t marching_cubes_triangles(const SurfelComplex& sc) {
  std::size_t n = 0;
  for (std::size_t s = 0; s < sc.num_surfels(); ++s)
    n += sc.surfel_offset[s + 1] - sc.surfel_offset[s] - 2;
  return n;
}

}  // namespace

std::vector<OptionSpec> refine_option_specs() {
  return {
      {"-o", true, "write the refined mesh here (.ply .obj .off .stl)"},
      {"--levels", true, "uniform refinement: K levels; the output is M_K"},
      {"--max-error", true,
       "adaptive: every triangle within E of the surface, world units (default: 0.25 voxel, "
       "at most as many triangles as marching cubes)"},
      {"--triangles", true, "adaptive: the N-triangle mesh, worst triangles split first"},
      {"--hierarchy", true, "write the refinement hierarchy (.amh, see docs/HIERARCHY.md)"},
      {"--no-improve", false,
       "write the cut of the hierarchy as it is (no flips, moves or collapses for shape)"},
  };
}

RefineStage run_refine_stage(const Args& args, const Input& in, double iso, const SurfelComplex& sc,
                             const ConnectivityGraph& g, const BaseMesh& base, int threads,
                             Progress& progress, bool measure_levels) {
  const double h = sc.grid.min_spacing();
  RefineOptions ro;
  ro.threads = threads;
  std::ostringstream chosen;
  if (auto k = args.get_int("--levels")) {
    if (*k < 0 || *k > 30) fail(Status::usage, "adamesh extract: --levels must be 0..30");
    ro.mode = RefineMode::uniform;
    ro.levels = static_cast<int>(*k);
    chosen << "--levels " << *k;
  } else if (auto n = args.get_int("--triangles")) {
    if (*n < 1) fail(Status::usage, "adamesh extract: --triangles must be >= 1");
    ro.mode = RefineMode::budget;
    ro.max_triangles = static_cast<std::size_t>(*n);
    chosen << "--triangles " << *n;
  } else {
    ro.mode = RefineMode::max_error;
    if (auto e = args.get_double("--max-error")) {
      if (!(*e > 0) || !std::isfinite(*e))
        fail(Status::usage, "adamesh extract: --max-error must be > 0");
      ro.max_error = *e;
      chosen << "--max-error " << *e << " (" << *e / h << " voxel)";
    } else {
      // The default never gives more triangles than marching cubes would (noisy or label
      // volumes: the frog reached 4.7M triangles at 0.25 voxel, three times marching cubes).
      ro.max_error = kDefaultMaxError * h;
      ro.max_triangles = marching_cubes_triangles(sc);
      chosen << "--max-error " << ro.max_error << " (" << kDefaultMaxError
             << " voxel, the default), at most " << ro.max_triangles
             << " triangles (marching cubes' count)";
    }
  }
  ro.progress = [&](const char*, double f) { progress.fraction(f); };

  RefineStage out;
  Stopwatch clock;
  progress.stage("refine");
  const RefineResult r = refine(sc, base, *in.field, ro, &g);
  CutMesh cut = extract_all(r.hierarchy);
  progress.finish();
  out.refine_s = clock.lap();

  // Uniform levels are written as the hierarchy has them (semi-regular, nested); adaptive meshes
  // get the shape improvement, keeping their triangle count and error bound (docs/QUALITY.md).
  ImproveStats imp;
  if (!args.has("--no-improve") && ro.mode != RefineMode::uniform) {
    progress.stage("improve");
    ImproveOptions io;
    io.voxel = h;
    io.box = in.field->domain();
    io.target_triangles = cut.mesh.num_triangles();
    // An explicit --max-error is a bound the improvement keeps; the default's cap at marching
    // cubes' count already gives up the bound where it binds.
    if (ro.mode == RefineMode::max_error && ro.max_triangles == 0) {
      io.max_deviation = std::min(ro.max_error, 0.25 * h);
      io.max_error = ro.max_error;
    }
    imp = improve_mesh(cut.mesh, cut.vertex_border, in.field.get(), iso, io);
    progress.finish();
    out.improve_s = clock.lap();
  }

  progress.stage("write");
  if (auto path = args.get("-o")) {
    MeshWriteOptions wo;
    wo.ascii = args.has("--ascii");
    write_mesh(cut.mesh, *path, wo);
  }
  if (auto path = args.get("--hierarchy")) write_hierarchy(r.hierarchy, *path);
  progress.finish();
  out.write_s = clock.lap();

  const RefineStats& st = r.stats;
  out.info = {{"chosen", chosen.str()},
              {"base_triangles", st.base_triangles},
              {"blocks", st.blocks},
              {"border_half_blocks", st.border_half_blocks},
              {"matching", {{"greedy_pairs", st.greedy_pairs},
                            {"augmentations", st.augmentations},
                            {"local_augmentations", st.local_augmentations},
                            {"seconds", st.time_blocks_s}}},
              {"quad_fallback", st.quad_fallback},
              {"splits", st.splits},
              {"forced_splits", st.forced_splits},
              {"depth", st.max_level},
              {"at_limit_leaves", st.at_limit_leaves},
              {"placements", {{"normal_line", st.line_placements},
                              {"geodesic", st.geodesic_placements},
                              {"euclidean", st.euclidean_placements},
                              {"border", st.border_placements},
                              {"unconverged", st.unconverged_projections}}},
              {"improve", {{"flips", imp.flips}, {"moves", imp.moves},
                           {"collapses", imp.collapses}, {"splits", imp.splits},
                           {"rounds", imp.rounds},
                           {"min_angle_before", imp.min_angle_before_deg},
                           {"min_angle_after", imp.min_angle_after_deg},
                           {"pct_below_20_before", imp.pct_below_20_before},
                           {"pct_below_20_after", imp.pct_below_20_after}}},
              {"triangles", cut.mesh.num_triangles()},
              {"vertices", cut.mesh.num_vertices()},
              {"warnings", st.warnings}};
  if (measure_levels) {
    progress.stage("measure");
    const int last = ro.mode == RefineMode::uniform ? ro.levels : 0;
    for (int j = 0; j <= last; ++j) {
      nlohmann::json l = measure(extract_level(r.hierarchy, j).mesh, in, iso, threads);
      l["level"] = j;
      out.levels.push_back(l);
      progress.fraction(static_cast<double>(j + 1) / (last + 2));
    }
    if (ro.mode != RefineMode::uniform) {
      nlohmann::json l = measure(cut.mesh, in, iso, threads);
      l["level"] = "final";
      l["depth"] = cut.max_level;
      out.levels.push_back(l);
    }
    progress.finish();
  }
  std::ostringstream s;
  s << "refined (" << chosen.str() << "): " << cut.mesh.num_triangles() << " triangles, "
    << cut.mesh.num_vertices() << " vertices, depth " << cut.max_level << ", " << st.splits
    << " splits (" << st.forced_splits << " forced)";
  if (st.at_limit_leaves)
    s << "; " << st.at_limit_leaves << " triangles above the error bound (stopped at a size limit"
      << (ro.mode == RefineMode::max_error && ro.max_triangles > 0 ? " or the triangle cap)" : ")");
  out.summary = s.str();
  return out;
}

}  // namespace adamesh::cli
