// The connectivity graph G (ALGORITHM.md 2.3): one vertex per surfel (its c-vertex), an edge
// between two surfels that share a node, weighted by the Euclidean distance of their c-vertices.
// Shortest paths in G are the discrete geodesics of the method.
//
// Memory: build_graph stores no weights (they would cost as much as the columns, 4 bytes per
// directed edge); a weight is recomputed from the two c-vertices when needed, to the same float.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "adamesh/surfels.h"
#include "adamesh/vec.h"

namespace adamesh {

struct ConnectivityGraph {
  /// CSR rows: neighbours of v are col[row[v] .. row[v+1]). Each row lists v's neighbours in
  /// *link order* — surface order around v: edge-, corner-, edge-neighbour, ... read off v's
  /// polygon and its nodes' fans, starting at v's first polygon edge — each neighbour once.
  std::vector<std::uint32_t> row;
  std::vector<std::uint32_t> col;
  /// Stored edge weights (same indexing as col), or empty: then the weight of an edge is
  /// computed from `position`. build_graph leaves it empty; hand-built graphs may fill it.
  std::vector<float> weight;
  /// c-vertex coordinates, 3 floats per vertex, when `weight` is empty. build_graph points it at
  /// the complex's `cvertex`: the complex must outlive the graph (and keep its c-vertices).
  const float* position = nullptr;
  std::vector<std::uint8_t> border;       ///< 1 when the surfel has a segment on the volume border
  std::vector<std::uint32_t> component;   ///< component id, numbered by smallest vertex
  std::uint32_t num_components = 0;

  std::size_t num_vertices() const noexcept { return row.empty() ? 0 : row.size() - 1; }
  std::size_t num_edges() const noexcept { return col.size() / 2; }  ///< undirected
  std::span<const std::uint32_t> neighbours(std::size_t v) const noexcept {
    return {col.data() + row[v], row[v + 1] - row[v]};
  }
  /// Weight of the edge (v, col[k]), row[v] ≤ k < row[v+1]: |c(v) − c(col[k])| in world units,
  /// rounded to float (stored, or recomputed bit-identically from the c-vertices).
  float edge_weight(std::size_t v, std::size_t k) const noexcept {
    if (!weight.empty()) return weight[k];
    return cvertex_distance(position, v, col[k]);
  }
  /// |c(a) − c(b)| rounded to float, c-vertices read from `pos` (3 floats per vertex).
  static float cvertex_distance(const float* pos, std::size_t a, std::size_t b) noexcept {
    const float* p = pos + 3 * a;
    const float* q = pos + 3 * b;
    return static_cast<float>(distance(Vec3{p[0], p[1], p[2]}, Vec3{q[0], q[1], q[2]}));
  }
};

/// Builds G from the surfel complex (no stored weights: `position` = complex.cvertex). Parallel
/// over vertices; deterministic.
ConnectivityGraph build_graph(const SurfelComplex& complex);

}  // namespace adamesh
