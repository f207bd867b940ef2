// The whole pipeline in one call (ALGORITHM.md 2.2–2.10): input → surfel complex → connectivity
// graph → disk and Voronoi covering → base mesh M0 → 4-8 refinement hierarchy → output mesh.
// `adamesh extract` and the Python module are thin layers over extract(): the stage order, the
// memory released between stages (docs/SIMPLIFICATION.md) and the default error bound live here,
// so every caller gets the same meshes and the same peak memory.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "adamesh/context.h"
#include "adamesh/improve.h"
#include "adamesh/input.h"
#include "adamesh/metrics.h"
#include "adamesh/refine.h"
#include "adamesh/simplify.h"

namespace adamesh {

/// What the refinement aims at.
enum class Budget {
  none,       ///< base mesh only: no refinement, no hierarchy
  automatic,  ///< max error kDefaultMaxErrorVoxels voxel, at most marching cubes' triangle count
  levels,     ///< uniform: `levels` levels, the output is M_levels
  max_error,  ///< adaptive: every triangle within `max_error` of the surface (world units)
  triangles,  ///< adaptive: the `triangles`-triangle mesh, worst triangles split first
};

/// Default error bound of Budget::automatic, in voxels (smallest voxel edge).
inline constexpr double kDefaultMaxErrorVoxels = 0.25;

/// Options of extract(). Every field has a usable default; new options get one too.
struct ExtractOptions {
  /// Iso-value; empty = the input's default (0 for shape:/expr: inputs; files have none).
  std::optional<double> iso;

  // ---- Refinement budget (one of them, chosen by `budget`).
  Budget budget = Budget::automatic;
  int levels = 0;               ///< Budget::levels: 0..30
  double max_error = 0;         ///< Budget::max_error: > 0, world units
  std::size_t triangles = 0;    ///< Budget::triangles: ≥ 1

  // ---- Simplification (base mesh).
  double r_max = 0;             ///< largest disk radius; 0 = sqrt(area/1000) (in `unit`)
  double r_min = 0;             ///< smallest disk radius; 0 = 2 voxels (in `unit`)
  LengthUnit unit = LengthUnit::world;  ///< unit of r_max and r_min
  std::size_t min_component = 0;  ///< drop components with fewer surfels (0: keep all)
  bool validate = false;        ///< run the covering validator (slow); fills report.covering

  // ---- Topology control (off by default: the exact topology of the trilinear iso-surface).
  /// Fill cavities (enclosed pockets of outside, 6-connected) with fewer samples than this before
  /// extraction (fill_cavities()); 0 = keep them. Voxels.
  std::int64_t min_cavity = 0;
  /// Cut handles and plug tunnels whose shortest non-separating loop is shorter than about this
  /// many voxels (remove_handles()) before extraction, then fill cavities; 0 = keep them.
  double max_handle = 0;

  // ---- Shape (docs/QUALITY.md).
  /// Improve the shape of M0 before the blocks are built and of the output mesh (adaptive
  /// budgets; uniform levels are written as the hierarchy has them): edge flips, tangential moves
  /// with re-projection, needle collapses, all topology-preserving (improve.h). A triangle budget
  /// above 3/4 of M0's size decimates M0 to 3/4 of the budget first. The hierarchy keeps the improved M0; the output
  /// mesh is improved after the cut (the .amh cut of the same budget is the mesh before).
  bool improve = true;
  /// Vertex positions of the output mesh: least-squares offsets along the normals
  /// (fit_least_squares(), `--fit l2`: lower RMS distance and no worse shape on every shape and
  /// scan measured, docs/QUALITY.md "Fit"), or on the surface (the hierarchy's placements, as
  /// the .amh's cuts have them; `--fit surface`). `automatic` (the default): l2 for the improved
  /// adaptive meshes, surface for uniform levels and with `improve = false` (the hierarchy's cut
  /// as it is).
  enum class Fit { automatic, surface, l2 } fit = Fit::automatic;

  // ---- Report.
  /// Measure every level of the result (distance to the surface, ε_e, ε_n, angles) for
  /// report.levels: one field-error pass per level (slow on large meshes).
  bool measure_levels = false;

