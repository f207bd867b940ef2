// Deterministic area-weighted sample points on a mesh (docs/METRICS.md "Sample points").
//
// Allocation: with C_t the summed area of triangles 0..t−1 and A the total, triangle t gets the
// samples g in [floor(N·C_t/A), floor(N·C_{t+1}/A)): exactly N in all, each triangle within one
// sample of N·A(T)/A. Placement: sample g is point g of the R2 low-discrepancy sequence,
// (u, v) = frac(0.5 + g·(1/φ₂, 1/φ₂²)) with φ₂ the plastic number, folded into the triangle
// (u + v > 1 → 1 − u, 1 − v) and mapped to a + u(b − a) + v(c − a). No random numbers.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "adamesh/mesh.h"
#include "adamesh/metrics.h"
#include "metrics/buffers.h"

namespace adamesh::detail {

struct SampleLayout {
  std::vector<std::uint64_t> first;  ///< num_triangles + 1 entries
  std::uint64_t count() const noexcept { return first.empty() ? 0 : first.back(); }
};

/// Allocates n samples over the triangles by area (call inside the caller's thread arena).
SampleLayout layout_samples(const Mesh& mesh, std::uint64_t n);

inline Vec3 sample_point(const Mesh& m, std::size_t t, std::uint64_t g) {
  constexpr double a1 = 0.7548776662466927, a2 = 0.5698402909980532;  // 1/φ₂, 1/φ₂²
  const double x = 0.5 + static_cast<double>(g) * a1, y = 0.5 + static_cast<double>(g) * a2;
  double u = x - std::floor(x), v = y - std::floor(y);
  if (u + v > 1) {
    u = 1 - u;
    v = 1 - v;
  }
  const Vec3 a = m.vertex(m.triangles[3 * t]);
  return a + u * (m.vertex(m.triangles[3 * t + 1]) - a) + v * (m.vertex(m.triangles[3 * t + 2]) - a);
}

/// Vertices referenced by at least one triangle, in increasing order.
std::vector<std::uint32_t> referenced_vertices(const Mesh& mesh);

/// mean, rms and p99 of the per-sample distances (reordered), max over them and `vertex_max`.
DistanceStats summarize_distances(RawVector<double>& sample_distances, double vertex_max);

}  // namespace adamesh::detail
