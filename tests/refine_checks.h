// Checks shared by the refinement tests: conformity (combinatorial and geometric T-junctions),
// semi-regular valences, nesting, and a fixture that builds a base mesh from an input.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "adamesh/input.h"
#include "adamesh/refine.h"
#include "adamesh/simplify.h"
#include "adamesh/surfels.h"
#include "mesh_checks.h"

namespace adamesh::testutil {

struct Fixture {
  Input in;
  SurfelComplex sc;
  BaseMesh base;
  MeshTopo base_topo;
  double h = 0;
};

inline Fixture make_fixture(const std::string& spec, int resolution, double iso = 0,
                            SimplifyOptions so = {}) {
  Fixture f;
  InputOptions io;
  io.resolution = resolution;
  f.in = load_input(spec, io);
  f.sc = build_surfels(*f.in.volume, iso, f.in.inside_sign);
  f.base = simplify(f.sc, f.in.field.get(), so);
  f.base_topo = mesh_topo(f.base.mesh);
  f.h = f.sc.grid.min_spacing();
  return f;
}

/// Edge (min, max) → midpoint vertex of every split of the hierarchy.
inline std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoint_map(
    const Hierarchy& h) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> m;
  for (const auto& e : split_edges(h)) m[{std::min(e[0], e[1]), std::max(e[0], e[1])}] = e[2];
  return m;
}

/// Vertices lying within tol of the interior of an edge they are not an end of.
inline long geometric_t_junctions(const Mesh& m, double tol) {
  const Box b = m.bounds();
  double mean_edge = 0;
  for (std::size_t f = 0; f < m.num_triangles(); ++f)
    mean_edge += distance(m.vertex(m.triangles[3 * f]), m.vertex(m.triangles[3 * f + 1]));
  mean_edge /= std::max<std::size_t>(1, m.num_triangles());
  const double cell = std::max(mean_edge, 1e-12);
  auto key = [&](long i, long j, long k) { return (i * 73856093L) ^ (j * 19349663L) ^ (k * 83492791L); };
  auto idx = [&](double x, double lo) { return static_cast<long>(std::floor((x - lo) / cell)); };
  std::unordered_multimap<long, std::uint32_t> grid;
  for (std::uint32_t v = 0; v < m.num_vertices(); ++v) {
    const Vec3 p = m.vertex(v);
    grid.insert({key(idx(p.x, b.lo.x), idx(p.y, b.lo.y), idx(p.z, b.lo.z)), v});
  }
  long bad = 0;
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> seen;
  for (std::size_t f = 0; f < m.num_triangles(); ++f)
    for (int e = 0; e < 3; ++e) {
      std::uint32_t a = m.triangles[3 * f + e], c = m.triangles[3 * f + (e + 1) % 3];
      if (a > c) std::swap(a, c);
      if (seen[{a, c}]++) continue;
      const Vec3 pa = m.vertex(a), pc = m.vertex(c), d = pc - pa;
      const Vec3 lo = vmin(pa, pc) - Vec3{tol, tol, tol}, hi = vmax(pa, pc) + Vec3{tol, tol, tol};
      for (long i = idx(lo.x, b.lo.x); i <= idx(hi.x, b.lo.x); ++i)
        for (long j = idx(lo.y, b.lo.y); j <= idx(hi.y, b.lo.y); ++j)
          for (long k = idx(lo.z, b.lo.z); k <= idx(hi.z, b.lo.z); ++k) {
            const auto range = grid.equal_range(key(i, j, k));
            for (auto it = range.first; it != range.second; ++it) {
              const std::uint32_t v = it->second;
              if (v == a || v == c) continue;
              const Vec3 p = m.vertex(v);
              const double t = dot(p - pa, d) / norm2(d);
              if (t <= 0 || t >= 1) continue;
              if (distance(p, pa + t * d) < tol) ++bad;
            }
          }
    }
  return bad;
}

