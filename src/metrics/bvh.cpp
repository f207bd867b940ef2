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
  // Branch-free: the larger of (lo − x), (x − hi) and 0 on each axis.
  const double dx = std::max({double(lo[0]) - p.x, p.x - double(hi[0]), 0.0});
  const double dy = std::max({double(lo[1]) - p.y, p.y - double(hi[1]), 0.0});
  const double dz = std::max({double(lo[2]) - p.z, p.z - double(hi[2]), 0.0});
  return dx * dx + dy * dy + dz * dz;
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

std::uint32_t TriangleBvh::subtree_inner_nodes(std::uint32_t n) const {
  for (const auto& [size, leaves] : leaves_of_size_)
    if (size == n) return leaves - 1;
  return 0;  // not reached: every size met by build() is in the table
}

TriangleBvh::TriangleBvh(const Mesh& mesh) {
  const auto nt = static_cast<std::uint32_t>(mesh.num_triangles());
  if (nt == 0) return;
  // Leaf counts of every subtree size the middle splits produce (at most two sizes per level).
  {
    std::vector<std::uint32_t> level = {nt}, sizes;
    while (!level.empty()) {
      std::vector<std::uint32_t> next;
      for (std::uint32_t n : level) {
        if (std::find(sizes.begin(), sizes.end(), n) != sizes.end()) continue;
        sizes.push_back(n);
        if (n > kLeaf) next.insert(next.end(), {n / 2, n - n / 2});
      }
      level = std::move(next);
    }
    std::sort(sizes.begin(), sizes.end());  // children first
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
  // Primitive references carry their centroid: the median splits then touch contiguous memory.
  refs_.resize(nt);
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, nt, 1 << 14), [&](const auto& r) {
    for (std::uint32_t t = r.begin(); t != r.end(); ++t) {
      PrimRef& ref = refs_[t];
      ref.id = t;
      for (int k = 0; k < 3; ++k)
        ref.c[k] = (mesh.positions[3 * mesh.triangles[3 * std::size_t{t}] + k] +
                    mesh.positions[3 * mesh.triangles[3 * std::size_t{t} + 1] + k] +
                    mesh.positions[3 * mesh.triangles[3 * std::size_t{t} + 2] + k]) / 3.0f;
    }
  });
  prims_.resize(nt);
  const std::uint32_t leaves = subtree_inner_nodes(nt) + 1;
  nodes_.resize(leaves - 1);
  leaf_begin_.resize(leaves + 1);
  leaf_begin_[leaves] = nt;
  corners_.resize(9 * std::size_t{nt});
  mesh_ = &mesh;
  root_ = build(0, 0, nt, 0, root_box_);
  mesh_ = nullptr;
  refs_ = {};
  slot_.resize(nt);
  for (std::uint32_t i = 0; i < nt; ++i) slot_[prims_[i]] = i;
}

std::int32_t TriangleBvh::build(std::uint32_t slot, std::uint32_t begin, std::uint32_t end,
                                std::uint32_t leaf, Box3f& box) {
  const std::uint32_t n = end - begin;
  if (n <= kLeaf) {
    leaf_begin_[leaf] = begin;
    for (std::uint32_t i = begin; i < end; ++i) prims_[i] = refs_[i].id;
    for (int k = 0; k < 3; ++k) {
      box.lo[k] = std::numeric_limits<float>::infinity();
      box.hi[k] = -std::numeric_limits<float>::infinity();
    }
    for (std::uint32_t i = begin; i < end; ++i)
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) {
          const float x = mesh_->positions[3 * mesh_->triangles[3 * std::size_t{prims_[i]} + c] + k];
          corners_[9 * std::size_t{i} + 3 * c + k] = x;
          box.lo[k] = std::min(box.lo[k], x);
          box.hi[k] = std::max(box.hi[k], x);
        }
    return ~static_cast<std::int32_t>(leaf);
  }
  // Median split on the longest axis of the centroid bounds (ties by index: a unique split).
  float clo[3], chi[3];
  for (int k = 0; k < 3; ++k) clo[k] = chi[k] = refs_[begin].c[k];
  for (std::uint32_t i = begin + 1; i < end; ++i)
    for (int k = 0; k < 3; ++k) {
      clo[k] = std::min(clo[k], refs_[i].c[k]);
      chi[k] = std::max(chi[k], refs_[i].c[k]);
    }
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
  const std::uint32_t mid = begin + n / 2;
  std::nth_element(refs_.begin() + begin, refs_.begin() + mid, refs_.begin() + end,
                   [axis](const PrimRef& x, const PrimRef& y) {
                     return x.c[axis] < y.c[axis] || (x.c[axis] == y.c[axis] && x.id < y.id);
                   });
  const std::uint32_t left_slot = slot + 1, right_slot = slot + 1 + subtree_inner_nodes(n / 2);
  const std::uint32_t right_leaf = leaf + subtree_inner_nodes(n / 2) + 1;
  Node& nd = nodes_[slot];
  auto left = [&] { nd.child[0] = build(left_slot, begin, mid, leaf, nd.box[0]); };
  auto right = [&] { nd.child[1] = build(right_slot, mid, end, right_leaf, nd.box[1]); };
  if (n >= kParallelBuild) tbb::parallel_invoke(left, right);
  else {
    left();
    right();
  }
  for (int k = 0; k < 3; ++k) {
    box.lo[k] = std::min(nd.box[0].lo[k], nd.box[1].lo[k]);
    box.hi[k] = std::max(nd.box[0].hi[k], nd.box[1].hi[k]);
  }
  return static_cast<std::int32_t>(slot);
}

double TriangleBvh::distance2_to(const Vec3& p, std::uint32_t i) const {
  const float* c = corners_.data() + 9 * std::size_t{i};
  return point_triangle_distance2(p, {c[0], c[1], c[2]}, {c[3], c[4], c[5]}, {c[6], c[7], c[8]});
}

TriangleBvh::Closest TriangleBvh::closest(const Vec3& p, std::uint32_t hint) const {
  Closest best;
  if (prims_.empty()) return best;
  if (hint < slot_.size()) {
    best.distance2 = distance2_to(p, slot_[hint]);
    best.triangle = hint;
  }
  struct Entry {
    std::int32_t ref;
    double d2;
  } stack[96];
  int top = 0;
  stack[top++] = {root_, box_distance2(p, root_box_.lo, root_box_.hi)};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.d2 >= best.distance2) continue;
    if (e.ref < 0) {
      const std::uint32_t leaf = ~static_cast<std::uint32_t>(e.ref);
      for (std::uint32_t i = leaf_begin_[leaf]; i < leaf_begin_[leaf + 1]; ++i) {
        const double d2 = distance2_to(p, i);
        if (d2 < best.distance2) {
          best.distance2 = d2;
          best.triangle = prims_[i];
        }
      }
      continue;
    }
    const Node& nd = nodes_[static_cast<std::uint32_t>(e.ref)];
    const double d0 = box_distance2(p, nd.box[0].lo, nd.box[0].hi);
    const double d1 = box_distance2(p, nd.box[1].lo, nd.box[1].hi);
    // Push the farther child first so that the nearer one is searched first.
    const int near = d1 < d0 ? 1 : 0;
    const double dn = near ? d1 : d0, df = near ? d0 : d1;
    if (df < best.distance2) stack[top++] = {nd.child[1 - near], df};
    if (dn < best.distance2) stack[top++] = {nd.child[near], dn};
  }
  return best;
}

}  // namespace adamesh::detail
