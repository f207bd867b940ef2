// Binary triangle forest of 4-8 (newest-vertex) bisection, shared by the refinement drivers and
// the replay of a stored hierarchy (ALGORITHM.md 2.8).
//
// Triangles are (v0, v1, v2) with v0 the newest vertex and (v1, v2) the refinement edge;
// nbr[i] is the triangle across the edge opposite v[i] (kNone on the border). Splitting the
// block of t bisects t and, when present, its neighbour across the refinement edge, which must
// share it as refinement edge (compatible). Ids are canonical: split number s creates vertex
// V0+s and triangles F0+4s+{0,1} (children of t) and F0+4s+{2,3} (children of the neighbour),
// so the ids of a triangle or vertex do not depend on which other splits were applied.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace adamesh::detail {

inline constexpr std::uint32_t kNone = 0xffffffffu;

struct ForestTri {
  std::array<std::uint32_t, 3> v{kNone, kNone, kNone};
  std::array<std::uint32_t, 3> nbr{kNone, kNone, kNone};
  std::uint32_t split = kNone;  ///< split that bisected it (kNone: leaf)
  std::uint8_t level = 0;
  std::uint8_t role = 0;        ///< 0: the split's `triangle`, 1: its neighbour
  std::uint8_t alive = 0;       ///< created (base, or child of an applied split)
};

class Forest {
 public:
  /// Builds neighbours from shared edges. Edges with more than two triangles or inconsistent
  /// orientation get no neighbour; `nonmanifold_edges()` counts them.
  Forest(std::span<const std::array<std::uint32_t, 3>> base, std::uint32_t num_base_vertices);

  std::uint32_t num_base_triangles() const noexcept { return f0_; }
  std::uint32_t num_base_vertices() const noexcept { return v0_; }
  std::size_t nonmanifold_edges() const noexcept { return nonmanifold_; }
  std::size_t num_leaves() const noexcept { return leaves_; }
  std::size_t num_applied() const noexcept { return applied_; }

  bool exists(std::uint32_t t) const noexcept { return t < tris_.size() && tris_[t].alive; }
  bool is_leaf(std::uint32_t t) const noexcept { return exists(t) && tris_[t].split == kNone; }
  const ForestTri& tri(std::uint32_t t) const noexcept { return tris_[t]; }
  /// Triangle across t's refinement edge (kNone on the border).
  std::uint32_t partner(std::uint32_t t) const noexcept { return tris_[t].nbr[0]; }
  /// t's partner shares t's refinement edge as its own refinement edge (or t is on the border).
  bool compatible(std::uint32_t t) const noexcept {
    const std::uint32_t p = tris_[t].nbr[0];
    return p == kNone || tris_[p].nbr[0] == t;
  }
  std::uint32_t child(std::uint32_t t, int k) const noexcept {
    return f0_ + 4 * tris_[t].split + 2 * tris_[t].role + static_cast<std::uint32_t>(k);
  }
  std::uint32_t vertex_of_split(std::uint32_t s) const noexcept { return v0_ + s; }
  /// Split that created t (kNone for base triangles).
  std::uint32_t creator(std::uint32_t t) const noexcept {
    return t < f0_ ? kNone : (t - f0_) / 4;
  }

  /// Bisects the block of leaf t as split number s. Returns false and changes nothing when t is
  /// not a leaf, the neighbour is not a compatible leaf, or s was used already.
  bool split(std::uint32_t t, std::uint32_t s);

  /// Leaves in depth-first order (base triangles in order, children in order).
  std::vector<std::uint32_t> leaves() const;
  /// Throws std::logic_error naming the first broken invariant (tests, debugging).
  void check() const;

 private:
  void ensure(std::uint32_t s);
  void relink(std::uint32_t t, std::uint32_t old_nbr, std::uint32_t new_nbr);

  std::uint32_t f0_ = 0, v0_ = 0;
  std::vector<ForestTri> tris_;
  std::vector<std::uint8_t> used_split_;
  std::size_t leaves_ = 0, applied_ = 0, nonmanifold_ = 0;
};

}  // namespace adamesh::detail
