// Triangle BVH construction and closest-point queries (see bvh.h).
#include "metrics/bvh.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace adamesh::detail {

namespace {

double segment_distance2(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double l2 = norm2(ab);
  const double t = l2 > 0 ? std::clamp(dot(p - a, ab) / l2, 0.0, 1.0) : 0.0;
  return norm2(p - (a + t * ab));
}

double box_distance2(const Vec3& p, const float lo[3], const float hi[3]) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double x = p[k];
    const double d = x < lo[k] ? lo[k] - x : (x > hi[k] ? x - hi[k] : 0.0);
    d2 += d * d;
  }
  return d2;
}

constexpr std::uint32_t kParallelBuild = 1 << 15;

}  // namespace

double point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a;
  if (norm2(cross(ab, ac)) == 0)  // degenerate: the closest point is on a side
    return std::min({segment_distance2(p, a, b), segment_distance2(p, b, c), segment_distance2(p, c, a)});
  const Vec3 ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return norm2(ap);  // vertex a
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return norm2(bp);  // vertex b
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return norm2(p - (a + (d1 / (d1 - d3)) * ab));  // side ab
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return norm2(cp);  // vertex c
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return norm2(p - (a + (d2 / (d2 - d6)) * ac));  // side ac
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {  // side bc
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return norm2(p - (b + w * (c - b)));
  }
  const double denom = 1.0 / (va + vb + vc);  // inside the face
  return norm2(p - (a + (vb * denom) * ab + (vc * denom) * ac));
}

std::uint32_t TriangleBvh::subtree_nodes(std::uint32_t n) const {
  for (const auto& [size, leaves] : leaves_of_size_)
    if (size == n) return 2 * leaves - 1;
  return 1;  // not reached: every size met by build() is in the table
}

TriangleBvh::TriangleBvh(const Mesh& mesh) {
  const auto nt = static_cast<std::uint32_t>(mesh.num_triangles());
  if (nt == 0) return;
  // Leaf counts of every subtree size the median splits produce (at most two sizes per level).
  {
    std::vector<std::uint32_t> level = {nt};
    std::vector<std::uint32_t> sizes;
    while (!level.empty()) {
      std::vector<std::uint32_t> next;
      for (std::uint32_t n : level) {
        if (std::find(sizes.begin(), sizes.end(), n) != sizes.end()) continue;
        sizes.push_back(n);
        if (n > kLeaf) {
          next.push_back(n / 2);
          next.push_back(n - n / 2);
        }
      }
      level = std::move(next);
    }
    std::sort(sizes.begin(), sizes.end());  // children are smaller: fill bottom-up
    for (std::uint32_t n : sizes) {
      std::uint32_t leaves = 1;
      if (n > kLeaf) {
        leaves = 0;
        for (std::uint32_t half : {n / 2, n - n / 2})
          for (const auto& [size, l] : leaves_of_size_)
            if (size == half) leaves += l;
      }
      leaves_of_size_.emplace_back(n, leaves);
    }
  }
  std::vector<float> centroids(3 * std::size_t{nt});
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, nt, 1 << 14), [&](const auto& r) {
    for (std::uint32_t t = r.begin(); t != r.end(); ++t)
      for (int k = 0; k < 3; ++k)
        centroids[3 * std::size_t{t} + k] =
            (mesh.positions[3 * mesh.triangles[3 * t] + k] + mesh.positions[3 * mesh.triangles[3 * t + 1] + k] +
             mesh.positions[3 * mesh.triangles[3 * t + 2] + k]) / 3.0f;
  });
  prims_.resize(nt);
  std::iota(prims_.begin(), prims_.end(), 0u);
  nodes_.resize(subtree_nodes(nt));
  corners_.resize(9 * std::size_t{nt});
  // Corner coordinates in leaf order, filled by build() at the leaves.
  mesh_ = &mesh;
  build(0, 0, nt, centroids);
  mesh_ = nullptr;
  slot_.resize(nt);
  for (std::uint32_t i = 0; i < nt; ++i) slot_[prims_[i]] = i;
}

