// Internal interfaces of the refine module: the surface queries used to place new vertices
// (adapt.cpp), the refinement criterion (criterion.cpp) and the block pairing (blocks.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "adamesh/context.h"
#include "adamesh/field.h"
#include "adamesh/graph.h"
#include "adamesh/refine.h"
#include "adamesh/surfels.h"
#include "graph/shortest_paths.h"

namespace adamesh::detail {

/// Everything vertex placement needs, built once per refinement.
struct Surface {
  const SurfelComplex& sc;
  const ConnectivityGraph& g;
  const ScalarField& field;
  double iso = 0;
  double h = 1;                  ///< smallest voxel edge
  double tau = 0.3;
  double geodesic_min_edge = 0;  ///< world units: shorter edges use the Euclidean midpoint
  /// Noise guard: an unprojected fallback point may stay this far from the surface (world units;
  /// the error bound of an explicit max_error refinement, else unbounded).
  double guard_distance = 0;
  /// Border curve graph: border surfels adjacent when they share a border node (an endpoint of
  /// their border segments). Same vertex numbering as g; other surfels have no edges.
  ConnectivityGraph border_graph;

  Surface(const SurfelComplex& sc, const ConnectivityGraph& g, const ScalarField& field,
          const RefineOptions& options);
};

/// A new vertex on the edge (p1, p2): ring = its neighbours at creation in counter-clockwise
/// order (4, closed) or, on the border, the open fan [p2, v0, p1] (3).
struct EdgeInput {
  Vec3 p1, p2;
  std::uint32_t a1 = 0, a2 = 0;  ///< anchor c-vertices of the endpoints
  bool border = false;           ///< the edge lies on the volume border
  std::array<Vec3, 4> ring{};
  int ring_size = 0;             ///< 0: no smoothing
  double fraction = 0.5;         ///< position along the geodesic (0.5: midpoint)
};

enum class PlacementKind : std::uint8_t { geodesic, euclidean, border, normal_line };

struct Placed {
  Vec3 position;
  std::uint32_t anchor = 0;
  PlacementKind kind = PlacementKind::geodesic;
  bool converged = true;  ///< |T_S| < 1e-3 h after the projection
};

/// Places a new vertex (ALGORITHM.md 2.9). Interior edges: on the line along the block normal
/// through the Euclidean midpoint or an F_T move of it (normal_line); fallback and border edges:
/// geodesic point on G (border: on the border curve), tangential smoothing F_T, projection F_S.
/// New anchor by a greedy walk. Deterministic; safe to
/// call concurrently with distinct workspaces.
Placed place_vertex(const Surface& s, const EdgeInput& in, PathWorkspace& ws);

/// The 15 samples of a triangle miss its worst point by up to ~20 % (measured against the dense
/// sampling of the metrics module on the built-in shapes): the distance bound used by the
/// max-error driver and stored in hierarchies is the sampled max times this.
inline constexpr float kMaxErrorEstimate = 1.25f;

/// Sampled signed distances of a triangle (15 barycentric points, 4 subdivisions).
struct TriError {
  float sqrt_var = 0;  ///< sqrt(V_T), V_T = A(d²) − A(d)²
  float max_abs = 0;   ///< max |d_k|
  float area = 0;      ///< triangle area (world units²)
  float max_estimate() const { return kMaxErrorEstimate * max_abs; }
};
TriError evaluate_triangle(const ScalarField& f, double iso, const Vec3& a, const Vec3& b,
                           const Vec3& c);

/// Block pairing of a base mesh (ALGORITHM.md 2.7).
struct Blocks {
  std::vector<std::array<std::uint32_t, 3>> labelled;  ///< (v0, v1, v2), (v1, v2) the diagonal
  bool perfect = false;
  std::size_t greedy_pairs = 0, augmentations = 0, blocks = 0, border_half_blocks = 0;
  std::size_t local_augmentations = 0;  ///< of the augmentations, found inside local balls
};
/// Every base augments the greedy seed inside small balls first (blocks.cpp); bases under
/// `local_from` triangles then complete a maximum matching of the good blocks by Boost's global
/// search and search 10-exchange chains from sub-20° blocks, larger ones keep the local result
/// and 6-exchange chains. `ticker` (optional) is ticked in the searches for augmenting paths and
/// the improvement passes.
Blocks match_blocks(const std::vector<Vec3>& positions,
                    const std::vector<std::array<std::uint32_t, 3>>& triangles,
                    std::size_t local_from, StageTicker* ticker = nullptr);

/// Fallback blocks: every base triangle becomes three quads (corner, edge midpoints, centroid;
/// new vertices placed on the surface), each quad a block of two triangles. Appends the new
/// vertices to positions / anchors / border and returns the labelled triangles.
std::vector<std::array<std::uint32_t, 3>> quad_blocks(
    const Surface& s, const std::vector<std::array<std::uint32_t, 3>>& triangles,
    std::vector<Vec3>& positions, std::vector<std::uint32_t>& anchors,
    std::vector<std::uint8_t>& border);

}  // namespace adamesh::detail
