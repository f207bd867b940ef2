// Bounding-volume hierarchy over a mesh's triangles for exact closest-point distance queries
// (Hausdorff distances).
//
// Build: median split on the longest axis of the centroid bounds (nth_element on references
// that carry their centroid; ties by index, so the split is unique), down to leaves of at most
// kLeaf triangles. Node positions follow from the subtree sizes alone, so the tree is identical
// for any thread count; the top levels are built in parallel. Each inner node stores the boxes of
// both children, so a traversal step reads one cache line.
#pragma once

#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "adamesh/mesh.h"
#include "adamesh/vec.h"
#include "metrics/buffers.h"

namespace adamesh::detail {

constexpr std::uint32_t kNoTriangle = 0xffffffffu;

/// Squared distance from p to the triangle (a, b, c); degenerate triangles are handled as
/// their three segments. After Ericson, Real-Time Collision Detection, 5.1.5.
double point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

class TriangleBvh {
 public:
  static constexpr std::uint32_t kLeaf = 4;

  /// Indexes every triangle of `mesh` (call inside the caller's thread arena).
  explicit TriangleBvh(const Mesh& mesh);

  struct Closest {
    double distance2 = std::numeric_limits<double>::infinity();
    std::uint32_t triangle = kNoTriangle;  ///< none when the mesh has no triangles
  };
  /// Exact closest triangle to p (ties: whichever the traversal meets first). `hint`, e.g. the
  /// answer for a nearby point, seeds the search bound: same distance, often fewer steps.
  Closest closest(const Vec3& p, std::uint32_t hint = kNoTriangle) const;
  bool empty() const noexcept { return prims_.empty(); }

 private:
  struct Box3f {
    float lo[3], hi[3];
  };
  /// Inner node: boxes and references of its two children. A reference r ≥ 0 is an inner node,
  /// r < 0 the leaf ~r, whose primitives are [leaf_begin_[~r], leaf_begin_[~r + 1]).
  struct Node {
    Box3f box[2];
    std::int32_t child[2];
  };
  /// Builds [begin, end) at inner-node slot `slot` with its first leaf numbered `leaf`; returns
  /// the subtree's reference and its box.
  std::int32_t build(std::uint32_t slot, std::uint32_t begin, std::uint32_t end, std::uint32_t leaf,
                     Box3f& box);
  std::uint32_t subtree_inner_nodes(std::uint32_t n) const;
  double distance2_to(const Vec3& p, std::uint32_t slot) const;

  RawVector<Node> nodes_;
  Box3f root_box_{};
  std::int32_t root_ = 0;
  RawVector<std::uint32_t> prims_;  ///< triangle ids in leaf order
  RawVector<std::uint32_t> slot_;   ///< triangle id -> position in prims_
  RawVector<std::uint32_t> leaf_begin_;  ///< leaf id -> first primitive; one extra entry
  RawVector<float> corners_;        ///< 9 floats per primitive, in leaf order
  std::vector<std::pair<std::uint32_t, std::uint32_t>> leaves_of_size_;  ///< n -> leaf count
  struct PrimRef {
    float c[3];  ///< centroid
    std::uint32_t id;
  };
  RawVector<PrimRef> refs_;   ///< only during construction
  const Mesh* mesh_ = nullptr;  ///< only during construction
};

}  // namespace adamesh::detail
