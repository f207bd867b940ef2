// Least-squares vertex positions (issue 13, docs/QUALITY.md "Fit"): vertices on the surface make
// the error one-sided — a chord of a convex patch lies inside it everywhere — so moving each
// vertex along its normal to minimise the squared distance of its triangles to the surface
// halves the error on convex patches.
//
// Each pass, for every triangle T and seven sample points s of T (centroid, three interior
// points, three edge midpoints; weight |T|/7 each), the signed distance d(s) to the surface and
// the unit surface normal ĝ(s) there: d is the length of the Newton projection of s (on the
// derivative of the trilinear interpolant for sampled fields, as `adamesh stats --field`
// measures it), signed like f − iso, and ĝ the unit gradient at the projected point; where the
// projection does not converge or ends more than 4× the first-order distance away, the
// first-order (f − iso)/|∇f| and ∇f/|∇f| at s, which then counts in the error but does not
// steer the step. Moving vertex v by t·n_v moves s by
// w_v(s)·t·n_v and d by w_v(s)·t·(n_v·ĝ). Minimising Σ |T|/7 · d² over t_v alone:
//   t_v = −Σ w d (n_v·ĝ) / Σ (w (n_v·ĝ))²,
// applied to all vertices at once with damping (Jacobi), |t_v| capped. With free moves (the
// default) the step is not tied to n_v: moving v by δ moves d by w_v(s)·(ĝ·δ), and
//   δ_v = −(Σ w² ĝĝᵀ)⁺ Σ w d ĝ,
// the pseudo-inverse keeping only the eigen-directions whose eigenvalue is at least rank_ratio ×
// the largest (as dual contouring truncates its QEF): on a flat patch all ĝ agree and δ lies
// along the normal; on a curved one their spread also lets the vertex slide to where its
// triangles fit better; across a crease the normals of both sides span two directions and the
// vertex can move onto the crease, which a step along its normal cannot reach (docs/QUALITY.md
// "Free moves"). A direction no sample normal has a component in never moves. Sums per triangle are
// computed in parallel and added per vertex in a fixed order: identical for any thread count.
// The angle guard is checked on the pass's result (all moves at once), moves that break it
// undone until none does. Moves that make triangles intersect are undone (vertices of the new
// intersecting pairs back to where they were, until the count is not above the count before).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <iterator>
#include <numbers>
#include <optional>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/improve.h"
#include "adamesh/metrics.h"
#include "remesh/geometry.h"