double TriangleBvh::distance2_to(const Vec3& p, std::uint32_t i) const {
  const float* c = corners_.data() + 9 * std::size_t{i};
  return point_triangle_distance2(p, {c[0], c[1], c[2]}, {c[3], c[4], c[5]}, {c[6], c[7], c[8]});
}

void TriangleBvh::build(std::uint32_t node, std::uint32_t begin, std::uint32_t end,
                        const std::vector<float>& centroids) {
  Node& nd = nodes_[node];
  const std::uint32_t n = end - begin;
  if (n <= kLeaf) {
    nd.index = begin;
    nd.count = n;
    for (int k = 0; k < 3; ++k) {
      nd.lo[k] = std::numeric_limits<float>::infinity();
      nd.hi[k] = -std::numeric_limits<float>::infinity();
    }
    for (std::uint32_t i = begin; i < end; ++i)
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) {
          const float x = mesh_->positions[3 * mesh_->triangles[3 * std::size_t{prims_[i]} + c] + k];
          corners_[9 * std::size_t{i} + 3 * c + k] = x;
          nd.lo[k] = std::min(nd.lo[k], x);
          nd.hi[k] = std::max(nd.hi[k], x);
        }
    return;
  }
  float clo[3], chi[3];
  for (int k = 0; k < 3; ++k) {
    clo[k] = std::numeric_limits<float>::infinity();
    chi[k] = -std::numeric_limits<float>::infinity();
  }
  for (std::uint32_t i = begin; i < end; ++i)
    for (int k = 0; k < 3; ++k) {
      const float x = centroids[3 * std::size_t{prims_[i]} + k];
      clo[k] = std::min(clo[k], x);
      chi[k] = std::max(chi[k], x);
    }
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
  const std::uint32_t mid = begin + n / 2;
  std::nth_element(prims_.begin() + begin, prims_.begin() + mid, prims_.begin() + end,
                   [&](std::uint32_t x, std::uint32_t y) {
                     const float cx = centroids[3 * std::size_t{x} + axis], cy = centroids[3 * std::size_t{y} + axis];
                     return cx < cy || (cx == cy && x < y);  // total order: unique split
                   });
  const std::uint32_t left = node + 1, right = node + 1 + subtree_nodes(n / 2);
  nd.index = right;
  nd.count = 0;
  if (n >= kParallelBuild)
    tbb::parallel_invoke([&] { build(left, begin, mid, centroids); },
                         [&] { build(right, mid, end, centroids); });
  else {
    build(left, begin, mid, centroids);
    build(right, mid, end, centroids);
  }
  for (int k = 0; k < 3; ++k) {
    nd.lo[k] = std::min(nodes_[left].lo[k], nodes_[right].lo[k]);
    nd.hi[k] = std::max(nodes_[left].hi[k], nodes_[right].hi[k]);
  }
}

TriangleBvh::Closest TriangleBvh::closest(const Vec3& p, std::uint32_t hint) const {
  Closest best;
  if (nodes_.empty()) return best;
  if (hint < slot_.size()) {
    best.distance2 = distance2_to(p, slot_[hint]);
    best.triangle = hint;
  }
  std::uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& nd = nodes_[stack[--top]];
    if (box_distance2(p, nd.lo, nd.hi) >= best.distance2) continue;
    if (nd.count > 0) {
      for (std::uint32_t i = nd.index; i < nd.index + nd.count; ++i) {
        const double d2 = distance2_to(p, i);
        if (d2 < best.distance2) {
          best.distance2 = d2;
          best.triangle = prims_[i];
        }
      }
      continue;
    }
    const std::uint32_t l = static_cast<std::uint32_t>(&nd - nodes_.data()) + 1, r = nd.index;
    const double dl = box_distance2(p, nodes_[l].lo, nodes_[l].hi);
    const double dr = box_distance2(p, nodes_[r].lo, nodes_[r].hi);
    // Push the farther child first so the nearer one is searched first.
    if (dl <= dr) {
      if (dr < best.distance2) stack[top++] = r;
      if (dl < best.distance2) stack[top++] = l;
    } else {
      if (dl < best.distance2) stack[top++] = l;
      if (dr < best.distance2) stack[top++] = r;
    }
  }
  return best;
}

}  // namespace adamesh::detail
