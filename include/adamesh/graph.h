// The connectivity graph G (ALGORITHM.md 2.3): one vertex per surfel (its c-vertex), an edge
// between two surfels that share a node, weighted by the Euclidean distance of their c-vertices.
// Shortest paths in G are the discrete geodesics of the method.
//
// Memory: build_graph stores no weights (they would cost more than the columns); a weight is
// recomputed from the two c-vertices when needed, to the same float. Columns are 16-bit offsets
// when they fit (ConnectivityGraph::delta): 2 bytes per directed edge, ~16 per surfel.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iterator>
#include <span>
#include <vector>

#include "adamesh/surfels.h"
#include "adamesh/vec.h"

namespace adamesh {

struct ConnectivityGraph {
  /// CSR rows: the neighbours of v are entries row[v] .. row[v+1] of the column array. Each row
  /// lists v's neighbours in *link order* — surface order around v: edge-, corner-,
  /// edge-neighbour, ... read off v's polygon and its nodes' fans, starting at v's first polygon
  /// edge — each neighbour once.
  std::vector<std::uint32_t> row;
  /// Column array, absolute vertex ids. Empty when the columns are stored as `delta`.
  std::vector<std::uint32_t> col;
  /// Column array, compact form (memory: 2 instead of 4 bytes per directed edge): entry k of
  /// row v is the neighbour v + delta[k]. build_graph picks it whenever every neighbour lies
  /// within ±32767 ids of its vertex — on surfel graphs, whenever a voxel layer holds fewer than
  /// ~16k surfels, since surfel ids follow the voxel order.
  std::vector<std::int16_t> delta;
  /// Stored edge weights (same indexing as the columns), or empty: then the weight of an edge is
  /// computed from `position`. build_graph leaves it empty; hand-built graphs may fill it.
  std::vector<float> weight;
  /// c-vertex coordinates, 3 floats per vertex, when `weight` is empty. build_graph points it at
  /// the complex's `cvertex`: the complex must outlive the graph (and keep its c-vertices).
  const float* position = nullptr;
  std::vector<std::uint8_t> border;       ///< 1 when the surfel has a segment on the volume border
  std::vector<std::uint32_t> component;   ///< component id, numbered by smallest vertex
  std::uint32_t num_components = 0;

  /// Drops the adjacency (row and columns); border flags, components, positions and
  /// num_vertices() stay, neighbours() and the edge accessors may no longer be called.
  /// Memory: stages that need no neighbours (the dual triangulation) run without it.
  void release_adjacency();

  std::size_t num_vertices() const noexcept {
    return row.empty() ? border.size() : row.size() - 1;
  }
  std::size_t num_edges() const noexcept { return row.empty() ? 0 : row.back() / 2; }  ///< undirected
  /// The neighbour of v at column entry k, row[v] ≤ k < row[v+1].
  std::uint32_t neighbour(std::size_t v, std::size_t k) const noexcept {
    if (!col.empty()) return col[k];
    return static_cast<std::uint32_t>(static_cast<std::int64_t>(v) + delta[k]);
  }
  /// v's neighbours in link order, by value (a range for `for (auto u : g.neighbours(v))`).
  class Neighbours {
   public:
    class iterator {
     public:
      using iterator_category = std::input_iterator_tag;
      using value_type = std::uint32_t;
      using difference_type = std::ptrdiff_t;
      using pointer = const std::uint32_t*;
      using reference = std::uint32_t;  // by value: compact columns are decoded on the fly
      iterator() = default;
      iterator(const ConnectivityGraph* g, std::size_t v, std::size_t k) : g_(g), v_(v), k_(k) {}
      std::uint32_t operator*() const noexcept { return g_->neighbour(v_, k_); }
      iterator& operator++() noexcept { ++k_; return *this; }
      iterator operator++(int) noexcept { iterator old = *this; ++k_; return old; }
      bool operator==(const iterator& o) const noexcept { return k_ == o.k_; }
      bool operator!=(const iterator& o) const noexcept { return k_ != o.k_; }
     private:
      const ConnectivityGraph* g_ = nullptr;
      std::size_t v_ = 0, k_ = 0;
    };
    Neighbours(const ConnectivityGraph* g, std::size_t v) : g_(g), v_(v) {}
    iterator begin() const noexcept { return {g_, v_, g_->row[v_]}; }
    iterator end() const noexcept { return {g_, v_, g_->row[v_ + 1]}; }
    std::size_t size() const noexcept { return g_->row[v_ + 1] - g_->row[v_]; }
    std::uint32_t operator[](std::size_t i) const noexcept { return g_->neighbour(v_, g_->row[v_] + i); }
   private:
    const ConnectivityGraph* g_;
    std::size_t v_;
  };
  Neighbours neighbours(std::size_t v) const noexcept { return {this, v}; }
  /// Weight of the edge (v, neighbour(v, k)): |c(v) − c(u)| in world units, rounded to float
  /// (stored, or recomputed bit-identically from the c-vertices).
  float edge_weight(std::size_t v, std::size_t k) const noexcept {
    if (!weight.empty()) return weight[k];
    return cvertex_distance(position, v, neighbour(v, k));
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
