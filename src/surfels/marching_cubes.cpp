// Reference marching cubes: triangulates each surfel polygon over the shared node vertices.
//
// References: Lorensen & Cline, "Marching Cubes" (SIGGRAPH 1987); the polygons come from the
// face-consistent surfel complex (Nielson & Hamann's asymptotic decider on faces), so the mesh is
// crack-free. Polygons with more than three nodes are triangulated without new vertices by the
// classic O(k³) dynamic programme over the k-gon (Klincsek 1980) maximising the minimum angle.
//
// Manifoldness: polygon edges are face segments, shared by exactly the two surfels across the
// face (one on the volume border). A diagonal joins two nodes of one voxel; it could also be used
// by the neighbour only if both nodes lie on their common face — which happens on ambiguous faces
// (four nodes, two segments). Some cycles (116 of the 1026 configuration cycles, e.g. the 8- and
// 9-node saddles) cannot avoid such a diagonal, so the two voxels of a face split the four
// candidate pairs (detail::diagonal_allowed); the DP minimises the use of the other side's
// pairs first (always zero, checked for every configuration by tests/mc_test.cpp), so no edge
// has more than two triangles and no triangle is repeated.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <cassert>

#include "adamesh/surfels.h"
#include "surfels/cell_table.h"
#include "surfels/sized.h"

namespace adamesh {

namespace {

/// sin² of the smallest angle (the angle is at most 60°, so this is monotone in it).
double min_angle_quality(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, bc = c - b, ca = a - c;
  const double l0 = norm2(ab), l1 = norm2(bc), l2 = norm2(ca);
  const double cr = norm2(cross(ab, ca));
  // Product of the two largest squared lengths (the sides adjacent to the smallest angle).
  const double lmin = std::min(l0, std::min(l1, l2));
  const double denom = (l0 * l1 * l2) / (lmin > 0 ? lmin : 1);
  return denom > 0 ? cr / denom : 0;
}

struct Cost {
  int bad = 0;         // diagonals reserved for the voxel across a face
  double quality = 0;  // min over triangles of min_angle_quality
  bool better_than(const Cost& o) const {
    return bad != o.bad ? bad < o.bad : quality > o.quality;
  }
};

constexpr int kMax = 12;

/// Triangulates one polygon; writes (len − 2) triangles of polygon positions into `tri`.
class PolygonTriangulator {
 public:
  void run(int len, const std::array<Vec3, kMax>& p, const std::array<int, kMax>& local_edge,
           std::uint32_t* tri, const std::uint32_t* ids) {
    if (len == 4) {  // the common case, same choice and order as the general programme
      const Cost c1{!detail::diagonal_allowed(local_edge[1], local_edge[3]),
                    std::min(min_angle_quality(p[0], p[1], p[3]), min_angle_quality(p[1], p[2], p[3]))};
      const Cost c2{!detail::diagonal_allowed(local_edge[0], local_edge[2]),
                    std::min(min_angle_quality(p[0], p[2], p[3]), min_angle_quality(p[0], p[1], p[2]))};
      const int m = c2.better_than(c1) ? 2 : 1;
      const int o = m == 1 ? 1 : 0;  // second triangle (1,2,3) or (0,1,2)
      const std::uint32_t t[6] = {ids[0], ids[m], ids[3], ids[o], ids[o + 1], ids[o + 2]};
      std::copy(t, t + 6, tri);
      return;
    }
    len_ = len;
    for (int i = 0; i < len; ++i)
      for (int j = i + 1; j < len; ++j) {
        const bool side = j == i + 1 || (i == 0 && j == len - 1);
        bad_[i][j] = !side && !detail::diagonal_allowed(local_edge[i], local_edge[j]);
      }
    for (int i = 0; i + 1 < len; ++i) best_[i][i + 1] = Cost{0, 1e300};
    for (int gap = 2; gap < len; ++gap)
      for (int i = 0; i + gap < len; ++i) {
        const int j = i + gap;
        Cost best{1 << 20, -1};
        int arg = -1;
        for (int m = i + 1; m < j; ++m) {
          Cost c;
          c.bad = best_[i][m].bad + best_[m][j].bad + bad_[i][m] + bad_[m][j];
          c.quality = std::min(std::min(best_[i][m].quality, best_[m][j].quality),
                               min_angle_quality(p[i], p[m], p[j]));
          if (arg < 0 || c.better_than(best)) {
            best = c;
            arg = m;
          }
        }
        best_[i][j] = best;
        split_[i][j] = arg;
      }
    out_ = tri;
    ids_ = ids;
    emit(0, len - 1);
  }

 private:
  void emit(int i, int j) {
    if (j - i < 2) return;
    const int m = split_[i][j];
    *out_++ = ids_[i];
    *out_++ = ids_[m];
    *out_++ = ids_[j];
    emit(i, m);
    emit(m, j);
  }

  int len_ = 0;
  bool bad_[kMax][kMax]{};
  Cost best_[kMax][kMax];
  int split_[kMax][kMax]{};
  std::uint32_t* out_ = nullptr;
  const std::uint32_t* ids_ = nullptr;
};

}  // namespace

Mesh marching_cubes(const SurfelComplex& cx) {
  Mesh mesh;
  const std::size_t ns = cx.num_surfels();
  const std::size_t ntri = cx.surfel_nodes.size() - 2 * ns;
  tbb::parallel_invoke([&] { detail::sized(mesh.triangles, 3 * ntri); },
                       [&] { detail::sized(mesh.positions, cx.node_pos.size()); });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cx.node_pos.size(), 1 << 16),
                    [&](const auto& r) {
                      std::copy(cx.node_pos.begin() + r.begin(), cx.node_pos.begin() + r.end(),
                                mesh.positions.begin() + r.begin());
                    });
  const std::int64_t nx = cx.grid.dims[0], plane = cx.grid.dims[0] * cx.grid.dims[1];

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ns, 4096), [&](const auto& r) {
    PolygonTriangulator tri;
    std::array<Vec3, kMax> p;
    std::array<int, kMax> local_edge;
    for (std::size_t s = r.begin(); s < r.end(); ++s) {
      const auto nodes = cx.nodes_of(s);
      const int len = static_cast<int>(nodes.size());
      std::uint32_t* out = mesh.triangles.data() + 3 * (cx.surfel_offset[s] - 2 * s);
      if (len == 3) {
        out[0] = nodes[0];
        out[1] = nodes[1];
        out[2] = nodes[2];
        continue;
      }
      assert(len <= kMax);
      const auto voxel = static_cast<std::int64_t>(cx.surfel_voxel[s]);
      for (int k = 0; k < len; ++k) {
        const std::uint32_t n = nodes[k];
        p[k] = cx.node_position(n);
        const std::uint64_t key = cx.node_key[n];
        const int axis = static_cast<int>(key % 3);
        std::int64_t d = static_cast<std::int64_t>(key / 3) - voxel;  // lower endpoint − voxel
        const int dz = d >= plane;
        d -= dz * plane;
        const int dy = d >= nx;
        const int dx = static_cast<int>(d - dy * nx);
        const int o[3] = {dx, dy, dz};
        const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
        local_edge[k] = 4 * axis + o[a1] + 2 * o[a2];
      }
      tri.run(len, p, local_edge, out, nodes.data());
    }
  });
  return mesh;
}

}  // namespace adamesh
