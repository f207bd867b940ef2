// Area-weighted sample layout, referenced vertices and distance summaries (see sampling.h).
#include "metrics/sampling.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "metrics/parallel.h"

namespace adamesh::detail {

SampleLayout layout_samples(const Mesh& m, std::uint64_t n) {
  const std::size_t nt = m.num_triangles();
  RawVector<double> area(nt);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 1 << 14), [&](const auto& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const Vec3 a = m.vertex(m.triangles[3 * t]);
      area[t] = 0.5 * norm(cross(m.vertex(m.triangles[3 * t + 1]) - a, m.vertex(m.triangles[3 * t + 2]) - a));
    }
  });
  SampleLayout s;
  s.first.assign(nt + 1, 0);
  double total = 0;
  for (std::size_t t = 0; t < nt; ++t) total += area[t];
  if (!(total > 0)) return s;  // no area: no samples
  double c = 0;
  const double scale = static_cast<double>(n) / total;
  for (std::size_t t = 0; t < nt; ++t) {
    c += area[t];
    s.first[t + 1] = std::min<std::uint64_t>(n, static_cast<std::uint64_t>(std::floor(c * scale)));
  }
  s.first[nt] = n;  // c may end a rounding error short of the total
  return s;
}

std::vector<std::uint32_t> referenced_vertices(const Mesh& m) {
  std::vector<std::uint8_t> used(m.num_vertices(), 0);
  for (const std::uint32_t v : m.triangles) used[v] = 1;
  std::vector<std::uint32_t> out;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (used[v]) out.push_back(static_cast<std::uint32_t>(v));
  return out;
}

DistanceStats summarize_distances(RawVector<double>& d, double vertex_max) {
  DistanceStats s;
  s.samples = static_cast<std::int64_t>(d.size());
  s.max = vertex_max;
  if (d.empty()) return s;
  const double sum = chunked_sum(d.size(), [&](std::size_t i) { return d[i]; });
  const double sum2 = chunked_sum(d.size(), [&](std::size_t i) { return d[i] * d[i]; });
  s.mean = sum / static_cast<double>(d.size());
  s.rms = std::sqrt(sum2 / static_cast<double>(d.size()));
  s.max = std::max(vertex_max, *std::max_element(d.begin(), d.end()));
  s.p99 = percentile(d, 99);
  return s;
}

}  // namespace adamesh::detail
