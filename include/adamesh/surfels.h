// The surfel complex (ALGORITHM.md 2.2): nodes on sign-changing voxel edges, face segments joined
// by the asymptotic decider, segment cycles = surfels (several per voxel where the data says so),
// one c-vertex per surfel. It is the ground floor of the method: the connectivity graph, the base
// mesh's topology and every topology test rest on it; triangulated it is the reference marching
// cubes mesh.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "adamesh/context_fwd.h"
#include "adamesh/mesh.h"
#include "adamesh/vec.h"
#include "adamesh/volume.h"

namespace adamesh {

/// The opposite surfels of one polygon's edges (SurfelComplex::opposites_of), by value: they are
/// computed from the node fans, not stored. A voxel has 12 edges, so a polygon at most 12 nodes.
struct PolygonOpposites {
  static constexpr std::size_t kMax = 12;
  std::array<std::int32_t, kMax> v{};
  std::size_t n = 0;
  std::size_t size() const noexcept { return n; }
  std::int32_t operator[](std::size_t i) const noexcept { return v[i]; }
  const std::int32_t* begin() const noexcept { return v.data(); }
  const std::int32_t* end() const noexcept { return v.data() + n; }
};

/// Sign rule: a sample is *positive* (inside) when inside_sign·(f − iso) ≥ 0, so samples equal to
/// the iso-value are positive. Node parameters along an edge are clamped to [kNodeEps, 1 − kNodeEps].
struct SurfelComplex {
  static constexpr double kNodeEps = 1.0 / 1024.0;

  Grid grid;               ///< copy of the input grid (index ↔ world)
  double iso = 0;
  double inside_sign = 1;

  // ---- Nodes: one per sign-changing voxel edge, ids in increasing key order. ----
  std::vector<std::uint64_t> node_key;  ///< 3·linear_index(lower endpoint) + axis (0=x,1=y,2=z)
  std::vector<float> node_pos;          ///< 3 per node, world coordinates
  /// The up to four surfels around the node's edge, -1 where the voxel does not exist (volume
  /// border). Slot q is the voxel in quadrant q of the (u, v) plane, where (axis, u, v) is the
  /// cyclic permutation (x: y,z; y: z,x; z: x,y) and the quadrants are (−,−), (+,−), (+,+), (−,+):
  /// counter-clockwise about the +axis direction.
  std::vector<std::array<std::int32_t, 4>> node_fan;
  /// 1 or 3: the fan slot of the surfel across a surfel's outgoing polygon edge at this node,
  /// relative to the surfel's own slot (the surface's orientation about the edge's axis; the
  /// same for every surfel of the fan). This is how opposites are found without storing them.
  std::vector<std::uint8_t> node_turn;

  // ---- Surfels (CSR). ----
  std::vector<std::uint32_t> surfel_offset;   ///< size num_surfels()+1
  /// Polygon nodes, oriented counter-clockwise seen from outside; edge k = (n[k], n[k+1 mod len]).
  std::vector<std::uint32_t> surfel_nodes;
  /// Linear index of the voxel's lower corner. Nothing after the construction needs it (graph,
  /// simplification, refinement): callers short of memory may release it (8 B per surfel).
  std::vector<std::uint64_t> surfel_voxel;
  std::vector<float> cvertex;                 ///< 3 per surfel: average of its node positions