/// Topology equal to the base mesh's, manifold, oriented, no T-junction (both kinds).
inline void expect_valid_cut(const CutMesh& cut, const Hierarchy& h, const MeshTopo& ref,
                             const std::string& label) {
  SCOPED_TRACE(label);
  const MeshTopo t = mesh_topo(cut.mesh);
  EXPECT_EQ(t.chi, ref.chi);
  EXPECT_EQ(t.components, ref.components);
  EXPECT_EQ(t.boundary_loops, ref.boundary_loops);
  EXPECT_EQ(t.nonmanifold_edges, 0);
  EXPECT_EQ(t.nonmanifold_vertices, 0);
  EXPECT_EQ(t.duplicates, 0);
  EXPECT_EQ(t.degenerate, 0);
  EXPECT_TRUE(t.oriented);
  EXPECT_EQ(t.vertices, static_cast<long>(cut.mesh.num_vertices()));  // no unused vertex
  // Combinatorial conformity: an edge of the cut that some split bisects must not have that
  // split's vertex in the cut.
  const auto mid = midpoint_map(h);
  std::vector<std::uint8_t> used(h.num_vertices(), 0);
  for (const auto v : cut.vertex_id) used[v] = 1;
  long hanging = 0;
  for (std::size_t f = 0; f < cut.mesh.num_triangles(); ++f)
    for (int e = 0; e < 3; ++e) {
      std::uint32_t a = cut.vertex_id[cut.mesh.triangles[3 * f + e]];
      std::uint32_t b = cut.vertex_id[cut.mesh.triangles[3 * f + (e + 1) % 3]];
      const auto it = mid.find({std::min(a, b), std::max(a, b)});
      if (it != mid.end() && used[it->second]) ++hanging;
    }
  EXPECT_EQ(hanging, 0);
  EXPECT_EQ(geometric_t_junctions(cut.mesh, 1e-9 * cut.mesh.bounds().diagonal()), 0);
}

/// Valences of the vertices created by refinement: uniform {4, 8} / border {3, 5}; adaptive
/// 4..8 / 3..5.
inline void expect_semi_regular(const CutMesh& cut, std::size_t num_base_vertices, bool uniform,
                                const std::string& label) {
  SCOPED_TRACE(label);
  std::vector<int> valence(cut.mesh.num_vertices(), 0);
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (std::size_t f = 0; f < cut.mesh.num_triangles(); ++f)
    for (int e = 0; e < 3; ++e) {
      std::uint32_t a = cut.mesh.triangles[3 * f + e], b = cut.mesh.triangles[3 * f + (e + 1) % 3];
      if (edges[{std::min(a, b), std::max(a, b)}]++ == 0) ++valence[a], ++valence[b];
    }
  long bad = 0;
  for (std::size_t v = 0; v < valence.size(); ++v) {
    if (cut.vertex_id[v] < num_base_vertices) continue;
    const int k = valence[v];
    const bool ok = cut.vertex_border[v] ? (uniform ? (k == 3 || k == 5) : (k >= 3 && k <= 5))
                                         : (uniform ? (k == 4 || k == 8) : (k >= 4 && k <= 8));
    if (!ok && bad++ < 5) ADD_FAILURE() << "vertex " << cut.vertex_id[v] << " valence " << k
                                        << (cut.vertex_border[v] ? " (border)" : "");
  }
  EXPECT_EQ(bad, 0);
}

/// Nesting: every vertex of `coarse` is a vertex of `fine` with identical coordinates.
inline void expect_nested(const CutMesh& coarse, const CutMesh& fine, const std::string& label) {
  std::size_t k = 0, missing = 0, moved = 0;
  for (std::size_t i = 0; i < coarse.vertex_id.size(); ++i) {
    while (k < fine.vertex_id.size() && fine.vertex_id[k] < coarse.vertex_id[i]) ++k;
    if (k == fine.vertex_id.size() || fine.vertex_id[k] != coarse.vertex_id[i]) {
      ++missing;
      continue;
    }
    for (int c = 0; c < 3; ++c)
      moved += fine.mesh.positions[3 * k + c] != coarse.mesh.positions[3 * i + c];
  }
  EXPECT_EQ(missing, 0u) << label;
  EXPECT_EQ(moved, 0u) << label;
}

/// Median radius ratio and share of triangles with a minimum angle below 20°.
struct ShapeFigures {
  double median_q = 0, pct_below_20 = 0, min_angle = 180;
};
inline ShapeFigures shape_figures(const Mesh& m) {
  std::vector<double> q;
  long below = 0;
  ShapeFigures s;
  for (std::size_t f = 0; f < m.num_triangles(); ++f) {
    const Vec3 a = m.vertex(m.triangles[3 * f]), b = m.vertex(m.triangles[3 * f + 1]),
               c = m.vertex(m.triangles[3 * f + 2]);
    const double la = distance(b, c), lb = distance(a, c), lc = distance(a, b);
    const double area = 0.5 * norm(cross(b - a, c - a)), sp = 0.5 * (la + lb + lc);
    q.push_back(area > 0 ? 8 * area * area / (sp * la * lb * lc) : 0);
    auto angle = [](const Vec3& u, const Vec3& v) {
      return std::acos(std::clamp(dot(u, v) / (norm(u) * norm(v)), -1.0, 1.0)) * 180 / M_PI;
    };
    const double mn = std::min({angle(b - a, c - a), angle(a - b, c - b), angle(a - c, b - c)});
    s.min_angle = std::min(s.min_angle, mn);
    below += mn < 20;
  }
  std::sort(q.begin(), q.end());
  s.median_q = q.empty() ? 0 : q[q.size() / 2];
  s.pct_below_20 = q.empty() ? 0 : 100.0 * below / q.size();
  return s;
}

}  // namespace adamesh::testutil
