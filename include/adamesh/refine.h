// Refinement (ALGORITHM.md 2.7–2.10): the base mesh M0 is paired into 4-8 blocks, then refined by
// newest-vertex bisection of block diagonals (forced splits keep every mesh conforming). Each new
// vertex is placed once, at creation: geodesic midpoint on the connectivity graph, tangential
// smoothing, projection onto the iso-surface. The result is a Hierarchy — the base mesh plus the
// list of splits in a progressive order — from which uniform levels and adaptive cuts are
// extracted without the volume, and which is saved as an `.amh` file (docs/HIERARCHY.md).
//
// References: Velho & Zorin, "4-8 subdivision" (CAGD 2001); Velho & Gomes, "Variable resolution
// 4-k meshes" (2000); Bänsch (1991) and Kossaczký (1994) newest-vertex bisection; Duchaineau et
// al., ROAM (1997) split queue; Ohtake, Belyaev & Pasko (2001) for F_T / F_S; Wood et al.,
// "Semi-regular mesh extraction from volumes" (2000) for the variance criterion.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "adamesh/context_fwd.h"
#include "adamesh/field.h"
#include "adamesh/graph.h"
#include "adamesh/mesh.h"
#include "adamesh/simplify.h"
#include "adamesh/surfels.h"
#include "adamesh/vec.h"

namespace adamesh {

/// What drives the refinement.
enum class RefineMode {
  uniform,    ///< split every block `levels` times: M0 … M_levels (triangles double per level)
  threshold,  ///< level-synchronous: split leaves with sqrt(V_T) > delta or max|d| > 4·delta
  max_error,  ///< level-synchronous: split leaves whose sampled max |d| exceeds max_error
  budget,     ///< max-heap of leaves by integrated variance, worst first, until max_triangles
};

struct RefineOptions {
  RefineMode mode = RefineMode::threshold;
  /// uniform: number of levels J (≥ 0). Other modes: deepest triangle level allowed.
  int levels = 20;
  /// threshold: δ_len in world units; 0 = 0.1·h (h = smallest voxel edge).
  double delta = 0;
  /// max_error: E in world units (> 0). Leaves are split until 1.25 × their sampled max |d| ≤ E
  /// (the 15 samples of a triangle can miss its worst point; the metrics sample densely).
  double max_error = 0;
  /// budget: triangle count not to exceed (> 0). Other adaptive modes: optional cap (0 = none);
  /// max_error with a cap splits the worst leaf first, so the cap leaves the smallest errors.
  std::size_t max_triangles = 0;
  /// Adaptive modes never split a triangle whose refinement edge is below this or whose smallest
  /// altitude is below half this (world units), nor deeper than the level at which uniform
  /// bisection brings its base triangle's edges to this. < 0: h/2 for sampled fields
  /// (ALGORITHM.md 2.10 guard), h/4 for analytic ones (creases never converge).
  double min_edge = -1;
  /// Tangential smoothing weight of F_T. ALGORITHM.md suggests 0.3; measured on the built-in
  /// shapes, 0.6 halves the triangles with a minimum angle below 20° and keeps ε_n non-increasing
  /// from level 1 on, at equal distance error (docs/HIERARCHY.md, "Choices").
  double tau = 0.6;
  /// Edges shorter than geodesic_min_edge·h get the Euclidean midpoint instead of the graph
  /// geodesic midpoint (graph paths are quantised at that scale; ALGORITHM.md 5.2).
  double geodesic_min_edge = 4.0;
  /// Testing: build blocks with the fallback (three quads per base triangle) even when a perfect
  /// matching exists.
  bool force_quad_blocks = false;
  /// Every base pairs its blocks by augmenting paths inside small balls around the unmatched
  /// triangles first (the global search costs O(n·m)); bases with at least this many triangles
  /// keep the local (maximal) set of good blocks and search shorter improving chains, smaller
  /// ones complete a maximum good matching globally. Testing sets 0 to force the large-base path.
  std::size_t local_matching_from = 16384;
};

struct RefineStats {
  std::size_t base_triangles = 0;     ///< triangles of the input base mesh
  std::size_t greedy_pairs = 0;       ///< blocks found by the greedy seed (doubled graph pairs)
  std::size_t augmentations = 0;      ///< blossom augmentations after the seed
  std::size_t local_augmentations = 0;  ///< of which found inside local balls
  std::size_t blocks = 0;             ///< blocks of M0 (pairs + border half-blocks)
  std::size_t border_half_blocks = 0;
  bool quad_fallback = false;         ///< blocks built from three quads per base triangle
  std::size_t splits = 0;             ///< block splits in the hierarchy
  std::size_t forced_splits = 0;      ///< of which forced by a finer split
  /// Interior vertices on the line along the block normal (the rule); the others are the
  /// fallback: geodesic or Euclidean midpoint, F_T, projection along ∇f.
  std::size_t line_placements = 0;
  std::size_t geodesic_placements = 0, euclidean_placements = 0, border_placements = 0;
  std::size_t unconverged_projections = 0;  ///< |T_S| ≥ 1e-3 h after F_S
  std::size_t at_limit_leaves = 0;    ///< leaves above the threshold stopped by a limit or cap
  int max_level = 0;                  ///< deepest level reached
  double time_blocks_s = 0, time_refine_s = 0;
  std::vector<std::string> warnings;
};

/// One block split: the block of `triangle` (that triangle and the neighbour across its
/// refinement edge) is bisected, creating one vertex at `position`.
struct HierarchySplit {
  /// Hierarchy triangle id: base triangles are 0..F0−1; split s creates 4·s+F0, 4·s+F0+1
  /// (children of `triangle`) and 4·s+F0+2, 4·s+F0+3 (children of the neighbour).
  std::uint32_t triangle = 0;
  Vec3 position;
  /// Distance bound (world units) of the split block's triangles — 1.25 × their largest sampled
  /// |d| — made monotone: never smaller than the error of any split that depends on this one.
  /// Splits with error > E form a conforming cut whose leaves all have a bound ≤ E.
  float error = 0;
};

/// Base mesh with a compatible labelling plus the splits in progressive order: the splits are
/// sorted by decreasing `error` and every split comes after the splits it depends on, so any
/// prefix is a valid conforming coarser mesh. Vertex ids: base vertices 0..V0−1, then V0+s for
/// split s.
struct Hierarchy {
  double iso = 0;
  Box bounds;        ///< domain of the field (world)
  double voxel = 0;  ///< h, smallest voxel edge (world)
  std::vector<Vec3> base_positions;
  /// (v0, v1, v2), counter-clockwise from outside; (v1, v2) is the refinement edge.
  std::vector<std::array<std::uint32_t, 3>> base_triangles;
  std::vector<std::uint8_t> base_border;   ///< per base vertex: 1 on the volume border
  std::vector<std::uint32_t> base_anchor;  ///< per base vertex: c-vertex (optional, may be empty)
  std::vector<HierarchySplit> splits;

