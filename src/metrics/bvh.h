// Bounding-volume hierarchy over a mesh's triangles for exact closest-point distance queries
// (Hausdorff distances). Median split on the longest axis of the centroid bounds, leaves of at
// most kLeaf triangles, nodes in depth-first order at positions fixed by the subtree sizes, so
// the tree is the same for any thread count; the top levels are built in parallel.
#pragma once

#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "adamesh/mesh.h"
#include "adamesh/vec.h"

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
    std::uint32_t triangle = 0xffffffffu;  ///< none when the mesh has no triangles
  };
  /// Exact closest triangle to p (ties: whichever the traversal meets first). `hint`, e.g. the
  /// answer for a nearby point, seeds the search bound: faster, same distance.
  Closest closest(const Vec3& p, std::uint32_t hint = 0xffffffffu) const;
  bool empty() const noexcept { return nodes_.empty(); }

 private:
  double distance2_to(const Vec3& p, std::uint32_t slot) const;
  struct Node {
    float lo[3], hi[3];
    std::uint32_t index;  ///< leaf: first primitive; inner: right child (left child = this + 1)
    std::uint32_t count;  ///< leaf: primitives (> 0); inner: 0
  };
  void build(std::uint32_t node, std::uint32_t begin, std::uint32_t end,
             const std::vector<float>& centroids);
  std::uint32_t subtree_nodes(std::uint32_t n) const;

  std::vector<Node> nodes_;
  std::vector<std::uint32_t> prims_;  ///< triangle ids in leaf order
  std::vector<std::uint32_t> slot_;   ///< triangle id -> position in prims_
  std::vector<float> corners_;        ///< 9 floats per primitive, in leaf order
  std::vector<std::pair<std::uint32_t, std::uint32_t>> leaves_of_size_;  ///< n -> leaf count
  const Mesh* mesh_ = nullptr;  ///< only during construction
};

}  // namespace adamesh::detail
