// Refinement criterion (ALGORITHM.md 2.10): the variance of sampled signed distances,
// V_T(d) = A(d²) − A(d)², after Wood, Desbrun, Schröder & Breen, "Semi-regular mesh extraction
// from volumes" (2000), as used by Peixoto & Velho (2002).
//
// Samples: the barycentric grid with 4 subdivisions, (i, j, k)/4 with i + j + k = 4 — 15 points,
// corners included; d = T_S(p) = (f(p) − iso)/|∇f(p)| (signed_distance in field.h). sqrt(V_T)
// scales like L²κ (edge length L, curvature κ), so refinement depth follows curvature; the
// drivers also use max |d| (a constant offset, which the variance ignores).
#include <algorithm>
#include <cmath>

#include "refine_internal.h"

namespace adamesh::detail {

TriError evaluate_triangle(const ScalarField& f, double iso, const Vec3& a, const Vec3& b,
                           const Vec3& c) {
  constexpr int kDiv = 4;
  double sum = 0, sum2 = 0, mx = 0;
  int n = 0;
  for (int i = 0; i <= kDiv; ++i)
    for (int j = 0; i + j <= kDiv; ++j) {
      const int k = kDiv - i - j;
      const Vec3 p = (static_cast<double>(i) * a + static_cast<double>(j) * b +
                      static_cast<double>(k) * c) / static_cast<double>(kDiv);
      double d = signed_distance(f, iso, p, 1e30);
      if (!std::isfinite(d)) d = 1e30;
      sum += d;
      sum2 += d * d;
      mx = std::max(mx, std::abs(d));
      ++n;
    }
  const double mean = sum / n;
  const double var = std::max(0.0, sum2 / n - mean * mean);
  TriError e;
  e.sqrt_var = static_cast<float>(std::sqrt(var));
  e.max_abs = static_cast<float>(mx);
  e.area = static_cast<float>(0.5 * norm(cross(b - a, c - a)));
  return e;
}

}  // namespace adamesh::detail