namespace adamesh {
namespace {

using detail::smallest_angle;
using detail::symmetric_eigen;

constexpr int kSamples = 7, kInterior = 4;
// Barycentric weights of the sample points: four inside, then the midpoints of the sides
// (corners 0-1, 1-2, 2-0).
constexpr double kBary[kSamples][3] = {{1. / 3, 1. / 3, 1. / 3}, {2. / 3, 1. / 6, 1. / 6},
                                       {1. / 6, 2. / 3, 1. / 6}, {1. / 6, 1. / 6, 2. / 3},
                                       {0.5, 0.5, 0},           {0, 0.5, 0.5},
                                       {0.5, 0, 0.5}};

Vec3 cross3(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
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
  // Edges: side k of triangle t (corners k, k+1) is edge side_edge[3t+k]; an edge's midpoint is
  // a sample of both its triangles, measured once.
  std::vector<std::uint32_t> side_edge(3 * nt);
  std::vector<std::array<std::uint32_t, 2>> edge_ends;
  {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> edges;
    edges.reserve(3 * nt);
    for (std::size_t t = 0; t < nt; ++t) {
      const auto c = tri(t);
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = std::min(c[k], c[(k + 1) % 3]), b = std::max(c[k], c[(k + 1) % 3]);
        edges.push_back({(std::uint64_t{a} << 32) | b, static_cast<std::uint32_t>(3 * t + k)});
      }
    }
    std::sort(edges.begin(), edges.end());
    for (std::size_t i = 0; i < edges.size();) {
      std::size_t j = i;
      while (j < edges.size() && edges[j].first == edges[i].first) ++j;
      for (std::size_t q = i; q < j; ++q) side_edge[edges[q].second] = static_cast<std::uint32_t>(edge_ends.size());
      edge_ends.push_back({static_cast<std::uint32_t>(edges[i].first >> 32),
                           static_cast<std::uint32_t>(edges[i].first & 0xffffffffu)});
      if (j - i == 1) {
        hold[edges[i].first >> 32] = 1;
        hold[edges[i].first & 0xffffffffu] = 1;
      }
      i = j;
    }
  }
  // Distances on the derivative of the interpolant (sampled fields), as the evaluator does.
  const double diag = field.domain().diagonal();
  const std::unique_ptr<ScalarField> differenced =
      make_interpolant_gradient_field(field, 1e-6 * (diag > 0 ? diag : 1.0));
  const ScalarField& mf = field.is_analytic() ? field : *differenced;
  ProjectOptions po;
  po.max_steps = 8;
  po.max_step = 4 * o.max_step;
  po.tolerance = 1e-2 * o.max_step;
  // Signed distance d of x to the surface and the unit normal ĝ there (false: no gradient).
  auto surface_distance = [&](const Vec3& x, double& d, Vec3& gh, bool& reliable) {
    reliable = true;
    const ProjectResult pr = project_to_iso(mf, iso, x, po);
    const double sd = pr.start_distance;
    if (sd == 0 && pr.residual != 0) return false;  // flat at x, or not finite
    const double dist = distance(pr.point, x);
    const double gl = norm(pr.gradient);
    if (pr.converged && dist <= 4 * std::abs(sd) + po.tolerance && gl > 0 && std::isfinite(gl)) {
      d = std::copysign(dist, sd);
      gh = (1.0 / gl) * pr.gradient;
      return true;
    }
    // The first-order distance at x counts in the error but does not steer: a few tenths of a
    // voxel from a noisy or label surface it can point anywhere (frog at 100k: RMS 0.951 when
    // it steered, 0.915 when not, 0.956 on the surface).
    reliable = false;
    const Vec3 g = mf.gradient(x);
    const double gx = norm(g);
    if (!(gx > 0) || !std::isfinite(gx)) return false;
    d = sd;
    gh = (1.0 / gx) * g;
    return true;
  };
  // Per-triangle partial sums: [corner] numerator, denominator; plus the squared error.
  std::vector<std::array<double, 6>> part(nt);
  // Free (3D) steps: per corner the 3×3 normal matrix Σ w² ĝĝᵀ (6 entries) and Σ w d ĝ (3).
  const bool free3d = o.free_moves;
  std::vector<std::array<double, 27>> part3(free3d ? nt : 0);
  std::vector<double> err2(nt), area(nt);
  std::vector<Vec3> normal(nv);
  auto rms_of_err2 = [&] {
    double e = 0, at = 0;
    for (std::size_t t = 0; t < nt; ++t) e += err2[t], at += area[t];
    return at > 0 ? std::sqrt(e / at) : 0.0;
  };
  struct Sample {
    double d = 0;
    Vec3 gh;
    bool ok = false, reliable = false;
  };
  std::vector<Sample> mid(edge_ends.size());
  // Per-triangle error (and with `sums` the per-corner sums) at the positions p, for every
  // triangle or only those listed in `only`; returns the RMS over all triangles.
  auto measure_and_sum = [&](bool sums, const std::vector<std::uint32_t>* only = nullptr) {
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
    // The edge midpoints first: every edge, or those of the listed triangles.
    std::vector<std::uint32_t> edge_list;
    if (only) {
      for (const std::uint32_t t : *only)
        for (int k = 0; k < 3; ++k) edge_list.push_back(side_edge[3 * t + k]);
      std::sort(edge_list.begin(), edge_list.end());
      edge_list.erase(std::unique(edge_list.begin(), edge_list.end()), edge_list.end());
    }
    const std::size_t ecount = only ? edge_list.size() : edge_ends.size();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ecount, 2048), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        const std::uint32_t e = only ? edge_list[i] : static_cast<std::uint32_t>(i);
        Sample& m = mid[e];
        m.ok = surface_distance(0.5 * (p[edge_ends[e][0]] + p[edge_ends[e][1]]), m.d, m.gh, m.reliable);
      }
    });
    const std::size_t count = only ? only->size() : nt;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1024), [&](const auto& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        const std::size_t t = only ? (*only)[i] : i;
        const auto c = tri(t);
        const double a = 0.5 * norm(cross3(p[c[1]] - p[c[0]], p[c[2]] - p[c[0]]));
        area[t] = a;
        std::array<double, 6> s{};
        std::array<double, 27> s3{};
        double e2 = 0;
        for (int j = 0; j < kSamples; ++j) {
          const auto& b = kBary[j];
          double d;
          Vec3 gh;
          bool reliable;
          if (j < kInterior) {
            const Vec3 x = b[0] * p[c[0]] + b[1] * p[c[1]] + b[2] * p[c[2]];
            if (!surface_distance(x, d, gh, reliable)) continue;
          } else {  // the midpoint of side j − kInterior
            const Sample& m = mid[side_edge[3 * t + (j - kInterior)]];
            if (!m.ok) continue;
            d = m.d, gh = m.gh, reliable = m.reliable;
          }
          e2 += a / kSamples * d * d;
          if (!sums || !reliable) continue;
          for (int k = 0; k < 3; ++k) {
            const double wg = b[k] * dot(normal[c[k]], gh);
            s[2 * k] += a / kSamples * wg * d;
            s[2 * k + 1] += a / kSamples * wg * wg;
          }
          if (free3d)
            for (int k = 0; k < 3; ++k) {
              const double w2 = a / kSamples * b[k] * b[k], wd = a / kSamples * b[k] * d;
              double* m = &s3[9 * k];
              m[0] += w2 * gh.x * gh.x, m[1] += w2 * gh.x * gh.y, m[2] += w2 * gh.x * gh.z;
              m[3] += w2 * gh.y * gh.y, m[4] += w2 * gh.y * gh.z, m[5] += w2 * gh.z * gh.z;
              m[6] += wd * gh.x, m[7] += wd * gh.y, m[8] += wd * gh.z;
            }
        }
        part[t] = s;
        if (free3d) part3[t] = s3;
        err2[t] = e2;
      }
    });
    return rms_of_err2();
  };

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
  constexpr double kMinAngle = kMinAngleDeg * std::numbers::pi / 180;
  // True when a triangle around v is sharper with the positions `q` than min(with `ref`, 20°).
  auto ring_breaks = [&](const std::vector<Vec3>& q, const std::vector<Vec3>& ref,
                         std::uint32_t v) {
    for (std::uint32_t i = inc_off[v]; i < inc_off[v + 1]; ++i) {
      const auto c = tri(inc[i]);
      const double now = smallest_angle(q[c[0]], q[c[1]], q[c[2]]);
      if (now < kMinAngle && now < smallest_angle(ref[c[0]], ref[c[1]], ref[c[2]])) return true;
    }
    return false;
  };
  // Moves the vertices of `moved` whose ring breaks the guard back to `ref` until none does
  // (each round only moves vertices back, so it ends); `moved` keeps the others. Returns the
  // vertices moved back.
  auto guard = [&](std::vector<Vec3>& q, const std::vector<Vec3>& ref,
                   std::vector<std::uint32_t>& moved) {
    std::vector<std::uint32_t> back;
    for (bool changed = true; changed;) {
      changed = false;
      std::vector<std::uint32_t> keep;
      for (const std::uint32_t v : moved) {
        if (ring_breaks(q, ref, v)) {
          q[v] = ref[v];
          back.push_back(v);
          changed = true;
        } else {
          keep.push_back(v);
        }
      }
      moved.swap(keep);
    }
    return back;
  };
  auto ring_sum = [&](const std::vector<double>& e, std::uint32_t v) {
    double sum = 0;
    for (std::uint32_t i = inc_off[v]; i < inc_off[v + 1]; ++i) sum += e[inc[i]];
    return sum;
  };
  std::vector<double> num(nv), den(nv), old_err;
  std::vector<std::array<double, 9>> sum3(free3d ? nv : 0);
  std::vector<Vec3> next(nv);
  std::vector<std::uint8_t> touched(nt), moving(nv);
  st.rms_before = measure_and_sum(true);
  const Mat3 faces_to_world = o.faces.empty() ? Mat3{} : o.faces.to_index.inverse();
  for (int pass = 0; pass < o.passes; ++pass) {
    context.report("fit", static_cast<double>(pass) / o.passes);
    next = p;
    // Per vertex, in parallel: gather its triangles' sums (in ascending triangle order, the
    // order of the incidence lists, so the sums do not depend on the thread count), then the
    // step. `moving` marks the vertices that take one; they are listed in order afterwards.
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, static_cast<std::uint32_t>(nv), 1024),
                      [&](const auto& range) {
      for (std::uint32_t v = range.begin(); v != range.end(); ++v) {
        moving[v] = 0;
        double nu = 0, de = 0;
        std::array<double, 9> m3{};
        for (std::uint32_t i = inc_off[v]; i < inc_off[v + 1]; ++i) {
          const std::uint32_t t = inc[i];
          const auto c = tri(t);
          const int k = c[0] == v ? 0 : c[1] == v ? 1 : 2;
          nu += part[t][2 * k], de += part[t][2 * k + 1];
          if (free3d)
            for (int j = 0; j < 9; ++j) m3[j] += part3[t][9 * k + j];
        }
        num[v] = nu, den[v] = de;
        if (free3d) sum3[v] = m3;
        if (hold[v] || !(den[v] > 0)) continue;
        const double t = std::clamp(-o.damping * num[v] / den[v], -o.max_step, o.max_step);
        Vec3 q = p[v] + t * normal[v];
        if (free3d) {
          // Least squares over all three directions, truncated like dual contouring's QEF: only
          // directions whose curvature is at least kRank × the largest (a flat patch constrains
          // the normal alone, a crease two directions, a corner three).
          const auto& m = sum3[v];
          std::array<double, 3> w;
          std::array<Vec3, 3> ax;
          symmetric_eigen({m[0], m[1], m[2], m[1], m[3], m[4], m[2], m[4], m[5]}, w, ax);
          const Vec3 r{m[6], m[7], m[8]};
          Vec3 step{};
          for (int i = 0; i < 3; ++i)
            if (w[i] > 0 && w[i] >= o.rank_ratio * w[0]) step = step - (dot(ax[i], r) / w[i]) * ax[i];
          step = o.damping * step;
          const double len = norm(step);
          if (len > o.max_step) step = (o.max_step / len) * step;
          q = p[v] + step;
        }
        if (!o.faces.empty()) {  // oblique grid: clamped in index space (when outside only)
          Vec3 u = o.faces.to_index * (q - o.faces.origin);
          bool out = false;
          for (int k = 0; k < 3; ++k)
            if (u[k] < 0 || u[k] > o.faces.extent[k]) {
              u[k] = std::clamp(u[k], 0.0, o.faces.extent[k]);
              out = true;
            }
          if (out) q = o.faces.origin + faces_to_world * u;
        } else if (o.box.lo.x < o.box.hi.x) {
          for (int k = 0; k < 3; ++k) q[k] = std::clamp(q[k], o.box.lo[k], o.box.hi[k]);
        }
        next[v] = q;
        moving[v] = 1;
      }
    });
    std::vector<std::uint32_t> moved;
    for (std::uint32_t v = 0; v < nv; ++v)
      if (moving[v]) moved.push_back(v);
    // The guard on the pass's result (all moves at once): a moved vertex with a triangle around
    // it now sharper than min(before, 20°) goes back.
    st.guarded += guard(next, p, moved).size();
    // Measure the moved mesh; a vertex whose triangles are farther from the surface in sum than
    // before the pass goes back (the linearised step overshoots where the surface bends within a
    // triangle: voxel-sized triangles on noisy data), then the guard again, and the triangles
    // around the vertices that went back are measured again.
    old_err = err2;
    p.swap(next);  // p: the moved positions, next: the pass's start
    measure_and_sum(true);
    std::vector<std::uint32_t> back, kept;
    for (const std::uint32_t v : moved) (ring_sum(err2, v) > ring_sum(old_err, v) ? back : kept).push_back(v);
    for (const std::uint32_t v : back) p[v] = next[v];
    const std::vector<std::uint32_t> more = guard(p, next, kept);
    back.insert(back.end(), more.begin(), more.end());
    st.worse += back.size();
    if (!back.empty()) {
      std::fill(touched.begin(), touched.end(), 0);
      for (const std::uint32_t v : back)
        for (std::uint32_t i = inc_off[v]; i < inc_off[v + 1]; ++i) touched[inc[i]] = 1;
      std::vector<std::uint32_t> again;
      for (std::uint32_t t = 0; t < nt; ++t)
        if (touched[t]) again.push_back(t);
      measure_and_sum(true, &again);
    }
    ++st.passes;
  }
  auto write = [&] {
    for (std::size_t v = 0; v < nv; ++v)
      for (int k = 0; k < 3; ++k) mesh.positions[3 * v + k] = static_cast<float>(p[v][k]);
  };
  write();
  // No new intersections. Only pairs with a moved triangle can change: the pairs among them
  // are counted at the starting positions and now (intersecting_pairs_involving searches only
  // the grid cells of those triangles), and the moved vertices of every new pair go back, until
  // there is none (then the angle guard again).
  auto moved_vertex = [&](std::uint32_t v) {
    return p[v].x != start[v].x || p[v].y != start[v].y || p[v].z != start[v].z;
  };
  std::vector<std::uint8_t> involved(nt, 0);
  for (std::size_t t = 0; t < nt; ++t)
    for (auto v : tri(t)) involved[t] |= moved_vertex(v) ? 1 : 0;
  Mesh at_start = mesh;
  for (std::size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) at_start.positions[3 * v + k] = static_cast<float>(start[v][k]);
  using PairList = std::vector<std::pair<std::uint32_t, std::uint32_t>>;
  const std::optional<PairList> before = intersecting_pairs_involving(at_start, involved, context);
  at_start = Mesh{};
  if (before) {  // nullopt: not measured (piles of triangles)
    st.intersections_before = before->size();
    st.intersections_after = before->size();
    // After the first round only the triangles whose vertices went back can gain or lose a
    // pair: the other pairs stay, and the query asks about those triangles alone (each is an
    // involved one, so the pairs found are the ones the full query would add).
    std::optional<PairList> now = intersecting_pairs_involving(mesh, involved, context);
    std::vector<Vec3> prev;
    for (int round = 0; round < 20; ++round) {
      if (round > 0) {
        std::vector<std::uint8_t> changed(nt, 0);
        std::size_t n_changed = 0;
        for (std::size_t t = 0; t < nt; ++t) {
          for (auto v : tri(t)) changed[t] |= p[v] != prev[v] ? 1 : 0;
          n_changed += changed[t];
        }
        if (n_changed > 0) {
          const std::optional<PairList> near = intersecting_pairs_involving(mesh, changed, context);
          if (!near) break;
          now = pairs_after_change(*now, changed, *near);
        }
      }
      if (!now) break;
      st.intersections_after = now->size();
      prev = p;
      // Every pair left with a moved vertex, new or not: the pairs the mesh had are left as they
      // were for the separation that follows (moved, it could not push 3 of gyroid@128 20k's 7
      // apart; it separates all 7 unmoved).
      const PairList& added = *now;
      std::size_t undone = 0;
      for (const auto& [a, b] : added)
        for (auto t : {a, b})
          for (auto v : tri(t))
            if (moved_vertex(v)) p[v] = start[v], ++undone;
      if (undone == 0) break;
      st.undone += undone;
      // Moving some vertices back next to moved ones may sharpen triangles: the guard again,
      // against the starting positions.
      std::vector<std::uint32_t> moved;
      for (std::uint32_t v = 0; v < nv; ++v)
        if (moved_vertex(v)) moved.push_back(v);
      st.undone += guard(p, start, moved).size();
      write();
    }
  }
  for (std::size_t v = 0; v < nv; ++v)
    st.moved += p[v].x != start[v].x || p[v].y != start[v].y || p[v].z != start[v].z;
  // err2 holds the errors of the positions p unless moves were undone since.
  st.rms_after = st.undone > 0 ? measure_and_sum(false) : rms_of_err2();
  mesh.normals.clear();
  return st;
}

}  // namespace adamesh
