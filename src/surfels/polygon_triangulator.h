// Triangulation of one surfel polygon over its nodes, shared by marching_cubes(complex) and the
// direct marching_cubes(volume) of build_surfels.cpp so both give the same triangles, bit for bit.
// Polygons with more than three nodes: the classic O(k³) dynamic programme over the k-gon
// (Klincsek 1980) maximising the minimum angle, never using a diagonal reserved for the voxel
// across a face (detail::diagonal_allowed; see marching_cubes.cpp).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "adamesh/vec.h"
#include "surfels/cell_table.h"

namespace adamesh::detail {

/// sin² of the smallest angle (the angle is at most 60°, so this is monotone in it).
inline double min_angle_quality(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, bc = c - b, ca = a - c;
  const double l0 = norm2(ab), l1 = norm2(bc), l2 = norm2(ca);
  const double cr = norm2(cross(ab, ca));
  // Product of the two largest squared lengths (the sides adjacent to the smallest angle).
  const double lmin = std::min(l0, std::min(l1, l2));
  const double denom = (l0 * l1 * l2) / (lmin > 0 ? lmin : 1);
  return denom > 0 ? cr / denom : 0;
}

struct TriangulationCost {
  int bad = 0;         // diagonals reserved for the voxel across a face
  double quality = 0;  // min over triangles of min_angle_quality
  bool better_than(const TriangulationCost& o) const {
    return bad != o.bad ? bad < o.bad : quality > o.quality;
  }
};

inline constexpr int kMaxPolygonNodes = 12;  // a voxel has 12 edges

/// Triangulates one polygon; writes (len − 2) triangles of polygon positions into `tri`.
class PolygonTriangulator {
 public:
  void run(int len, const std::array<Vec3, kMaxPolygonNodes>& p,
           const std::array<int, kMaxPolygonNodes>& local_edge, std::uint32_t* tri,
           const std::uint32_t* ids) {
    if (len == 4) {  // the common case, same choice and order as the general programme
      const TriangulationCost c1{
          !diagonal_allowed(local_edge[1], local_edge[3]),
          std::min(min_angle_quality(p[0], p[1], p[3]), min_angle_quality(p[1], p[2], p[3]))};
      const TriangulationCost c2{
          !diagonal_allowed(local_edge[0], local_edge[2]),
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
        bad_[i][j] = !side && !diagonal_allowed(local_edge[i], local_edge[j]);
      }
    for (int i = 0; i + 1 < len; ++i) best_[i][i + 1] = TriangulationCost{0, 1e300};
    for (int gap = 2; gap < len; ++gap)
      for (int i = 0; i + gap < len; ++i) {
        const int j = i + gap;
        TriangulationCost best{1 << 20, -1};
        int arg = -1;
        for (int m = i + 1; m < j; ++m) {
          TriangulationCost c;
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
  bool bad_[kMaxPolygonNodes][kMaxPolygonNodes]{};
  TriangulationCost best_[kMaxPolygonNodes][kMaxPolygonNodes];
  int split_[kMaxPolygonNodes][kMaxPolygonNodes]{};
  std::uint32_t* out_ = nullptr;
  const std::uint32_t* ids_ = nullptr;
};

}  // namespace adamesh::detail
