// Mesh metrics: topology, triangle quality, area and volume, distance to a field's iso-surface
// with the edge and normal deviations ε_e / ε_n (ALGORITHM.md section 4), and Hausdorff distances
// to a reference mesh. Free functions on plain data; every number is defined in docs/METRICS.md.
//
// All functions run in parallel (oneTBB) with the context's worker threads (context.h; default:
// all hardware threads) and return identical results for any thread count: floating-point sums
// are formed per fixed-size chunk and the chunk sums added in chunk order.
// Lengths are in the mesh's world units, angles in degrees.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "adamesh/context_fwd.h"
#include "adamesh/field.h"
#include "adamesh/mesh.h"
#include "adamesh/vec.h"

namespace adamesh {

// ------------------------------------------------------------------------------ topology

/// One connected component (triangles joined through shared vertices).
struct ComponentTopology {
  std::int64_t vertices = 0, edges = 0, triangles = 0;
  std::int64_t euler = 0;           ///< vertices − edges + triangles of this component
  std::int64_t boundary_loops = 0;  ///< see TopologyReport::boundary_loops
  bool closed = false;      ///< every edge has exactly two triangles
  bool manifold = false;    ///< no non-manifold edge or vertex
  bool orientable = false;  ///< a consistent orientation exists (through manifold edges)
  bool oriented = false;    ///< no inconsistently oriented edge
  /// (2 − euler − boundary_loops)/2 when the component is manifold and orientable (closed or
  /// with boundary); empty otherwise.
  std::optional<std::int64_t> genus;
};

/// Topology is computed on the *proper* triangles (three distinct vertex indices); triangles with
/// a repeated index are counted in `triangles`, `collapsed_triangles` and `degenerate_triangles`
/// only. Vertices are those referenced by proper triangles.
struct TopologyReport {
  std::int64_t vertices = 0;               ///< referenced by at least one proper triangle
  std::int64_t unreferenced_vertices = 0;  ///< mesh vertices no proper triangle uses
  std::int64_t edges = 0;                  ///< distinct undirected vertex pairs of proper triangles
  std::int64_t triangles = 0;              ///< all triangles of the mesh
  std::int64_t collapsed_triangles = 0;    ///< triangles with a repeated vertex index
  std::int64_t euler = 0;                  ///< vertices − edges + proper triangles
  std::int64_t components = 0;
  std::int64_t boundary_edges = 0;         ///< edges with exactly one triangle
  /// Boundary cycles of the surface cut open along its non-manifold edges and split at its
  /// non-manifold vertices, counting the cycles that contain at least one boundary edge.
  std::int64_t boundary_loops = 0;
  std::int64_t genus = 0;                  ///< sum of the components' genus (where defined)
  std::int64_t nonmanifold_edges = 0;      ///< edges with more than two triangles
  std::int64_t nonmanifold_vertices = 0;   ///< vertices whose triangles form more than one fan
  std::int64_t degenerate_triangles = 0;   ///< repeated index or zero area
  std::int64_t duplicate_triangles = 0;    ///< extra copies of an already seen vertex set
  std::int64_t inconsistent_edges = 0;     ///< two-triangle edges traversed the same way by both
  bool oriented = true;                    ///< inconsistent_edges == 0
  bool closed = false;                     ///< ≥ 1 triangle, every edge with exactly two triangles
  /// Components in order of their smallest vertex index.
  std::vector<ComponentTopology> component_list;
};

TopologyReport topology(const Mesh& mesh, const ExecutionContext& context = default_context());

// ------------------------------------------------------------------------ triangle quality

struct AngleStats {
  double min = 0, p1 = 0, p5 = 0, median = 0;  ///< degrees; nearest-rank percentiles
};

struct QualityReport {
  std::int64_t triangles = 0;
  AngleStats min_angle;  ///< of each triangle's smallest angle
  /// Percent of triangles whose smallest angle is below 10°, 20°, 30°.
  std::array<double, 3> pct_min_angle_below{};
  double max_angle = 0;  ///< largest angle of any triangle, degrees
  /// Radius ratio q = 2·r_in/r_circ (1 equilateral, 0 degenerate): triangle counts per bin
  /// [0.05·i, 0.05·(i+1)), the last bin including q = 1.
  std::array<std::int64_t, 20> q_hist{};
  double q_mean = 0;
  double q_min = 0;
};

/// Zero-area triangles count as min angle 0°, max angle 180°, q = 0. Empty mesh: all zero.
QualityReport quality(const Mesh& mesh, const ExecutionContext& context = default_context());

// ---------------------------------------------------------------------- area and volume

double surface_area(const Mesh& mesh, const ExecutionContext& context = default_context());
/// Σ_T (a·(b×c))/6 over all triangles (divergence theorem), relative to the bounding-box
/// centre. The enclosed volume when the mesh is closed and consistently oriented (positive for
/// outward orientation); meaningless otherwise.
double signed_volume(const Mesh& mesh, const ExecutionContext& context = default_context());
/// signed_volume() when `topo` says the mesh is closed and oriented, else empty.
std::optional<double> enclosed_volume(const Mesh& mesh, const TopologyReport& topo,
                                      const ExecutionContext& context = default_context());

// ---------------------------------------------------------------------- distance statistics

struct DistanceStats {
  std::int64_t samples = 0;  ///< area-weighted sample points (mean, rms, p99)
  double mean = 0, rms = 0;
  double max = 0;  ///< over the sample points and the mesh's referenced vertices
  double p99 = 0;  ///< nearest-rank 99th percentile of the sample points
};

/// Sample points: `samples` points spread over the triangles in proportion to their area
/// (docs/METRICS.md: cumulative-area allocation, R2 low-discrepancy points, no randomness).
/// 0 = default: clamp(triangles, 200 000, 2 000 000).
std::int64_t default_sample_count(const Mesh& mesh);

// ---------------------------------------------------------------------- against a field

struct FieldErrorOptions {
  double inside_sign = 1;    ///< inside where inside_sign·(f − iso) ≥ 0 (see input.h)
  std::int64_t samples = 0;  ///< 0 = default_sample_count()
  /// Projection tolerance (world units); 0 = 1e-7 × the mesh's bounding-box diagonal.
  /// `adamesh stats` passes 1e-5 × the voxel size.
  double tolerance = 0;
  /// Cap on each Newton step (world units), which keeps projections on the nearby sheet of the
  /// surface; 0 = the mesh's mean edge length. `adamesh stats` passes the voxel size.
  double max_step = 0;
  int max_steps = 50;  ///< Newton steps per projection
};

struct FieldErrorReport {
  double diagonal = 0;       ///< mesh bounding-box diagonal (the `_rel` divisor)
  DistanceStats distance;    ///< distance of sample points to the iso-surface
  DistanceStats distance_rel;  ///< the same divided by `diagonal`
  double eps_e = 0;           ///< edge deviation (length²)
  double eps_e_sqrt_rel = 0;  ///< sqrt(eps_e) / diagonal
  double eps_n = 0;           ///< normal deviation, in [0, 2]
  /// Points whose projection did not converge or ended more than 4× |signed_distance| away
  /// (distance = |signed_distance| instead), among the sample points, vertices, edge midpoints.
  std::int64_t unconverged = 0;
  std::int64_t flat_gradient_triangles = 0;  ///< centroid with ∇f = 0 (m(T) = 0 in ε_n)
};

/// Distances from the mesh to the iso-surface f = iso: each point's distance is the length of
/// its converged projection (project_to_iso). ε_e and ε_n as in ALGORITHM.md section 4.
FieldErrorReport field_error(const Mesh& mesh, const ScalarField& field, double iso,
                             const FieldErrorOptions& options = {},
                             const ExecutionContext& context = default_context());

// ---------------------------------------------------------------------- against a mesh

struct HausdorffOptions {
  std::int64_t samples = 0;  ///< per side; 0 = default_sample_count() of the sampled mesh
};

struct HausdorffReport {
  DistanceStats a_to_b;   ///< points of a to their closest point on b
  DistanceStats b_to_a;
  double symmetric = 0;   ///< max(a_to_b.max, b_to_a.max)
  double diagonal = 0;    ///< bounding-box diagonal of a (the `_rel` divisor)
  double symmetric_rel = 0;
};

/// One-sided distances both ways (exact point-to-triangle distances through a BVH) and the
/// symmetric Hausdorff distance. A mesh without triangles is at infinite distance.
HausdorffReport hausdorff(const Mesh& a, const Mesh& b, const HausdorffOptions& options = {},
                          const ExecutionContext& context = default_context());

/// `mesh` as a scalar field: the signed distance to its closest triangle (exact, through a BVH),
/// positive on the side its triangles' normals face (the vertices' area-weighted normals
/// interpolated at the closest point give the side there); the gradient is the unit direction
/// away from the closest point, so iso 0 is the mesh itself and a Newton step lands on it.
/// domain() is `domain`. value() and gradient() may be called concurrently. What `adamesh level
/// --fit-finest` fits a cut against: the hierarchy's finest mesh stands for the volume.
std::unique_ptr<ScalarField> make_mesh_distance_field(Mesh mesh, const Box& domain);

// ---------------------------------------------------------------------- self-intersections

struct IntersectionReport {
  /// Triangle pairs that meet other than in what they share; −1 when not measured (more than
  /// 64 pair tests per triangle: piles of triangles over one spot).
  std::int64_t pairs = 0;
  /// The first pairs (lowest triangle indices), at most keep_pairs of them.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> first_pairs;
};

/// Pairs of triangles that intersect: without a common vertex, any contact; with one common
/// vertex, a contact elsewhere; with a common edge, a fold onto each other. Duplicate and
/// collapsed triangles are not counted (they are topology findings). Double-precision orientation
/// tests with a relative tolerance: a contact within it counts (docs/METRICS.md).
IntersectionReport self_intersections(const Mesh& mesh, std::size_t keep_pairs = 0,
                                      const ExecutionContext& context = default_context());

/// The intersecting pairs of self_intersections(mesh) that have at least one triangle t with
/// involved[t] != 0, all of them, sorted; nullopt when not measured (the same test budget). Only
/// the grid cells the involved triangles cover are searched: a recount after local moves costs
/// O(triangles) for the boxes plus the tests near the moved triangles.
std::optional<std::vector<std::pair<std::uint32_t, std::uint32_t>>> intersecting_pairs_involving(
    const Mesh& mesh, const std::vector<std::uint8_t>& involved,
    const ExecutionContext& context = default_context());

/// A pair list (sorted) after the triangles flagged in `changed` moved: the pairs without a
/// changed triangle stay, the others are replaced by `near` = intersecting_pairs_involving(mesh,
/// changed). Sorted, the same list a full recount would give.
std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs_after_change(
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs,
    const std::vector<std::uint8_t>& changed,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& near);

// ---------------------------------------------------------------------- reports

/// Everything `adamesh stats` prints.
struct Grid;

/// Mesh vertices outside a volume's grid (in index space, so oblique grids are exact): beyond a
/// face by more than the rounding of float coordinates.
struct VolumeBoundsReport {
  std::int64_t outside = 0;  ///< vertices outside the grid
  double max_voxels = 0;     ///< the farthest of them beyond a face, in voxels (index units)
};
VolumeBoundsReport vertices_outside_volume(const Mesh& mesh, const Grid& grid);

struct MeshReport {
  TopologyReport topology;
  QualityReport quality;
  double area = 0;
  std::optional<double> volume;  ///< closed and oriented meshes only
  Box bounds;
  std::optional<FieldErrorReport> field;
  std::optional<VolumeBoundsReport> volume_bounds;  ///< with a volume (stats --field)
  std::optional<HausdorffReport> hausdorff;
  std::int64_t self_intersecting_pairs = 0;  ///< self_intersections(mesh).pairs (−1: not measured)
};

/// Topology, quality, area and volume (field and hausdorff are left empty).
MeshReport mesh_report(const Mesh& mesh, const ExecutionContext& context = default_context());

/// JSON object with the keys of docs/METRICS.md (vertices, edges, ..., distance, eps_e, eps_n,
/// hausdorff, area, volume); absent measurements are null.
std::string report_json(const MeshReport& report);
/// Human-readable multi-line summary.
std::string report_text(const MeshReport& report);

}  // namespace adamesh
