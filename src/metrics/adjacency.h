// Edge and vertex adjacency of a triangle soup, built in parallel and numbered deterministically:
// corners grouped by vertex, and triangle sides grouped by undirected edge. Shared by the
// topology report and the edge deviation ε_e.
#pragma once

#include <cstdint>
#include <vector>

#include "adamesh/mesh.h"
#include "metrics/buffers.h"

namespace adamesh::detail {

constexpr std::uint32_t kNone = 0xffffffffu;

/// Side s = 3t + k of triangle t runs from tri[k] to tri[(k+1) % 3]; corner c = 3t + k is
/// vertex tri[k] of triangle t. Only *proper* triangles (three distinct indices) take part.
struct Adjacency {
  RawVector<std::uint8_t> proper;  ///< per triangle: 1 when its three indices differ

  /// Corners grouped by vertex, increasing corner id within a vertex.
  std::vector<std::uint32_t> corner_offset;  ///< num_vertices + 1
  RawVector<std::uint32_t> vertex_corners;

  /// Edges numbered in (smaller vertex, larger vertex) order; their sides in increasing id.
  RawVector<std::uint32_t> edge_offset;  ///< num_edges + 1
  RawVector<std::uint32_t> edge_sides;
  RawVector<std::uint32_t> side_edge;    ///< per side: edge id, kNone for collapsed triangles

  std::size_t num_edges() const noexcept { return edge_offset.size() - 1; }
  std::uint32_t edge_valence(std::size_t e) const noexcept {
    return edge_offset[e + 1] - edge_offset[e];
  }
  std::uint32_t corners_of(std::size_t v) const noexcept {
    return corner_offset[v + 1] - corner_offset[v];
  }
};

/// Builds the adjacency (call inside the caller's thread arena). Requires valid indices and
/// fewer than 2^32 / 3 triangles.
Adjacency build_adjacency(const Mesh& mesh);

/// Vertices of side s.
inline std::uint32_t side_from(const Mesh& m, std::uint32_t s) { return m.triangles[s]; }
inline std::uint32_t side_to(const Mesh& m, std::uint32_t s) {
  return m.triangles[s - s % 3 + (s % 3 + 1) % 3];
}

}  // namespace adamesh::detail
