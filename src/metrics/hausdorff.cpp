// One-sided and symmetric Hausdorff distances between two meshes: area-weighted sample points
// (metrics/sampling.h) and the referenced vertices of one mesh, each with its exact distance to
// the other mesh's closest triangle through a BVH (metrics/bvh.h).
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "adamesh/metrics.h"
#include "metrics/buffers.h"
#include "metrics/bvh.h"
#include "metrics/mesh_check.h"
#include "metrics/parallel.h"
#include "metrics/sampling.h"

namespace adamesh {

namespace {

DistanceStats one_sided(const Mesh& from, const detail::TriangleBvh& to, std::int64_t samples) {
  const std::uint64_t n = samples > 0 ? static_cast<std::uint64_t>(samples)
                                      : static_cast<std::uint64_t>(default_sample_count(from));
  // `hint`: the previous answer of this task, a good first bound for the next nearby point.
  auto dist = [&](const Vec3& p, std::uint32_t& hint) {
    if (to.empty()) return std::numeric_limits<double>::infinity();
    const detail::TriangleBvh::Closest c = to.closest(p, hint);
    hint = c.triangle;
    return std::sqrt(c.distance2);
  };
  const detail::SampleLayout layout = detail::layout_samples(from, n);
  detail::RawVector<double> d(layout.count());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, from.num_triangles(), 256), [&](const auto& r) {
    std::uint32_t hint = detail::kNoTriangle;
    for (std::size_t t = r.begin(); t != r.end(); ++t)
      for (std::uint64_t g = layout.first[t]; g < layout.first[t + 1]; ++g)
        d[g] = dist(detail::sample_point(from, t, g), hint);
  });
  const std::vector<std::uint32_t> verts = detail::referenced_vertices(from);
  const double vmax = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, verts.size(), 1024), 0.0,
      [&](const auto& r, double m) {
        std::uint32_t hint = detail::kNoTriangle;
        for (std::size_t i = r.begin(); i != r.end(); ++i) m = std::max(m, dist(from.vertex(verts[i]), hint));
        return m;
      },
      [](double a, double b) { return std::max(a, b); });
  return detail::summarize_distances(d, vmax);
}

}  // namespace

HausdorffReport hausdorff(const Mesh& a, const Mesh& b, const HausdorffOptions& options,
                          const ExecutionContext& context) {
  detail::check_mesh(a, "mesh");
  detail::check_mesh(b, "reference mesh");
  return detail::with_threads(context, [&] {
    HausdorffReport r;
    {
      const detail::TriangleBvh bvh_b(b);
      r.a_to_b = one_sided(a, bvh_b, options.samples);
    }
    {
      const detail::TriangleBvh bvh_a(a);
      r.b_to_a = one_sided(b, bvh_a, options.samples);
    }
    r.symmetric = std::max(r.a_to_b.max, r.b_to_a.max);
    r.diagonal = a.bounds().diagonal();
    r.symmetric_rel = r.diagonal > 0 ? r.symmetric / r.diagonal : 0;
    return r;
  });
}

}  // namespace adamesh
