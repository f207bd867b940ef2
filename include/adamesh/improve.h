// Shape improvement of a triangle mesh that lies on an iso-surface: edge flips that raise the
// smallest angle, tangential vertex moves toward well-shaped triangles with re-projection onto the
// surface, and collapses of needle edges — none of which changes the mesh's topology (components,
// Euler characteristic, boundary loops) or moves a vertex off the volume's box.
//
// Why (docs/QUALITY.md): on noisy scans the base mesh and the bisection placements follow
// voxel-scale bumps, and a 4-8 hierarchy passes a sliver on to all its descendants; the meshes
// written to files are improved here, after the cut.
//
// References: Botsch & Kobbelt, "A remeshing approach to multiresolution modeling" (SGP 2004:
// flips + tangential relaxation + projection); Dyer, Zhang & Möller, "Delaunay mesh construction"
// (SGP 2007: flips limited by the surface change); Hoppe et al., "Mesh optimization" (1993:
// collapses with the link condition).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "adamesh/context_fwd.h"
#include "adamesh/field.h"
#include "adamesh/mesh.h"
#include "adamesh/simplify.h"
#include "adamesh/vec.h"

namespace adamesh {

struct Grid;

/// The faces of an oblique volume's grid (direction not the identity), which its world bounding
/// box does not describe: index = to_index (p − origin) lies in [0, extent] inside the grid and
/// at 0 or extent[a] on a face. Empty (extent 0) for axis-aligned volumes, whose box is exact.
struct GridFaces {
  Mat3 to_index{};
  Vec3 origin{}, extent{};
  Vec3 rounding{};  ///< Grid::float_rounding_in_index(): how far off its face a vertex may be
  bool empty() const { return !(extent.x > 0); }
};
/// The faces of `grid` when it is oblique, else empty.
GridFaces oblique_faces(const Grid& grid);

struct ImproveOptions {
  /// Outer rounds of flips → moves → collapses (each stops early when nothing changes).
  int rounds = 8;
  /// Vertices whose incident triangles all have a smallest angle at or above this (degrees) are
  /// left where they are: the moves aim at the bad triangles, not at a uniform mesh (adaptive
  /// density is kept).
  double target_angle_deg = 35;
  /// Largest distance (world units) by which a flip or a collapse may move the surface, measured
  /// at the new edge's midpoint against the iso-surface (with a field) or against the old edge
  /// (without): a flip is refused when its new edge lies farther than max(this, the old edge's
  /// distance). 0 = 0.25 × `voxel`.
  double max_deviation = 0;
  /// h, smallest voxel edge (world units): sets the default deviation and the projection steps.
  double voxel = 1;
  /// Collapse an edge of a triangle whose smallest angle is below this (degrees) when it is the
  /// triangle's shortest edge and flips and moves could not fix it. 0 = no collapses (the
  /// triangle count stays the same).
  double collapse_below_deg = 12;
  /// After the rounds, split edges (farthest from the surface first) until the mesh has this many
  /// triangles again, or one less: collapses do not eat a triangle budget. 0 = no splits.
  std::size_t target_triangles = 0;
  /// With a field: an error bound (world units) no changed triangle may exceed — at seven sampled
  /// points, with the refinement's 1.25 margin — unless it was already above. 0 = none.
  double max_error = 0;
  /// The box vertices must stay in (the volume's world box); empty (lo == hi) = no box.
  Box box;
  /// Oblique volumes: the grid's faces, which take the box's place (vertices inside the grid,
  /// border vertices on its faces).
  GridFaces faces;
  /// After the rounds, move the vertices of self-intersecting triangles to the mean of their
  /// neighbours while that lowers the number of intersecting pairs (docs/QUALITY.md).
  bool untangle = false;
  /// Last, the vertices of triangles whose smallest angle is below this (degrees) may leave the
  /// surface (docs/QUALITY.md "Rescue"): each moves — in 3-D; a border vertex within its box
  /// face — to raise the smallest angle around it, while its triangles' sample points (the
  /// vertex, the midpoints of its edges, the centroids) stay within the deviation bound of the
  /// surface (or no farther than they were), inside the box and under an explicit error bound;
  /// moves that make triangles intersect go back; what is still under 10° gets a last stage with
  /// four times the deviation bound. Before that, closed sphere components at most 5 voxels long
  /// with such a triangle become a tetrahedron or an octahedron, and border needles lose their
  /// boundary edge. Thin slivers of the surface (tiny components a few hundredths of a voxel
  /// thick) and crumpled patches have no well-shaped mesh *on* the surface. 0 = off.
  double rescue_below_deg = 0;
};

/// improve_base_mesh's decimation makes no triangle with a smaller angle than this (degrees)
/// unless one was there, until it is stuck (then 10°, 5°, 2°).
inline constexpr double kDecimateShapeFloorDeg = 15;

struct ImproveStats {
  std::size_t flips = 0, moves = 0, collapses = 0, splits = 0;
  std::size_t decimated = 0;  ///< improve_base_mesh: collapses made to reach `decimate_to`
  /// improve_base_mesh with `decimate_to`: the lowest smallest-angle floor the decimation's
  /// collapses needed (15°, then 10°, 5°, 2° when stuck), and the triangle count where the 15°
  /// floor found no collapse (0: it never stuck; below it the shape gives way to the budget).
  double decimate_floor_deg = 0;
  std::size_t decimate_stuck_at = 0;
  int rounds = 0;
  double min_angle_before_deg = 0, min_angle_after_deg = 0;
  double pct_below_20_before = 0, pct_below_20_after = 0;
  /// With `untangle`: intersecting triangle pairs before and after, and the vertex moves made.
  std::size_t intersections_before = 0, intersections_after = 0, untangle_moves = 0;
  /// With `rescue_below_deg`: vertices moved off the surface (after the undoing) and moves undone
  /// because they made triangles intersect.
  std::size_t rescued = 0, rescue_undone = 0;
  /// With `rescue_below_deg`: specks replaced by a tetrahedron or an octahedron, and specks left
  /// as they were because the replacement crossed another triangle.
  std::size_t specks = 0, specks_undone = 0;
  /// With `rescue_below_deg`: graded splits of needles held by the topology (kept ones; also
  /// counted in `splits`).
  std::size_t needle_splits = 0;
};

/// Improves `mesh` in place. `fixed` (empty, or one flag per vertex): vertices that must not move
/// or disappear (volume-border vertices: they lie on the box faces). Edges on the mesh boundary
/// are never flipped or collapsed. With `field`, moved vertices are projected onto its
/// iso-surface `iso` and flips are judged by the field's distance; without, moves stay in the
/// vertex's tangent plane. Deterministic (serial, fixed visiting order). Vertex attributes and
/// normals are dropped when collapses renumber the vertices.
/// `vertex_map` (optional): per input vertex, its index in the output (UINT32_MAX if removed).
/// `context`: cancellation (and progress, stage "improve") checked inside the passes.
ImproveStats improve_mesh(Mesh& mesh, const std::vector<std::uint8_t>& fixed,
                          const ScalarField* field, double iso, const ImproveOptions& options = {},
                          std::vector<std::uint32_t>* vertex_map = nullptr,
                          const ExecutionContext& context = default_context());

/// Per-vertex flags (e.g. a cut's border flags) carried through improve_mesh's `vertex_map`:
/// entry map[v] of the result is flags[v]; vertices the improvement added are 0. Callers that
/// keep flags beside the mesh need it: collapses, specks and splits renumber the vertices.
std::vector<std::uint8_t> remap_vertex_flags(const std::vector<std::uint8_t>& flags,
                                             const std::vector<std::uint32_t>& vertex_map,
                                             std::size_t num_vertices);

/// The same on a base mesh M0 before refinement (ALGORITHM.md leaves level 0 free until the blocks
/// are built): border vertices stay, the per-vertex anchor/border/component arrays follow the
/// renumbering. Moves are small (under ¾ of the shortest incident edge), so anchors stay valid
/// starting points for the refinement's graph searches.
/// `decimate_to` > 0: first collapse the shortest edges (link condition, no new triangle below
/// 15°, flips between passes) until M0 has at most that many triangles or no edge can go — the smallest base a triangle
/// budget below M0's size needs. Progress stage: "improve M0".
ImproveStats improve_base_mesh(BaseMesh& base, const ScalarField* field, double iso,
                               const ImproveOptions& options = {}, std::size_t decimate_to = 0,
                               const ExecutionContext& context = default_context());

/// Least-squares vertex positions (`extract --fit l2`, docs/QUALITY.md): vertices move along
/// their normals to minimise the squared distance of seven points per triangle to the
/// iso-surface (the length of their Newton projections, on the derivative of the trilinear
/// interpolant for sampled fields), which makes the error two-sided instead of one-sided.
struct FitOptions {
  int passes = 4;         ///< Jacobi passes
  double damping = 0.7;   ///< fraction of each vertex's own least-squares step taken per pass
  double max_step = 1;    ///< cap on each step (world units); callers pass a fraction of a voxel
  Box box;                ///< vertices are clamped into it (empty: none)
  GridFaces faces;        ///< oblique volumes: vertices are clamped into the grid instead
  /// Steps in every direction the samples' normals constrain (a crease: two, a corner: three)
  /// instead of along the vertex normal only; the angle, error and intersection guards hold.
  bool free_moves = true;
  /// free_moves: directions whose weight (eigenvalue of Σ w² ĝĝᵀ) is under this × the largest
  /// do not move (they are determined by noise; 1e-6 measured worse than 1e-3 on shapes).
  double rank_ratio = 1e-3;
};

struct FitStats {
  int passes = 0;
  std::size_t moved = 0;   ///< vertices that moved (and were not moved back)
  std::size_t undone = 0;  ///< vertex moves undone because they made triangles intersect
  std::size_t guarded = 0; ///< moves not made: a triangle would drop below min(its angle, 20°)
  std::size_t worse = 0;   ///< moves undone: the vertex's triangles got farther from the surface
  double rms_before = 0, rms_after = 0;  ///< area-weighted RMS distance of the sample points
  /// Intersecting triangle pairs with a triangle the fit moved (the others do not change),
  /// at the starting positions and at the end: no pair is new, so after ≤ before.
  std::size_t intersections_before = 0, intersections_after = 0;
};

/// Fits `mesh` in place. `fixed` (empty or one flag per vertex) and the mesh's boundary vertices
/// stay; no move is kept that leaves more intersecting triangle pairs than before. Identical
/// results for any thread count.
FitStats fit_least_squares(Mesh& mesh, const std::vector<std::uint8_t>& fixed,
                           const ScalarField& field, double iso, const FitOptions& options = {},
                           const ExecutionContext& context = default_context());

struct SeparateOptions {
  double voxel = 1;          ///< world length of a voxel: the margin (0.001) and the reach are in voxels
  double max_move = 0.5;     ///< no vertex ends farther than this (voxels) from where it started
  double min_angle_deg = 20; ///< no triangle around a moved vertex below min(its angle, this)
  int rounds = 16;
  Box box;                   ///< vertices stay in it (empty: none)
  GridFaces faces;           ///< oblique volumes: vertices stay in the grid instead
};

struct SeparateStats {
  std::size_t intersections_before = 0, intersections_after = 0;
  std::size_t moves = 0;   ///< vertex moves kept (a vertex may move in several rounds)
  std::size_t moved = 0;   ///< vertices that ended elsewhere
  std::size_t undone = 0;  ///< moves sent back because they made a new intersecting pair
  double max_move = 0;     ///< largest distance a vertex ended from where it started (world)
};

/// Separates intersecting triangle pairs where a small push does it (docs/QUALITY.md
/// "Separation"): a vertex of one triangle on the wrong side of the other's plane crosses it,
/// along the plane's normal, to 0.001 voxel past it — the cheapest of the four such moves of
/// each pair whose vertices may move (not `fixed`, not on the mesh's boundary), stay in the box
/// and within `max_move`, and keep the angles; moves that make a new pair go back (then the next cheapest). The pairs no
/// such move separates stay (folds where two sheets of the surface are closer than the
/// triangles are wide). Identical results for any thread count.
SeparateStats separate_crossings(Mesh& mesh, const std::vector<std::uint8_t>& fixed,
                                 const SeparateOptions& options = {},
                                 const ExecutionContext& context = default_context());

}  // namespace adamesh
