// The report of extract() as JSON (`adamesh extract --report`, the Python module's `report`) and
// the one-line terminal summaries. JSON only in this file.
#include <sys/resource.h>

#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "adamesh/extract.h"

namespace adamesh {

namespace {

nlohmann::json improve_json(const ImproveStats& st) {
  return {{"flips", st.flips},
          {"moves", st.moves},
          {"collapses", st.collapses},
          {"splits", st.splits},
          {"decimation_collapses", st.decimated},
          {"decimation_floor_deg", st.decimate_floor_deg},
          {"decimation_stuck_at", st.decimate_stuck_at},
          {"rounds", st.rounds},
          {"min_angle_before", st.min_angle_before_deg},
          {"min_angle_after", st.min_angle_after_deg},
          {"pct_below_20_before", st.pct_below_20_before},
          {"pct_below_20_after", st.pct_below_20_after},
          {"intersections_before", st.intersections_before},
          {"intersections_after", st.intersections_after},
          {"untangle_moves", st.untangle_moves},
          {"rescued", st.rescued},
          {"rescue_undone", st.rescue_undone},
          {"specks", st.specks},
          {"specks_undone", st.specks_undone},
          {"needle_splits", st.needle_splits}};
}

nlohmann::json topology_json(const TopologyReport& t) {
  return {{"vertices", t.vertices},           {"triangles", t.triangles},
          {"euler", t.euler},                 {"components", t.components},
          {"boundary_loops", t.boundary_loops}, {"nonmanifold_edges", t.nonmanifold_edges},
          {"oriented", t.oriented}};
}

nlohmann::json level_json(const LevelReport& l) {
  const FieldErrorReport& e = l.error;
  const QualityReport& q = l.quality;
  nlohmann::json j = {{"triangles", l.triangles},
                      {"vertices", l.vertices},
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
  if (l.level >= 0) {
    j["level"] = l.level;
  } else {
    j["level"] = "final";
    j["depth"] = l.depth;
  }
  return j;
}

nlohmann::json refine_json(const ExtractReport& r) {
  const RefineStats& st = r.refine;
  return {{"chosen", r.chosen},
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
          {"improve", improve_json(r.improve)},
          {"fit", r.fit ? nlohmann::json{{"method", "l2"},
                                         {"passes", r.fit->passes},
                                         {"moved", r.fit->moved},
                                         {"undone", r.fit->undone},
                                         {"guarded", r.fit->guarded},
                                         {"worse", r.fit->worse},
                                         {"rms_before", r.fit->rms_before},
                                         {"rms_after", r.fit->rms_after},
                                         {"intersections_before", r.fit->intersections_before},
                                         {"intersections_after", r.fit->intersections_after}}
                        : nlohmann::json{{"method", "surface"}}},
          {"separate", r.separate ? nlohmann::json{{"intersections_before", r.separate->intersections_before},
                                                   {"intersections_after", r.separate->intersections_after},
                                                   {"moves", r.separate->moves},
                                                   {"moved", r.separate->moved},
                                                   {"undone", r.separate->undone},
                                                   {"max_move", r.separate->max_move}}
                                  : nlohmann::json(nullptr)},
          {"triangles", r.triangles},
          {"vertices", r.vertices},
          {"warnings", st.warnings}};
}

}  // namespace

std::string report_json(const ExtractReport& rep) {
  const SimplifyStats& st = rep.covering;
  nlohmann::json r;
  r["input"] = rep.input;
  r["iso"] = rep.iso;
  r["graph"] = {{"cvertices", rep.graph.cvertices},
                {"edges", rep.graph.edges},
                {"components", rep.graph.components},
                {"compact_columns", rep.graph.compact_columns}};
  r["surfels"] = rep.surfels;
  r["base"] = topology_json(rep.base_topology);
  r["base"]["quality"] = {{"q_mean", rep.base_q_mean}};
  r["base"]["improve"] = improve_json(rep.base_improve);
  r["topology_control"] = {{"cavities_filled", rep.cavities.filled},
                           {"cavity_voxels_filled", rep.cavities.filled_voxels},
                           {"largest_cavity_filled", rep.cavities.largest_filled},
                           {"components_dropped", st.dropped_components},
                           {"max_handle_radius", rep.handles.radius},
                           {"handles_cut", rep.handles.handles_cut},
                           {"handle_voxels_cut", rep.handles.cut_voxels},
                           {"tunnels_filled", rep.handles.tunnels_filled},
                           {"tunnel_voxels_filled", rep.handles.plug_voxels},
                           {"inside_euler_before", rep.handles.inside_euler_before},
                           {"inside_euler_after", rep.handles.inside_euler_after}};
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
  if (rep.refined) {
    r["refine"] = refine_json(rep);
    r["levels"] = nlohmann::json::array();
    for (const LevelReport& l : rep.levels) r["levels"].push_back(level_json(l));
  }
  r["warnings"] = st.warnings;
  r["timings_s"] = rep.timings_s;
  r["peak_rss_mb"] = rep.peak_rss_mb;
  r["peak_rss_after_mb"] = rep.peak_rss_after_mb;
  std::ostringstream os;
  os << std::setw(2) << r << "\n";
  return os.str();
}

std::string base_summary(const ExtractReport& rep) {
  const TopologyReport& topo = rep.base_topology;
  std::ostringstream s;
  if (rep.handles.radius > 0)
    s << "cut " << rep.handles.handles_cut << " handles (" << rep.handles.cut_voxels
      << " voxels) and plugged " << rep.handles.tunnels_filled << " tunnels ("
      << rep.handles.plug_voxels << " voxels), χ of the inside " << rep.handles.inside_euler_before << " -> "
      << rep.handles.inside_euler_after << "; ";
  if (rep.cavities.filled > 0)
    s << "filled " << rep.cavities.filled << " cavities (" << rep.cavities.filled_voxels
      << " voxels, the largest " << rep.cavities.largest_filled << "); ";
  if (rep.covering.dropped_components > 0)
    s << "dropped " << rep.covering.dropped_components << " components below --min-component; ";
  s << "surfels " << rep.surfels << " -> base mesh " << topo.vertices << " vertices, "
    << topo.triangles << " triangles (χ " << topo.euler << ", " << topo.components
    << " components, " << topo.boundary_loops << " boundary loops)";
  if (rep.covering.fallback_components)
    s << "; " << rep.covering.fallback_components << " components meshed from surfels";
  return s.str();
}

std::string refine_summary(const ExtractReport& rep) {
  if (!rep.refined) return {};
  const RefineStats& st = rep.refine;
  std::ostringstream s;
  s << "refined (" << rep.chosen << "): " << rep.triangles << " triangles, " << rep.vertices
    << " vertices, depth " << rep.depth << ", " << st.splits << " splits (" << st.forced_splits
    << " forced)";
  if (rep.fit)
    s << "; fitted (least squares along the normals): RMS distance " << rep.fit->rms_before << " -> "
      << rep.fit->rms_after;
  if (st.at_limit_leaves) {
    s << "; " << st.at_limit_leaves << " triangles above the error bound (stopped at a size limit"
      << (rep.triangle_cap > 0 ? " or the triangle cap)" : ")");
  }
  if (!rep.levels.empty() && rep.levels.back().level == -1) {
    const DistanceStats& d = rep.levels.back().error.distance;
    s << "; measured distance to the surface: p99 " << d.p99 << ", max " << d.max;
    if (rep.max_error > 0)
      s << (d.p99 <= rep.max_error ? " (p99 within " : " (p99 ABOVE ") << "--max-error "
        << rep.max_error << (d.p99 <= rep.max_error ? ")" : ": noise below the size limit h/2)");
  }
  return s.str();
}

double peak_rss_mb() noexcept {
  rusage ru{};
  if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
  return static_cast<double>(ru.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

}  // namespace adamesh
