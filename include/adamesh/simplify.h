// Simplification (ALGORITHM.md 2.4–2.6): geodesic disk covering of the connectivity graph →
// geodesic Voronoi covering (violated cells re-subdivided locally) → dual triangulation = the
// base mesh M0, which has the iso-surface's topology, boundaries and components.
//
// Peixoto & Velho, "Adaptive Mesh Extraction using Simplification and Refinement" (2002);
// closed-ball conditions after Edelsbrunner & Shah, "Triangulating topological spaces" (1997).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "adamesh/context_fwd.h"
#include "adamesh/field.h"
#include "adamesh/graph.h"
#include "adamesh/mesh.h"
#include "adamesh/surfels.h"

namespace adamesh {

enum class LengthUnit { world, voxels };

struct SimplifyOptions {
  /// Largest disk radius. 0 = default sqrt(surface area / target_cells), in `unit`.
  double r_max = 0;
  /// Smallest disk radius. 0 = default 2 voxels (2h, h = smallest voxel edge), in `unit`.
  double r_min = 0;
  LengthUnit unit = LengthUnit::world;  ///< unit of r_max and r_min
  double target_cells = 1000;           ///< sets the default r_max: area / r_max² ≈ target_cells
  /// Components of G with fewer surfels are dropped (noise). 0 = keep all (default).
  std::size_t min_component_surfels = 0;
  bool validate = false;                ///< run the debug validator (slow) and fill the report
  /// Move base vertices onto the iso-surface with safeguarded Newton steps (needs a field).
  bool project_vertices = true;
  int max_rounds = 64;                  ///< violated-cell repair rounds before falling back
  /// Surface area of the kept components (sets the default r_max), when the caller computed it
  /// with active_surface_area(); < 0: build_covering computes it from the node positions.
  double surface_area = -1;
};

/// What the debug validator found (ALGORITHM.md section 4, "Covering").
struct CoveringValidation {
  bool ran = false;
  std::size_t uncovered = 0;            ///< c-vertices in no disk (active components)
  std::size_t independence = 0;         ///< disks containing another centre
  std::size_t grading = 0;              ///< vertex pairs of disks whose radii differ by > 2
  std::size_t non_disks = 0;            ///< disks that are not topological disks
  std::size_t violated_cells = 0;       ///< violated Voronoi cells left (non-fallback components)
  bool ok() const {
    return uncovered == 0 && independence == 0 && grading == 0 && non_disks == 0 &&
           violated_cells == 0;
  }
};

struct SimplifyStats {
  double r_max = 0, r_min = 0;          ///< world units actually used
  std::size_t disks = 0;                ///< centres at the end
  std::size_t disks_grown = 0;          ///< growth attempts
  std::size_t events = 0;               ///< topological events met while growing
  std::size_t halvings = 0;             ///< disks halved (grading cascade + repairs)
  std::size_t floor_conflicts = 0;      ///< conflicts left at r_min
  std::size_t repair_rounds = 0;        ///< Voronoi repair rounds
  std::size_t violated_cells_repaired = 0;
  std::size_t regularized = 0;          ///< surfels moved between cells to remove corner pinches
  std::size_t components = 0;           ///< components of G (kept)
  std::size_t dropped_components = 0;   ///< below min_component_surfels
  std::size_t fallback_components = 0;  ///< meshed from their surfels
  std::size_t cone_cells = 0;           ///< cells triangulated as cones (local fallback)
  std::size_t split_cells = 0;          ///< non-disk cells split into one cell per surfel
  std::vector<std::size_t> violations_by_kind = std::vector<std::size_t>(7, 0);
  double time_disk_cover_s = 0, time_voronoi_s = 0, time_dual_s = 0;
  CoveringValidation validation;
  std::vector<std::string> warnings;
};

/// The Voronoi covering of G: centres, radii and the cell of every c-vertex.
struct Covering {
  static constexpr std::uint32_t kNoCell = 0xffffffffu;
  std::vector<std::uint32_t> centre;      ///< per cell: its centre c-vertex
  std::vector<double> radius;             ///< per cell: its disk radius (world)
  std::vector<std::uint32_t> cell;        ///< per c-vertex: its cell, or kNoCell (dropped/fallback)
  /// Per cell: 1 = triangulate as a cone over its boundary nodes (a cell whose Voronoi
  /// violations survived at r_min; cells that were not even disks are split into one cell per
  /// surfel first).
  std::vector<std::uint8_t> cone;
  std::vector<std::uint8_t> fallback;     ///< per component of G: 1 = mesh it from its surfels
  std::vector<std::uint8_t> dropped;      ///< per component of G: 1 = dropped as noise
};

struct BaseMesh {
  Mesh mesh;                              ///< M0 (CCW seen from outside)
  std::vector<std::uint32_t> anchor;      ///< per vertex: c-vertex (surfel) it stands for
  std::vector<std::uint8_t> border;       ///< per vertex: 1 on the volume border
  std::vector<std::uint32_t> component;   ///< per vertex: component of G
  SimplifyStats stats;
};

/// Area of the surfels of the components the covering keeps (options.min_component_surfels),
/// summed in surfel order: what build_covering uses for the default r_max. Reads node positions.
double active_surface_area(const SurfelComplex& complex, const ConnectivityGraph& graph,
                           const SimplifyOptions& options);

/// Disk covering + Voronoi covering with local repair of violated cells. Reads no node keys or
/// positions when options.surface_area is given (the complex's node geometry may be released).
/// Sequential. Reports progress ("disk cover" then "voronoi") and checks cancellation through
/// `context` during both.
Covering build_covering(const SurfelComplex& complex, const ConnectivityGraph& graph,
                        const SimplifyOptions& options, SimplifyStats& stats,
                        const ExecutionContext& context = default_context());

/// Dual triangulation of the covering (fallback components meshed from their surfels).
/// `field` (optional) is used to project vertices onto the iso-surface.
BaseMesh build_base_mesh(const SurfelComplex& complex, const ConnectivityGraph& graph,
                         Covering covering, const ScalarField* field,
                         const SimplifyOptions& options, SimplifyStats stats,
                         const ExecutionContext& context = default_context());

/// Debug validator: coverage, independence, grading ≤ 2, disks are topological disks, no violated
/// Voronoi cell (components meshed by the fallback are skipped). One Dijkstra per disk: slow.
CoveringValidation validate_covering(const SurfelComplex& complex, const ConnectivityGraph& graph,
                                     const Covering& covering);

/// Convenience: graph → covering → base mesh.
BaseMesh simplify(const SurfelComplex& complex, const ScalarField* field,
                  const SimplifyOptions& options = {},
                  const ExecutionContext& context = default_context());

}  // namespace adamesh
