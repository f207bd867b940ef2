// Least-squares vertex positions (issue 13, docs/QUALITY.md "Fit"): vertices on the surface make
// the error one-sided — a chord of a convex patch lies inside it everywhere — so moving each
// vertex along its normal to minimise the squared distance of its triangles to the surface
// halves the error on convex patches.
//
// Each pass, for every triangle T and seven sample points s of T (centroid, three interior
// points, three edge midpoints; weight |T|/7 each), the first-order signed distance
// d(s) = (f(s) − iso)/|∇f(s)| and the unit gradient ĝ(s); moving vertex v by t·n_v moves s by
// w_v(s)·t·n_v and d by w_v(s)·t·(n_v·ĝ). Minimising Σ |T|/7 · d² over t_v alone:
//   t_v = −Σ w d (n_v·ĝ) / Σ (w (n_v·ĝ))²,
// applied to all vertices at once with damping (Jacobi), |t_v| capped. Sums per triangle are
// computed in parallel and added per vertex in a fixed order: identical for any thread count.
// Moves that make triangles intersect are undone (vertices of the new intersecting pairs back
// to where they were, until the count is not above the count before).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/improve.h"
#include "adamesh/metrics.h"

namespace adamesh {
namespace {

constexpr int kSamples = 7;
// Barycentric weights of the sample points.
constexpr double kBary[kSamples][3] = {{1. / 3, 1. / 3, 1. / 3}, {2. / 3, 1. / 6, 1. / 6},
                                       {1. / 6, 2. / 3, 1. / 6}, {1. / 6, 1. / 6, 2. / 3},
                                       {0.5, 0.5, 0},           {0, 0.5, 0.5},
                                       {0.5, 0, 0.5}};

Vec3 cross3(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/// Smallest interior angle (radians) of triangle abc.
double smallest_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  auto at = [](const Vec3& o, const Vec3& u, const Vec3& w) {
    return std::atan2(norm(cross3(u - o, w - o)), dot(u - o, w - o));
  };
  const double x = at(a, b, c), y = at(b, c, a);
  return std::max(0.0, std::min({x, y, std::numbers::pi - x - y}));
}

/// A move may not make a triangle of the vertex's ring sharper than this unless it was already.
constexpr double kMinAngleDeg = 20;

}  // namespace

FitStats fit_least_squares(Mesh& mesh, const std::vector<std::uint8_t>& fixed,
                           const ScalarField& field, double iso, const FitOptions& o,
                           const ExecutionContext& context) {
  if (context.threads > 0) {
    // The same call inside an arena of that many threads, with the caller's progress callback
    // and cancellation flag (it used to drop them: `--fit l2` could not be cancelled).
    ExecutionContext inside = context;
    inside.threads = 0;
    tbb::task_arena arena(context.threads);
    return arena.execute([&] { return fit_least_squares(mesh, fixed, field, iso, o, inside); });
  }
  FitStats st;
  const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();
  if (nt == 0) return st;
  if (!(o.max_step > 0) || !std::isfinite(o.max_step))
    fail(Status::usage, "fit_least_squares: max_step must be positive");
  std::vector<Vec3> p(nv);
  for (std::size_t v = 0; v < nv; ++v) p[v] = mesh.vertex(v);
  const std::vector<Vec3> start = p;
  auto tri = [&](std::size_t t) {
    return std::array<std::uint32_t, 3>{mesh.triangles[3 * t], mesh.triangles[3 * t + 1],
                                        mesh.triangles[3 * t + 2]};
  };
  // Vertices that stay: fixed ones and those on the mesh boundary.
  std::vector<std::uint8_t> hold(nv, 0);
  for (std::size_t v = 0; v < nv && v < fixed.size(); ++v) hold[v] = fixed[v];
  {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> edges;
    edges.reserve(3 * nt);
    for (std::size_t t = 0; t < nt; ++t) {
      const auto c = tri(t);
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = std::min(c[k], c[(k + 1) % 3]), b = std::max(c[k], c[(k + 1) % 3]);
        edges.push_back({(std::uint64_t{a} << 32) | b, 0});
      }
    }
    std::sort(edges.begin(), edges.end());
    for (std::size_t i = 0; i < edges.size();) {
      std::size_t j = i;
      while (j < edges.size() && edges[j].first == edges[i].first) ++j;
      if (j - i == 1) {
        hold[edges[i].first >> 32] = 1;
        hold[edges[i].first & 0xffffffffu] = 1;
      }
      i = j;
    }
  }
  // Per-triangle partial sums: [corner] numerator, denominator; plus the squared error.
  std::vector<std::array<double, 6>> part(nt);
  std::vector<double> err2(nt), area(nt);
  std::vector<Vec3> normal(nv);
  auto measure_and_sum = [&](bool sums) {
    // Area-weighted vertex normals.
    std::fill(normal.begin(), normal.end(), Vec3{});
    for (std::size_t t = 0; t < nt; ++t) {
      const auto c = tri(t);
      const Vec3 n = cross3(p[c[1]] - p[c[0]], p[c[2]] - p[c[0]]);
      for (auto v : c) normal[v] = normal[v] + n;
    }
    for (auto& n : normal) {
      const double l = norm(n);
      n = l > 0 ? (1.0 / l) * n : Vec3{};
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 1024), [&](const auto& r) {
      for (std::size_t t = r.begin(); t != r.end(); ++t) {
        const auto c = tri(t);
        const double a = 0.5 * norm(cross3(p[c[1]] - p[c[0]], p[c[2]] - p[c[0]]));
        area[t] = a;
        std::array<double, 6> s{};
        double e2 = 0;
        for (const auto& b : kBary) {
          const Vec3 x = b[0] * p[c[0]] + b[1] * p[c[1]] + b[2] * p[c[2]];
          const Vec3 g = field.gradient(x);
          const double gl = norm(g);
          if (!(gl > 0) || !std::isfinite(gl)) continue;
          const double d = (field.value(x) - iso) / gl;
          if (!std::isfinite(d)) continue;
          e2 += a / kSamples * d * d;
          if (!sums) continue;
          const Vec3 gh = (1.0 / gl) * g;
          for (int k = 0; k < 3; ++k) {
            const double wg = b[k] * dot(normal[c[k]], gh);
            s[2 * k] += a / kSamples * wg * d;
            s[2 * k + 1] += a / kSamples * wg * wg;
          }
        }
        part[t] = s;
        err2[t] = e2;
      }
    });
    double e = 0, at = 0;
    for (std::size_t t = 0; t < nt; ++t) e += err2[t], at += area[t];
    return at > 0 ? std::sqrt(e / at) : 0.0;
  };

  st.rms_before = measure_and_sum(false);
  const std::int64_t crossings_measured = self_intersections(mesh).pairs;  // −1: not measured
  const std::size_t crossings_before = static_cast<std::size_t>(std::max<std::int64_t>(crossings_measured, 0));
  // Triangles around each vertex (CSR), for the angle guard.
  std::vector<std::uint32_t> inc_off(nv + 1, 0), inc;
  for (std::size_t t = 0; t < nt; ++t)
    for (auto v : tri(t)) ++inc_off[v + 1];
  for (std::size_t v = 0; v < nv; ++v) inc_off[v + 1] += inc_off[v];
  inc.resize(inc_off.back());
  {
    std::vector<std::uint32_t> fill(inc_off.begin(), inc_off.end() - 1);
    for (std::size_t t = 0; t < nt; ++t)
      for (auto v : tri(t)) inc[fill[v]++] = static_cast<std::uint32_t>(t);
  }
  auto ring_min_angle = [&](std::uint32_t v, const Vec3& at) {
    double m = std::numbers::pi;
    for (std::uint32_t i = inc_off[v]; i < inc_off[v + 1]; ++i) {
      auto c = tri(inc[i]);
      Vec3 x[3] = {p[c[0]], p[c[1]], p[c[2]]};
      for (int k = 0; k < 3; ++k)
        if (c[k] == v) x[k] = at;
      m = std::min(m, smallest_angle(x[0], x[1], x[2]));
    }
    return m;
  };
  std::vector<double> num(nv), den(nv);
  std::vector<Vec3> next(nv);
  for (int pass = 0; pass < o.passes; ++pass) {
    context.report("fit", static_cast<double>(pass) / o.passes);
    measure_and_sum(true);
    std::fill(num.begin(), num.end(), 0.0);
    std::fill(den.begin(), den.end(), 0.0);
    for (std::size_t t = 0; t < nt; ++t) {
      const auto c = tri(t);
      for (int k = 0; k < 3; ++k) num[c[k]] += part[t][2 * k], den[c[k]] += part[t][2 * k + 1];
    }
    next = p;
    for (std::uint32_t v = 0; v < nv; ++v) {
      if (hold[v] || !(den[v] > 0)) continue;
      const double t = std::clamp(-o.damping * num[v] / den[v], -o.max_step, o.max_step);
      Vec3 q = p[v] + t * normal[v];
      if (o.box.lo.x < o.box.hi.x)
        for (int k = 0; k < 3; ++k) q[k] = std::clamp(q[k], o.box.lo[k], o.box.hi[k]);
      const double before = ring_min_angle(v, p[v]);
      if (ring_min_angle(v, q) < std::min(before, kMinAngleDeg * std::numbers::pi / 180)) {
        ++st.guarded;
        continue;
      }
      next[v] = q;
    }
    p.swap(next);
    ++st.passes;
  }
  auto write = [&] {
    for (std::size_t v = 0; v < nv; ++v)
      for (int k = 0; k < 3; ++k) mesh.positions[3 * v + k] = static_cast<float>(p[v][k]);
  };
  write();
  // No new intersections: undo the moves of the vertices of intersecting triangles.
  for (int round = 0; round < 20 && crossings_measured >= 0; ++round) {
    const IntersectionReport r = self_intersections(mesh, nt * nt);
    if (r.pairs < 0) break;
    st.intersections_after = static_cast<std::size_t>(r.pairs);
    if (st.intersections_after <= crossings_before) break;
    std::size_t undone = 0;
    for (const auto& [a, b] : r.first_pairs)
      for (auto t : {a, b})
        for (auto v : tri(t))
          if (p[v].x != start[v].x || p[v].y != start[v].y || p[v].z != start[v].z)
            p[v] = start[v], ++undone;
    if (undone == 0) break;
    st.undone += undone;
    write();
  }
  st.intersections_before = crossings_before;
  for (std::size_t v = 0; v < nv; ++v)
    st.moved += p[v].x != start[v].x || p[v].y != start[v].y || p[v].z != start[v].z;
  st.rms_after = measure_and_sum(false);
  mesh.normals.clear();
  return st;
}

}  // namespace adamesh
