// Triangle quality (angles, radius ratio), surface area, divergence-theorem volume and the
// report that bundles them with the topology. Definitions: docs/METRICS.md.
//
// Per triangle with side lengths l0, l1, l2 and twice-area 2A = |(b−a)×(c−a)|:
//   q = 2 r_in / r_circ = 16A² / ((l0+l1+l2) l0 l1 l2), from r_in = 2A/(l0+l1+l2) and
//   r_circ = l0 l1 l2 / (4A); the angle at a corner is atan2(2A, dot of its two edge vectors)
//   (accurate for needles and flat triangles alike). The smallest angle faces the shortest side
//   and the largest the longest, so two atan2 per triangle suffice.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "adamesh/metrics.h"
#include "metrics/buffers.h"
#include "metrics/mesh_check.h"
#include "metrics/parallel.h"

namespace adamesh {

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

struct TriangleShape {
  double min_angle = 0, max_angle = 180, q = 0;  // degrees; zero-area defaults
};

TriangleShape shape_of(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e[3] = {c - b, a - c, b - a};  // e[i] is the side opposite corner i
  const double l[3] = {norm(e[0]), norm(e[1]), norm(e[2])};
  const double two_a = norm(cross(e[2], -e[1]));
  TriangleShape s;
  if (!(two_a > 0) || !(l[0] > 0) || !(l[1] > 0) || !(l[2] > 0)) return s;
  s.q = 4 * two_a * two_a / ((l[0] + l[1] + l[2]) * l[0] * l[1] * l[2]);
  s.q = std::min(s.q, 1.0);
  auto angle_at = [&](int i) {  // between the two sides meeting at corner i
    const Vec3 u = -e[(i + 1) % 3], v = e[(i + 2) % 3];
    return std::atan2(two_a, dot(u, v)) * kDeg;
  };
  const int shortest = static_cast<int>(std::min_element(l, l + 3) - l);
  const int longest = static_cast<int>(std::max_element(l, l + 3) - l);
  s.min_angle = angle_at(shortest);
  s.max_angle = angle_at(longest);
  return s;
}

struct QualityParts {
  std::array<std::int64_t, 20> hist{};
  std::array<std::int64_t, 3> below{};
  double q_sum = 0, q_min = 1, max_angle = 0;
};

}  // namespace

QualityReport quality(const Mesh& mesh, const ExecutionContext& context) {
  detail::check_mesh(mesh);
  return detail::with_threads(context, [&] {
    const std::size_t nt = mesh.num_triangles();
    const std::uint32_t* tri = mesh.triangles.data();
    QualityReport r;
    r.triangles = static_cast<std::int64_t>(nt);
    if (nt == 0) return r;
    detail::RawVector<float> min_angles(nt);
    const QualityParts p = detail::chunked_reduce(
        nt, QualityParts{},
        [&](std::size_t b, std::size_t e) {
          QualityParts part;
          for (std::size_t t = b; t < e; ++t) {
            const TriangleShape s = shape_of(mesh.vertex(tri[3 * t]), mesh.vertex(tri[3 * t + 1]),
                                             mesh.vertex(tri[3 * t + 2]));
            min_angles[t] = static_cast<float>(s.min_angle);
            ++part.hist[std::min(19, static_cast<int>(s.q * 20))];
            part.q_sum += s.q;
            part.q_min = std::min(part.q_min, s.q);
            part.max_angle = std::max(part.max_angle, s.max_angle);
            for (int k = 0; k < 3; ++k) part.below[k] += s.min_angle < 10.0 * (k + 1);
          }
          return part;
        },
        [](QualityParts a, const QualityParts& b) {
          for (int i = 0; i < 20; ++i) a.hist[i] += b.hist[i];
          for (int k = 0; k < 3; ++k) a.below[k] += b.below[k];
          a.q_sum += b.q_sum;
          a.q_min = std::min(a.q_min, b.q_min);
          a.max_angle = std::max(a.max_angle, b.max_angle);
          return a;
        });
    r.q_hist = p.hist;
    r.q_mean = p.q_sum / static_cast<double>(nt);
    r.q_min = p.q_min;
    r.max_angle = p.max_angle;
    for (int k = 0; k < 3; ++k) r.pct_min_angle_below[k] = 100.0 * p.below[k] / static_cast<double>(nt);
    r.min_angle.min = *std::min_element(min_angles.begin(), min_angles.end());
    r.min_angle.p1 = detail::percentile(min_angles, 1);
    r.min_angle.p5 = detail::percentile(min_angles, 5);
    r.min_angle.median = detail::percentile(min_angles, 50);
    return r;
  });
}

double surface_area(const Mesh& mesh, const ExecutionContext& context) {
  detail::check_mesh(mesh);
  const std::uint32_t* tri = mesh.triangles.data();
  return detail::with_threads(context, [&] {
    return detail::chunked_sum(mesh.num_triangles(), [&](std::size_t t) {
      const Vec3 a = mesh.vertex(tri[3 * t]);
      return 0.5 * norm(cross(mesh.vertex(tri[3 * t + 1]) - a, mesh.vertex(tri[3 * t + 2]) - a));
    });
  });
}

double signed_volume(const Mesh& mesh, const ExecutionContext& context) {
  detail::check_mesh(mesh);
  const Box box = mesh.bounds();
  const Vec3 o = 0.5 * (box.lo + box.hi);  // keeps the products small: less cancellation
  const std::uint32_t* tri = mesh.triangles.data();
  return detail::with_threads(context, [&] {
    return detail::chunked_sum(mesh.num_triangles(), [&](std::size_t t) {
      const Vec3 a = mesh.vertex(tri[3 * t]) - o, b = mesh.vertex(tri[3 * t + 1]) - o,
                 c = mesh.vertex(tri[3 * t + 2]) - o;
      return dot(a, cross(b, c)) / 6.0;
    });
  });
}

std::optional<double> enclosed_volume(const Mesh& mesh, const TopologyReport& topo,
                                      const ExecutionContext& context) {
  if (!topo.closed || !topo.oriented) return std::nullopt;
  return signed_volume(mesh, context);
}

std::int64_t default_sample_count(const Mesh& mesh) {
  return std::clamp<std::int64_t>(static_cast<std::int64_t>(mesh.num_triangles()), 200'000,
                                  2'000'000);
}

MeshReport mesh_report(const Mesh& mesh, const ExecutionContext& context) {
  MeshReport r;
  r.topology = topology(mesh, context);
  r.quality = quality(mesh, context);
  r.area = surface_area(mesh, context);
  r.volume = enclosed_volume(mesh, r.topology, context);
  r.bounds = mesh.bounds();
  r.self_intersecting_pairs = self_intersections(mesh, 0, context).pairs;
  return r;
}

}  // namespace adamesh
