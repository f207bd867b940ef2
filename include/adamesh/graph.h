// The connectivity graph G (ALGORITHM.md 2.3): one vertex per surfel (its c-vertex), an edge
// between two surfels that share a node, weighted by the Euclidean distance of their c-vertices.
// Shortest paths in G are the discrete geodesics of the method.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "adamesh/surfels.h"

namespace adamesh {

struct ConnectivityGraph {
  /// CSR rows: neighbours of v are col[row[v] .. row[v+1]). Each row lists v's neighbours in
  /// *link order* — surface order around v: edge-, corner-, edge-neighbour, ... read off v's
  /// polygon and its nodes' fans, starting at v's first polygon edge — each neighbour once.
  std::vector<std::uint32_t> row;
  std::vector<std::uint32_t> col;
  std::vector<float> weight;              ///< |c(v) − c(col)|, world units
  std::vector<std::uint8_t> border;       ///< 1 when the surfel has a segment on the volume border
  std::vector<std::uint32_t> component;   ///< component id, numbered by smallest vertex
  std::uint32_t num_components = 0;

  std::size_t num_vertices() const noexcept { return row.empty() ? 0 : row.size() - 1; }
  std::size_t num_edges() const noexcept { return col.size() / 2; }  ///< undirected
  std::span<const std::uint32_t> neighbours(std::size_t v) const noexcept {
    return {col.data() + row[v], row[v + 1] - row[v]};
  }
  std::span<const float> weights(std::size_t v) const noexcept {
    return {weight.data() + row[v], row[v + 1] - row[v]};
  }
};

/// Builds G from the surfel complex. Parallel over vertices; deterministic.
ConnectivityGraph build_graph(const SurfelComplex& complex);

}  // namespace adamesh