  std::size_t num_vertices() const noexcept { return base_positions.size() + splits.size(); }
  Vec3 vertex(std::size_t id) const noexcept {
    return id < base_positions.size() ? base_positions[id]
                                      : splits[id - base_positions.size()].position;
  }
};

/// A mesh cut from a hierarchy, with the hierarchy ids of its elements. Vertices are listed by
/// increasing hierarchy id, triangles in depth-first order of the forest: the bytes depend only
/// on the set of splits applied.
struct CutMesh {
  Mesh mesh;
  std::vector<std::uint32_t> vertex_id;    ///< per mesh vertex: hierarchy vertex id
  std::vector<std::uint8_t> vertex_border; ///< per mesh vertex: on the volume border
  std::vector<std::uint32_t> triangle_id;  ///< per mesh triangle: hierarchy triangle id
  std::vector<std::uint8_t> triangle_level;
  std::size_t splits_applied = 0;
  int max_level = 0;                       ///< deepest triangle level in the cut
  float max_error = 0;  ///< largest `error` of a split not applied (0 when all were applied)
};

struct RefineResult {
  Hierarchy hierarchy;
  RefineStats stats;
};

/// Pairs M0 into blocks, then refines as `options` says. `graph` is built from `complex` when
/// null. `field` must be the field the complex was built from (same iso-value, `complex.iso`).
/// `context`: worker threads (results are identical for any count), progress ("refine") and
/// cancellation, checked during the refinement loops.
/// Throws Error(invalid_input) for an empty base mesh or invalid options.
RefineResult refine(const SurfelComplex& complex, const BaseMesh& base, const ScalarField& field,
                    const RefineOptions& options = {}, const ConnectivityGraph* graph = nullptr,
                    const ExecutionContext& context = default_context());

/// All splits: the finest mesh of the hierarchy.
CutMesh extract_all(const Hierarchy& h);
/// The splits of triangles of level < K: the uniform level M_K when the hierarchy holds it.
CutMesh extract_level(const Hierarchy& h, int level);
/// The splits with error > E (a prefix): every leaf's sampled max |d| ≤ E when the hierarchy
/// was refined to E or finer.
CutMesh extract_max_error(const Hierarchy& h, double max_error);
/// The longest prefix of splits whose mesh has at most `max_triangles` triangles.
CutMesh extract_triangles(const Hierarchy& h, std::size_t max_triangles);
/// The first `num_splits` splits.
CutMesh extract_prefix(const Hierarchy& h, std::size_t num_splits);

/// Per split s: the refinement edge (a, b) it bisects and its vertex V0+s (full replay).
std::vector<std::array<std::uint32_t, 3>> split_edges(const Hierarchy& h);
/// Number of triangles after each prefix: entry k = triangles of extract_prefix(h, k).
std::vector<std::size_t> prefix_triangle_counts(const Hierarchy& h);
/// Checks that the splits replay (each on an existing leaf with a compatible neighbour) and the
/// base labelling is compatible; throws Error(invalid_input, "<where>: ...") otherwise.
void validate_hierarchy(const Hierarchy& h, const std::string& where = "hierarchy");

// ------------------------------------------------------------------------- .amh files

struct HierarchyReadOptions {
  /// Progressive transmission: accept a file cut short inside the split list and keep the
  /// complete split records (the checksum is then not verified).
  bool allow_partial = false;
};

/// Writes the `.amh` file atomically. Throws Error(output_failed, "<path>: ...").
void write_hierarchy(const Hierarchy& h, const std::string& path);
/// Reads and validates an `.amh` file. Throws Error(invalid_input, "<path>: <problem>").
Hierarchy read_hierarchy(const std::string& path, const HierarchyReadOptions& options = {});

}  // namespace adamesh