  /// (From the fans, which stay when release_node_geometry() drops the keys and positions.)
  std::size_t num_nodes() const noexcept { return node_fan.size(); }
  std::size_t num_surfels() const noexcept {
    return surfel_offset.empty() ? 0 : surfel_offset.size() - 1;
  }
  std::span<const std::uint32_t> nodes_of(std::size_t s) const noexcept {
    return {surfel_nodes.data() + surfel_offset[s], surfel_offset[s + 1] - surfel_offset[s]};
  }
  /// The surfel across polygon edge k = (n[k], n[k+1]) of s — the one sharing that face segment
  /// in the neighbouring voxel — or -1 when the segment lies on the volume border. Not stored
  /// (memory: 16 bytes per surfel): read off the fan of n[k], node_turn slots after s's own.
  std::int32_t opposite(std::size_t s, std::size_t k) const noexcept {
    const std::uint32_t n = surfel_nodes[surfel_offset[s] + k];
    return opposite_at(s, n);
  }
  /// opposite(s, k) for every polygon edge of s, in polygon order.
  PolygonOpposites opposites_of(std::size_t s) const noexcept {
    PolygonOpposites out;
    const std::uint32_t b = surfel_offset[s];
    out.n = surfel_offset[s + 1] - b;
    for (std::uint32_t k = 0; k < out.n; ++k) out.v[k] = opposite_at(s, surfel_nodes[b + k]);
    return out;
  }
  /// The surfel across s's outgoing polygon edge at node n (n a node of s), or -1.
  std::int32_t opposite_at(std::size_t s, std::uint32_t n) const noexcept {
    const auto& fan = node_fan[n];
    const auto self = static_cast<std::int32_t>(s);
    int q = 0;
    while (q < 3 && fan[q] != self) ++q;
    return fan[(q + node_turn[n]) & 3];
  }
  Vec3 node_position(std::size_t n) const noexcept {
    return {node_pos[3 * n], node_pos[3 * n + 1], node_pos[3 * n + 2]};
  }
  Vec3 cvertex_position(std::size_t s) const noexcept {
    return {cvertex[3 * s], cvertex[3 * s + 1], cvertex[3 * s + 2]};
  }
  /// Node id for an edge key, or -1 (binary search).
  std::int64_t find_node(std::uint64_t key) const noexcept;
  /// Number of polygon edges on the volume border (border segments).
  std::size_t num_border_segments() const noexcept;
  /// Number of face segments: an interior segment is an edge of two surfels, a border one of one.
  std::size_t num_segments() const noexcept {
    return (surfel_nodes.size() + num_border_segments()) / 2;
  }
  /// Euler characteristic of the complex: nodes − segments + surfels.
  std::int64_t euler_characteristic() const noexcept {
    return static_cast<std::int64_t>(num_nodes()) - static_cast<std::int64_t>(num_segments()) +
           static_cast<std::int64_t>(num_surfels());
  }
};

/// Builds the surfel complex of `volume` at `iso`. Parallel over z-slabs without locks, with
/// `context.threads` workers; the result is byte-identical for any thread count. Ambiguous faces: asymptotic decider on the
/// face's own four values (saddle value 0 counts as positive), so both voxels of a face agree.
/// Orientation is combinatorial (docs/TOPOLOGY.md): polygons are counter-clockwise seen from the
/// negative side, i.e. their normal follows −inside_sign·∇f, also for grids whose direction
/// matrix reverses orientation. No interior tunnels are modelled (ALGORITHM.md 2.2).
/// A volume with fewer than 2 samples along an axis has no voxels: empty complex.
/// \throw Error(invalid_input) when iso is not finite or inside_sign is not ±1;
///        Error(unsupported) when ids would overflow 32 bits.
SurfelComplex build_surfels(const Volume& volume, double iso, double inside_sign = 1,
                            const ExecutionContext& context = default_context());

/// Memory: releases node_key and node_pos (20 bytes per node). Nothing in the covering
/// (build_covering) reads them; restore_node_geometry() recomputes them before anything else does.
void release_node_geometry(SurfelComplex& complex);

/// Recomputes node_key and node_pos, bit-identical to build_surfels, from the volume the complex
/// was built from (same grid, iso-value and sign). No-op when they are present.
/// \throw Error(internal) when the volume's nodes do not match the complex.
void restore_node_geometry(const Volume& volume, SurfelComplex& complex,
                           const ExecutionContext& context = default_context());

/// Reference marching cubes: triangulates every surfel polygon over the shared node vertices
/// (vertex i = node i), maximising each polygon's minimum angle. Watertight where the surface is
/// closed, 2-manifold, consistently oriented (normals out), no degenerate or duplicate triangles;
/// χ(mesh) = complex.euler_characteristic(). Parallel (ambient oneTBB arena), deterministic.
Mesh marching_cubes(const SurfelComplex& complex);

/// Reference marching cubes straight from the volume: the same mesh as
/// marching_cubes(build_surfels(volume, iso, inside_sign, context)), byte for byte and for any
/// thread count, without building the complex (no keys, fans, c-vertices): the same count and
/// prefix passes, then one fill pass writing node positions and each polygon's triangles.
/// `num_surfels` (optional) receives the number of surfels (polygons) triangulated.
/// \throw as build_surfels.
Mesh marching_cubes(const Volume& volume, double iso, double inside_sign = 1,
                    const ExecutionContext& context = default_context(),
                    std::size_t* num_surfels = nullptr);

}  // namespace adamesh
