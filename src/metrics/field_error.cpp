// Error of a mesh against the iso-surface of a scalar field (docs/METRICS.md "Against a field",
// ALGORITHM.md section 4):
//   distance  each area-weighted sample point's (and vertex's) distance to the surface, measured
//             as the length of its converged Newton projection (project_to_iso);
//   ε_e       Σ_e D(mid e)² · Σ_{T∋e} A(T)/2  /  Σ_T A(T)   (border edges: A(T1)/2);
//   ε_n       Σ_T A(T) (1 − n(T)·m(T)) / Σ_T A(T), n the unit triangle normal and m the unit
//             outward field normal −inside_sign·∇f/|∇f| at the centroid.
// A projection that does not converge, or that ends more than 4× the first-order distance away,
// is replaced by the nearest surface crossing on short lines through the point (along the
// triangle or vertex normal, the gradient and the three axes; farther when none crosses), else by
// |signed_distance|, and counted in `unconverged`.
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>

#include "adamesh/metrics.h"
#include "adamesh/volume.h"
#include "metrics/adjacency.h"
#include "metrics/buffers.h"
#include "metrics/mesh_check.h"
#include "metrics/parallel.h"
#include "metrics/sampling.h"

namespace adamesh {

FieldErrorReport field_error(const Mesh& mesh, const ScalarField& field, double iso,
                             const FieldErrorOptions& opt, const ExecutionContext& context) {
  detail::check_mesh(mesh);
  return detail::with_threads(context, [&] {
    FieldErrorReport r;
    const std::size_t nt = mesh.num_triangles();
    const std::uint32_t* tri = mesh.triangles.data();
    r.diagonal = mesh.bounds().diagonal();
    const double scale = std::max(r.diagonal, field.domain().diagonal());
    ProjectOptions po;
    po.max_steps = opt.max_steps;
    po.tolerance = opt.tolerance > 0 ? opt.tolerance : 1e-7 * (r.diagonal > 0 ? r.diagonal : scale);
    if (opt.max_step > 0) {
      po.max_step = opt.max_step;
    } else {  // mean edge length (each interior edge counted twice: no matter for a mean)
      const double len = detail::chunked_sum(nt, [&](std::size_t t) {
        const Vec3 a = mesh.vertex(tri[3 * t]), b = mesh.vertex(tri[3 * t + 1]), c = mesh.vertex(tri[3 * t + 2]);
        return distance(a, b) + distance(b, c) + distance(c, a);
      });
      po.max_step = nt > 0 ? len / (3.0 * static_cast<double>(nt)) : scale;
    }
    po.max_step = std::max(po.max_step, po.tolerance);
    const double cap = scale > 0 ? scale : 1.0;
    // Distances are measured on exact derivatives: the field's own gradient when analytic, else
    // differences of its values.
    const std::unique_ptr<ScalarField> differenced = make_differenced_field(field, 1e-6 * cap);
    const ScalarField& mf = field.is_analytic() ? field : *differenced;

    // Nearest crossing of f = iso on the segment p ± R·u: scanned outwards at t = R·(k/kScan)²
    // on each side (fine near p, where thin features matter), the first sign change refined by
    // bisection. +inf when there is none.
    constexpr int kScan = 24;
    auto line_crossing = [&](const Vec3& p, const Vec3& u, double f0, double R) {
      double best = std::numeric_limits<double>::infinity();
      if (!(norm2(u) > 0) || f0 == 0) return f0 == 0 ? 0.0 : best;
      for (const double side : {1.0, -1.0}) {
        double t0 = 0, v0 = f0;
        for (int k = 1; k <= kScan; ++k) {
          const double t1 = side * R * (double(k) / kScan) * (double(k) / kScan);
          const double v1 = mf.value(p + t1 * u) - iso;
          if (!std::isfinite(v1)) break;
          if ((v0 < 0) != (v1 < 0) || v1 == 0) {
            double a = t0, b = t1, va = v0;
            for (int it = 0; it < 60 && std::abs(b - a) > po.tolerance; ++it) {
              const double m = 0.5 * (a + b), vm = mf.value(p + m * u) - iso;
              if ((vm < 0) == (va < 0) && vm != 0) {
                a = m;
                va = vm;
              } else {
                b = m;
              }
            }
            best = std::min(best, std::abs(b));
            break;
          }
          t0 = t1;
          v0 = v1;
        }
      }
      return best;
    };
    // Distance of p to the surface. The Newton projection is taken when it converged and stayed
    // near: no farther than kFarFactor × the first-order distance |f − iso|/|∇f| (plus the
    // tolerance). Otherwise (no convergence, or the steps left the nearby sheet, as a sampled
    // field's interpolated gradient can make them do) the distance is the nearest surface point
    // among the converged projection and the crossings on the lines through p along `normal`
    // (the triangle's normal; may be zero) and along ∇f(p), up to kSearch steps away; every
    // candidate is a point of the surface, so the result is an upper bound. With no candidate
    // the first-order distance is used. Both cases are counted in `unconverged`.
    constexpr double kFarFactor = 4, kSearch = 4;
    constexpr int kShells = 24;
    std::atomic<std::int64_t> unconverged{0};
    auto dist = [&](const Vec3& p, const Vec3& normal) {
      const double f0 = mf.value(p) - iso;
      const Vec3 g = mf.gradient(p);
      const double gl = norm(g);
      double sd = f0 == 0 ? 0.0 : (gl > 0 && std::isfinite(gl) ? std::abs(f0) / gl : cap);
      if (!std::isfinite(sd)) sd = cap;  // NaN field values: count as far away
      sd = std::min(sd, cap);
      const ProjectResult pr = project_to_iso(mf, iso, p, po);
      const double d = distance(pr.point, p);
      if (pr.converged && d <= kFarFactor * sd + po.tolerance) return d;
      unconverged.fetch_add(1, std::memory_order_relaxed);
      if (!std::isfinite(f0)) return cap;
      const double R = std::max(kSearch * po.max_step, std::min(2 * sd, cap));
      double best = pr.converged ? d : std::numeric_limits<double>::infinity();
      // Lines along the normal, the gradient and the three axes (a flat field — label masks,
      // saturated data — has no gradient a voxel away from the surface, and a crossing found on
      // one line can be much farther than the nearest point), then the same four times farther.
      const double R2 = std::min(std::max(4 * R, 16 * po.max_step), cap);
      for (const double radius : {R, R2}) {
        best = std::min(best, line_crossing(p, normal, f0, radius));
        if (gl > 0 && std::isfinite(gl)) best = std::min(best, line_crossing(p, g / gl, f0, radius));
        for (int k = 0; k < 3; ++k) {
          Vec3 e{};
          e[k] = 1;
          best = std::min(best, line_crossing(p, e, f0, radius));
        }
        if (std::isfinite(best)) break;
      }
      if (std::isfinite(best)) return best;
      // Still nothing (a thin feature the five lines miss, in a flat field): the nearest sign
      // change on cubic shells of growing radius around p, refined along the segment to it.
      const double step = std::max(0.5 * po.max_step, 1e-9 * cap);
      for (int k = 1; k <= kShells && !std::isfinite(best); ++k) {
        const double r = k * step;
        for (int a = 0; a < 3; ++a)
          for (const double side : {-1.0, 1.0})
            for (int i = -k; i <= k; ++i)
              for (int j = -k; j <= k; ++j) {
                Vec3 q = p;
                q[a] += side * r;
                q[(a + 1) % 3] += i * step;
                q[(a + 2) % 3] += j * step;
                const double v = mf.value(q) - iso;
                if (!std::isfinite(v) || ((v < 0) == (f0 < 0) && v != 0)) continue;
                const Vec3 u = q - p;
                const double len = norm(u);
                best = std::min(best, line_crossing(p, u / len, f0, len * 1.0001));
              }
      }
      return std::isfinite(best) ? best : sd;
    };

    auto normal_of = [&](std::size_t t) {
      const Vec3 a = mesh.vertex(tri[3 * t]);
      return normalized(cross(mesh.vertex(tri[3 * t + 1]) - a, mesh.vertex(tri[3 * t + 2]) - a));
    };

    // Distances of the sample points and vertices.
    const std::uint64_t n = opt.samples > 0 ? static_cast<std::uint64_t>(opt.samples)
                                            : static_cast<std::uint64_t>(default_sample_count(mesh));
    const detail::SampleLayout layout = detail::layout_samples(mesh, n);
    detail::RawVector<double> d(layout.count());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 256), [&](const auto& rg) {
      for (std::size_t t = rg.begin(); t != rg.end(); ++t)
        for (std::uint64_t g = layout.first[t]; g < layout.first[t + 1]; ++g)
          d[g] = dist(detail::sample_point(mesh, t, g), normal_of(t));
    });
    const std::vector<std::uint32_t> verts = detail::referenced_vertices(mesh);
    std::vector<Vec3> vnormal(mesh.num_vertices());
    for (std::size_t t = 0; t < nt; ++t) {
      const Vec3 a = mesh.vertex(tri[3 * t]);
      const Vec3 nrm = cross(mesh.vertex(tri[3 * t + 1]) - a, mesh.vertex(tri[3 * t + 2]) - a);
      for (int k = 0; k < 3; ++k) vnormal[tri[3 * t + k]] += nrm;
    }
    const double vmax = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, verts.size(), 1024), 0.0,
        [&](const auto& rg, double m) {
          for (std::size_t i = rg.begin(); i != rg.end(); ++i) m = std::max(m, dist(mesh.vertex(verts[i]), normalized(vnormal[verts[i]])));
          return m;
        },
        [](double a, double b) { return std::max(a, b); });
    r.distance = detail::summarize_distances(d, vmax);
    d = {};
    r.distance_rel = r.distance;
    if (r.diagonal > 0)
      for (double* x : {&r.distance_rel.mean, &r.distance_rel.rms, &r.distance_rel.max, &r.distance_rel.p99})
        *x /= r.diagonal;

    // Triangle areas and ε_n.
    detail::RawVector<double> area(nt);
    std::atomic<std::int64_t> flat{0};
    const double total_area = detail::chunked_sum(nt, [&](std::size_t t) {
      const Vec3 a = mesh.vertex(tri[3 * t]), b = mesh.vertex(tri[3 * t + 1]), c = mesh.vertex(tri[3 * t + 2]);
      area[t] = 0.5 * norm(cross(b - a, c - a));
      return area[t];
    });
    const double normal_sum = detail::chunked_sum(nt, [&](std::size_t t) {
      const Vec3 a = mesh.vertex(tri[3 * t]), b = mesh.vertex(tri[3 * t + 1]), c = mesh.vertex(tri[3 * t + 2]);
      const Vec3 nrm = normalized(cross(b - a, c - a));
      const Vec3 g = field.gradient((a + b + c) / 3.0);
      const double gl = norm(g);
      Vec3 m{};
      if (gl > 0 && std::isfinite(gl)) m = (-opt.inside_sign / gl) * g;
      else flat.fetch_add(1, std::memory_order_relaxed);
      return area[t] * (1.0 - dot(nrm, m));
    });

    // ε_e over the edges of the proper triangles.
    const detail::Adjacency adj = detail::build_adjacency(mesh);
    const double edge_sum = detail::chunked_sum(adj.num_edges(), [&](std::size_t e) {
      const std::uint32_t* es = adj.edge_sides.data() + adj.edge_offset[e];
      const std::uint32_t s = es[0];
      const Vec3 mid = 0.5 * (mesh.vertex(detail::side_from(mesh, s)) + mesh.vertex(detail::side_to(mesh, s)));
      double w = 0;
      for (std::uint32_t i = 0; i < adj.edge_valence(e); ++i) w += 0.5 * area[es[i] / 3];
      if (w == 0) return 0.0;
      const double dm = dist(mid, normal_of(es[0] / 3));
      return dm * dm * w;
    });

    if (total_area > 0) {
      r.eps_e = edge_sum / total_area;
      r.eps_n = normal_sum / total_area;
    }
    r.eps_e_sqrt_rel = r.diagonal > 0 ? std::sqrt(r.eps_e) / r.diagonal : 0;
    r.unconverged = unconverged.load();
    r.flat_gradient_triangles = flat.load();
    return r;
  });
}

VolumeBoundsReport vertices_outside_volume(const Mesh& mesh, const Grid& grid) {
  VolumeBoundsReport r;
  const Mat3 to_index = grid.index_to_world_matrix().inverse();
  const Vec3 tol = grid.float_rounding_in_index();
  for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
    const Vec3 u = to_index * (mesh.vertex(v) - grid.origin);
    double beyond = 0;  // past a face by more than the rounding: how far
    for (int a = 0; a < 3; ++a) {
      const double past = std::max(-u[a], u[a] - static_cast<double>(grid.dims[a] - 1));
      if (past > tol[a]) beyond = std::max(beyond, past);
    }
    if (beyond > 0) {
      ++r.outside;
      r.max_voxels = std::max(r.max_voxels, beyond);
    }
  }
  return r;
}

}  // namespace adamesh