  /// Threads, progress and cancellation for the whole call.
  ExecutionContext context;
};

/// Connectivity graph summary for the report.
struct GraphSummary {
  std::size_t cvertices = 0, edges = 0, components = 0;
  bool compact_columns = false;  ///< columns encoded in the CSR offsets (docs/SIMPLIFICATION.md)
};

/// Figures of one level of the result (ExtractOptions::measure_levels).
struct LevelReport {
  int level = 0;       ///< uniform level j of the hierarchy, or -1 for the final adaptive cut
  int depth = 0;       ///< level -1: deepest triangle level of the cut
  std::size_t triangles = 0, vertices = 0;
  FieldErrorReport error;
  QualityReport quality;
};

/// Everything `adamesh extract --report` writes (report_json() gives the JSON).
struct ExtractReport {
  std::string input;                ///< Input::spec
  double iso = 0;
  std::size_t surfels = 0;
  GraphSummary graph;
  TopologyReport base_topology;     ///< of the base mesh M0
  double base_q_mean = 0;           ///< mean radius ratio of M0's triangles
  SimplifyStats covering;           ///< the base mesh's statistics (= base.stats)
  bool refined = false;             ///< the fields below are set
  std::string chosen;               ///< the budget in CLI words ("--triangles 20000", ...)
  std::size_t triangle_cap = 0;     ///< Budget::automatic: marching cubes' triangle count
  double max_error = 0;             ///< Budget::max_error: the bound (the final cut is measured)
  RefineStats refine;
  std::size_t triangles = 0, vertices = 0;  ///< of the output mesh
  int depth = 0;                    ///< deepest triangle level of the output mesh
  std::vector<LevelReport> levels;  ///< when measure_levels
  CavityReport cavities;            ///< ExtractOptions::min_cavity
  HandleReport handles;             ///< ExtractOptions::max_handle
  ImproveStats base_improve;        ///< shape improvement (and decimation) of M0
  ImproveStats improve;             ///< shape improvement of the output mesh
  std::optional<FitStats> fit;      ///< when the output mesh was fitted (ExtractOptions::fit)
  std::optional<SeparateStats> separate;  ///< the last pass on an improved adaptive mesh
  /// Seconds per stage: topology_control (with max_handle or min_cavity), surfels, graph,
  /// disk_cover, voronoi, dual, improve_base, refine, improve, fit, separate (read: load + the
  /// iso-value check; write: filled by callers that write files).
  std::map<std::string, double> timings_s;
  /// Peak resident set size of the process (MiB) at the end of each stage, and at the end.
  std::map<std::string, double> peak_rss_after_mb;
  double peak_rss_mb = 0;
};

struct ExtractResult {
  BaseMesh base;                      ///< M0 with per-vertex anchor, border, component; stats
  std::optional<Hierarchy> hierarchy; ///< unless Budget::none
  /// The refined mesh (the hierarchy's finest cut for the budget); empty for Budget::none.
  Mesh mesh;
  ExtractReport report;
};

/// Runs the pipeline on a loaded input (load_input(), make_input()). The volume is read, not
/// copied; the input must stay valid during the call. Memory: the first call sets glibc's
/// M_MMAP_THRESHOLD to 1 MiB (process-wide), so that the arrays the stages free go back to the
/// system; the freed memory of all malloc arenas is returned between stages (malloc_trim).
/// \throw Error(usage) for invalid options (message names the option); Error(invalid_input) when
///        the iso-value is missing for a volume file, outside the value range, or gives no surface;
///        Error(cancelled) when options.context.cancel is set; other Errors from the stages.
ExtractResult extract(const Input& input, const ExtractOptions& options = {});

/// Loads `spec` (a volume file, shape:NAME or expr:'EXPR') with `input_options`, then extract().
ExtractResult extract(const std::string& spec, const ExtractOptions& options = {},
                      const InputOptions& input_options = {});

/// Least-squares vertex offsets (fit_least_squares) for a cut of `h` without the volume: the
/// hierarchy's finest mesh (extract_all) stands for the iso-surface, as a signed distance field
/// (make_mesh_distance_field); the cut's border vertices stay, moves are clamped into h.bounds.
/// `adamesh level --fit-finest`, Python `Hierarchy.cut(..., fit=True)`; docs/QUALITY.md "Fit".
FitStats fit_cut_to_finest(CutMesh& cut, const Hierarchy& h,
                           const ExecutionContext& context = default_context());

/// The report as the JSON object `adamesh extract --report` writes (2-space indent, newline).
std::string report_json(const ExtractReport& report);

/// One-line summaries for a terminal: the base mesh, the refinement (empty when not refined).
std::string base_summary(const ExtractReport& report);
std::string refine_summary(const ExtractReport& report);

/// Peak resident set size of this process so far, MiB (0 where the system does not say).
double peak_rss_mb() noexcept;

/// Triangles of the marching cubes mesh of `complex` (each surfel polygon as a fan): the cap of
/// Budget::automatic.
std::size_t marching_cubes_triangles(const SurfelComplex& complex);

}  // namespace adamesh
