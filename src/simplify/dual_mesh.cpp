// Dual triangulation of the Voronoi covering → base mesh M0 (ALGORITHM.md 2.6).
//
// One vertex per cell, at its centre (border cells: at the midpoint of the border segment of the
// cell's border surfel nearest the centre, so the vertex lies on the volume face); vertices are
// then moved onto the iso-surface by safeguarded Newton steps (border vertices inside their
// face plane). Triangles come from the junction scan (voronoi.cpp). Components whose covering
// could not be repaired are meshed from their surfels: each surfel polygon fanned around its
// c-vertex, which is always a valid triangulation of the complex. Finally every component's
// Euler characteristic and boundary-loop count are checked against the surfel complex; a
// component that disagrees (never expected) also falls back, with a warning.
#include <algorithm>
#include <chrono>
#include <numeric>
#include <unordered_map>

#include "adamesh/simplify.h"
#include "graph/shortest_paths.h"
#include "voronoi.h"

namespace adamesh {

namespace {

struct CompTopo {
  long chi = 0;
  long loops = 0;
  bool manifold = true;
};

/// χ and boundary loops of every component of the surfel complex.
std::vector<CompTopo> complex_topology(const SurfelComplex& sc, const ConnectivityGraph& g) {
  std::vector<CompTopo> t(g.num_components);
  std::vector<long> nodes_c(g.num_components, 0), faces_c(g.num_components, 0),
      half_c(g.num_components, 0);
  for (std::size_t n = 0; n < sc.num_nodes(); ++n)
    for (auto f : sc.node_fan[n])
      if (f >= 0) {
        ++nodes_c[g.component[f]];
        break;
      }
  std::unordered_map<std::uint32_t, std::uint32_t> border_next;
  for (std::uint32_t s = 0; s < sc.num_surfels(); ++s) {
    ++faces_c[g.component[s]];
    const auto nodes = sc.nodes_of(s);
    const auto opp = sc.opposites_of(s);
    for (std::size_t e = 0; e < nodes.size(); ++e) {
      half_c[g.component[s]] += opp[e] < 0 ? 2 : 1;  // border segments have no twin
      if (opp[e] < 0) border_next[nodes[e]] = nodes[(e + 1) % nodes.size()];
    }
  }
  for (std::uint32_t c = 0; c < g.num_components; ++c)
    t[c].chi = nodes_c[c] - half_c[c] / 2 + faces_c[c];
  // Boundary loops: chains of border segments.
  std::unordered_map<std::uint32_t, std::uint8_t> visited;
  for (const auto& [start, next] : border_next) {
    if (visited.count(start)) continue;
    std::uint32_t a = start;
    std::int32_t comp = -1;
    while (!visited.count(a)) {
      visited[a] = 1;
      if (comp < 0)
        for (auto f : sc.node_fan[a])
          if (f >= 0) comp = static_cast<std::int32_t>(g.component[f]);
      auto it = border_next.find(a);
      if (it == border_next.end()) break;
      a = it->second;
    }
    if (comp >= 0) ++t[comp].loops;
  }
  return t;
}

/// χ, boundary loops and manifoldness of every component of a mesh (components given per vertex).
std::vector<CompTopo> mesh_topology(const Mesh& m, const std::vector<std::uint32_t>& comp,
                                             std::size_t num_components) {
  std::vector<CompTopo> t(num_components);
  for (std::size_t v = 0; v < m.num_vertices(); ++v) t[comp[v]].chi += 1;
  // Corners by vertex (CSR): half-edge a → b is corner c of triangle c / 3 at a, b the next
  // corner's vertex. Memory: 4 bytes per half-edge, where a sorted half-edge list needs 8.
  std::vector<std::uint32_t> offset(m.num_vertices() + 1, 0);
  for (auto v : m.triangles) ++offset[v + 1];
  std::partial_sum(offset.begin(), offset.end(), offset.begin());
  std::vector<std::uint32_t> corner(m.triangles.size());
  {
    std::vector<std::uint32_t> fill(offset.begin(), offset.end() - 1);
    for (std::size_t i = 0; i < m.triangles.size(); ++i)
      corner[fill[m.triangles[i]]++] = static_cast<std::uint32_t>(i);
  }
  auto head = [&](std::uint32_t c) { return m.triangles[c - c % 3 + (c % 3 + 1) % 3]; };
  auto has_half_edge = [&](std::uint32_t a, std::uint32_t b) {
    for (std::uint32_t i = offset[a]; i < offset[a + 1]; ++i)
      if (head(corner[i]) == b) return true;
    return false;
  };
  for (std::size_t f = 0; f < m.num_triangles(); ++f) t[comp[m.triangles[3 * f]]].chi += 1;
  // Undirected edges and boundary half-edges.
  std::unordered_map<std::uint32_t, std::uint32_t> boundary_next;
  std::vector<std::uint8_t> vertex_boundary_out(m.num_vertices(), 0);
  for (std::uint32_t a = 0; a < m.num_vertices(); ++a)
    for (std::uint32_t i = offset[a]; i < offset[a + 1]; ++i) {
      const std::uint32_t b = head(corner[i]);
      for (std::uint32_t j = offset[a]; j < i; ++j)
        if (head(corner[j]) == b) t[comp[a]].manifold = false;  // repeated directed edge
      if (has_half_edge(b, a)) {
        if (a < b) t[comp[a]].chi -= 1;
      } else {
        t[comp[a]].chi -= 1;
        if (vertex_boundary_out[a]++) t[comp[a]].manifold = false;
        boundary_next[a] = b;
      }
    }
  std::vector<std::uint8_t> seen(m.num_vertices(), 0);
  for (const auto& [start, next] : boundary_next) {
    if (seen[start]) continue;
    std::uint32_t a = start;
    while (!seen[a]) {
      seen[a] = 1;
      auto it = boundary_next.find(a);
      if (it == boundary_next.end()) {
        t[comp[start]].manifold = false;
        break;
      }
      a = it->second;
    }
    ++t[comp[start]].loops;
  }
  // Vertex links: the triangles around each vertex form one fan (one cycle or one path).
  for (std::uint32_t v = 0; v < m.num_vertices(); ++v) {
    const std::uint32_t deg = offset[v + 1] - offset[v];
    if (deg == 0) continue;
    // Walk the fan from one corner via "next" vertices; count the triangles reached.
    std::unordered_map<std::uint32_t, std::uint32_t> next_of;  // link edge b -> c
    for (std::uint32_t i = offset[v]; i < offset[v + 1]; ++i) {
      const std::uint32_t c = corner[i], f = c / 3, k = c % 3;
      next_of[m.triangles[3 * f + (k + 1) % 3]] = m.triangles[3 * f + (k + 2) % 3];
    }
    std::uint32_t start = next_of.begin()->first;
    if (vertex_boundary_out[v]) {  // on the boundary: start where no triangle ends
      std::unordered_map<std::uint32_t, std::uint8_t> is_target;
      for (const auto& [b, c] : next_of) is_target[c] = 1;
      for (const auto& [b, c] : next_of)
        if (!is_target.count(b)) start = b;
    }
    std::uint32_t count = 0, at = start;
    while (count <= deg) {
      auto it = next_of.find(at);
      if (it == next_of.end()) break;
      ++count;
      at = it->second;
      if (at == start) break;
    }
    if (count != deg) t[comp[v]].manifold = false;
  }
  return t;
}

/// Axis a and index value of the volume face a border segment (n0, n1) lies on.
bool border_face(const SurfelComplex& sc, std::uint32_t n0, std::uint32_t n1, int& axis, bool& high) {
  const auto& d = sc.grid.dims;
  auto decode = [&](std::uint32_t n, std::array<std::int64_t, 3>& ijk, int& ax) {
    const std::uint64_t key = sc.node_key[n];
    ax = static_cast<int>(key % 3);
    std::uint64_t lin = key / 3;
    ijk[0] = static_cast<std::int64_t>(lin % d[0]);
    lin /= d[0];
    ijk[1] = static_cast<std::int64_t>(lin % d[1]);
    ijk[2] = static_cast<std::int64_t>(lin / d[1]);
  };
  std::array<std::int64_t, 3> p0, p1;
  int a0, a1;
  decode(n0, p0, a0);
  decode(n1, p1, a1);
  for (int a = 0; a < 3; ++a) {
    if (a == a0 || a == a1 || p0[a] != p1[a]) continue;
    if (p0[a] == 0 || p0[a] == d[a] - 1) {
      axis = a;
      high = p0[a] != 0;
      return true;
    }
  }
  return false;
}

}  // namespace

/// Replaces every flagged cell by one cell per member surfel (each a cone over its polygon).
void split_cells(Covering& cov, const std::vector<std::uint8_t>& split, SimplifyStats& stats) {
  bool any = false;
  for (auto f : split) any |= f != 0;
  if (!any) return;
  for (std::uint32_t v = 0; v < cov.cell.size(); ++v) {
    const auto c = cov.cell[v];
    if (c == Covering::kNoCell || c >= split.size() || !split[c]) continue;
    cov.cell[v] = static_cast<std::uint32_t>(cov.centre.size());
    cov.centre.push_back(v);
    cov.radius.push_back(0.0);
    cov.cone.push_back(1);
    ++stats.cone_cells;
  }
  for (std::size_t c = 0; c < split.size(); ++c) stats.split_cells += split[c];
}

BaseMesh build_base_mesh(const SurfelComplex& sc, const ConnectivityGraph& g,
                         Covering cov, const ScalarField* field,
                         const SimplifyOptions& opt, SimplifyStats stats,
                         const ExecutionContext& ctx) {
  using namespace detail;
  StageTicker tick(ctx, "dual", 1024);
  const auto t0 = std::chrono::steady_clock::now();
  const double h = sc.grid.min_spacing();
  const auto reference = complex_topology(sc, g);
  const Mat3 a = sc.grid.index_to_world_matrix();

  BaseMesh bm;
  if (cov.cone.size() != cov.centre.size()) cov.cone.assign(cov.centre.size(), 0);
  auto fall_back = [&](std::uint32_t comp, const std::string& why) {
    if (cov.fallback[comp]) return;
    cov.fallback[comp] = 1;
    ++stats.fallback_components;
    stats.warnings.push_back("component " + std::to_string(comp) + ": " + why +
                             "; meshed from its surfels");
  };
  for (int attempt = 0; attempt < 8; ++attempt) {
    tick.poll(0);
    bm = BaseMesh{};
    // Cells without the fallback components' surfels (a copy only when there are such).
    bool any_fallback = false;
    for (auto f : cov.fallback) any_fallback |= f != 0;
    std::vector<std::uint32_t> masked;
    if (any_fallback) {
      masked = cov.cell;
      for (std::size_t v = 0; v < masked.size(); ++v)
        if (masked[v] != Covering::kNoCell && cov.fallback[g.component[v]])
          masked[v] = Covering::kNoCell;
    }
    const std::vector<std::uint32_t>& cells = any_fallback ? masked : cov.cell;
    HybridResult hr = hybrid_triangles(sc, cells, cov.centre, cov.cone);
    tick.poll(0.5);
    if (!hr.problem_cells.empty()) {  // escalate: split cells into surfels, then fall back
      std::vector<std::uint8_t> split(cov.centre.size(), 0);
      for (auto c : hr.problem_cells) {
        if (!cov.cone[c]) split[c] = 1;
        else fall_back(g.component[cov.centre[c]], "cells are not disks at the smallest radius");
      }
      split_cells(cov, split, stats);
      continue;
    }
    // Cell vertices.
    const std::size_t ncell = cov.centre.size();
    std::vector<std::uint32_t> vertex_of(ncell + hr.kept_nodes.size(), Covering::kNoCell);
    std::vector<std::uint32_t> border_surfel(ncell, Covering::kNoCell);
    std::vector<double> border_d(ncell, kInf);
    for (std::uint32_t v = 0; v < g.num_vertices(); ++v) {
      const auto c = cells[v];
      if (c == Covering::kNoCell || !g.border[v]) continue;
      const double d = distance(sc.cvertex_position(v), sc.cvertex_position(cov.centre[c]));
      if (d < border_d[c]) {
        border_d[c] = d;
        border_surfel[c] = v;
      }
    }
    std::vector<std::uint8_t> used(ncell, 0);
    for (const auto& t : hr.triangles)
      for (auto x : t)
        if (x < ncell) used[x] = 1;
    {  // size the mesh once (fallback components, rare, may still grow it)
      std::size_t nv = hr.kept_nodes.size();
      for (std::uint32_t c = 0; c < ncell; ++c)
        nv += used[c] && !cov.fallback[g.component[cov.centre[c]]];
      bm.mesh.positions.reserve(3 * nv);
      bm.mesh.triangles.reserve(3 * hr.triangles.size());
      bm.anchor.reserve(nv);
      bm.border.reserve(nv);
      bm.component.reserve(nv);
    }
    for (std::uint32_t c = 0; c < ncell; ++c) {
      tick.tick();  // a projection per cell
      const auto comp = g.component[cov.centre[c]];
      if (cov.fallback[comp] || !used[c]) continue;
      Vec3 p = sc.cvertex_position(cov.centre[c]);
      std::uint32_t anchor = cov.centre[c];
      ProjectOptions po;
      po.max_steps = 8;
      po.tolerance = 1e-4 * h;
      po.max_step = 0.5 * h;
      const bool on_border = border_surfel[c] != Covering::kNoCell && !cov.cone[c];
      const bool project = field && opt.project_vertices && !cov.cone[c];
      if (on_border) {
        anchor = border_surfel[c];
        const auto nodes = sc.nodes_of(anchor);
        const auto opp = sc.opposites_of(anchor);
        for (std::size_t e = 0; e < nodes.size(); ++e) {
          if (opp[e] >= 0) continue;
          const auto n0 = nodes[e], n1 = nodes[(e + 1) % nodes.size()];
          p = 0.5 * (sc.node_position(n0) + sc.node_position(n1));
          int axis;
          bool high;
          if (border_face(sc, n0, n1, axis, high))
            po.plane_normal = cross(a.column((axis + 1) % 3), a.column((axis + 2) % 3));
          break;
        }
      }
      if (project) {
        const ProjectResult r = project_to_iso(*field, sc.iso, p, po);
        if (distance(r.point, p) < 2.0 * h) p = r.point;
      }
      vertex_of[c] = bm.mesh.add_vertex(p);
      bm.anchor.push_back(anchor);
      bm.border.push_back(on_border ? 1 : 0);
      bm.component.push_back(comp);
    }
    // Kept nodes (cone cells' boundaries, unsplittable quads) are vertices too.
    for (std::size_t i = 0; i < hr.kept_nodes.size(); ++i) {
      const std::uint32_t n = hr.kept_nodes[i];
      std::int32_t anchor = -1;
      bool border = false;
      for (auto f : sc.node_fan[n]) {
        if (f < 0) border = true;
        else if (anchor < 0) anchor = f;
      }
      vertex_of[ncell + i] = bm.mesh.add_vertex(sc.node_position(n));
      bm.anchor.push_back(static_cast<std::uint32_t>(anchor));
      bm.border.push_back(border ? 1 : 0);
      bm.component.push_back(g.component[anchor]);
    }
    for (const auto& t : hr.triangles)
      bm.mesh.add_triangle(vertex_of[t[0]], vertex_of[t[1]], vertex_of[t[2]]);
    std::vector<std::array<std::uint32_t, 3>>().swap(hr.triangles);
    // Fallback components: fan every surfel polygon around its c-vertex.
    std::unordered_map<std::uint32_t, std::uint32_t> vertex_of_node;
    for (std::uint32_t s = 0; s < sc.num_surfels(); ++s) {
      const auto comp = g.component[s];
      if (!cov.fallback[comp] || cov.dropped[comp]) continue;
      const auto nodes = sc.nodes_of(s);
      auto node_vertex = [&](std::uint32_t n) {
        auto it = vertex_of_node.find(n);
        if (it != vertex_of_node.end()) return it->second;
        const auto id = bm.mesh.add_vertex(sc.node_position(n));
        std::uint32_t anchor = s;
        bool border = false;
        for (auto f : sc.node_fan[n]) border |= f < 0;
        bm.anchor.push_back(anchor);
        bm.border.push_back(border ? 1 : 0);
        bm.component.push_back(comp);
        vertex_of_node.emplace(n, id);
        return id;
      };
      Vec3 c = sc.cvertex_position(s);
      if (field && opt.project_vertices) {
        ProjectOptions po;
        po.tolerance = 1e-4 * h;
        po.max_step = 0.25 * h;
        const ProjectResult r = project_to_iso(*field, sc.iso, c, po);
        if (distance(r.point, c) < 0.5 * h) c = r.point;
      }
      const auto cv = bm.mesh.add_vertex(c);
      bm.anchor.push_back(s);
      bm.border.push_back(0);
      bm.component.push_back(comp);
      for (std::size_t i = 0; i < nodes.size(); ++i)
        bm.mesh.add_triangle(cv, node_vertex(nodes[i]), node_vertex(nodes[(i + 1) % nodes.size()]));
    }
    // Check every component against the surfel complex; escalate the ones that disagree:
    // first every cell of the component becomes a cone, then the component falls back.
    const auto got = mesh_topology(bm.mesh, bm.component, g.num_components);
    std::vector<std::uint8_t> bad_comp(g.num_components, 0);
    bool redo = false;
    for (std::uint32_t c = 0; c < g.num_components; ++c) {
      if (cov.dropped[c] || cov.fallback[c]) continue;
      if (got[c].chi != reference[c].chi || got[c].loops != reference[c].loops ||
          !got[c].manifold)
        bad_comp[c] = 1;
    }
    std::vector<std::uint8_t> all_cone(g.num_components, 1);
    for (std::uint32_t c = 0; c < ncell; ++c)
      if (!cov.cone[c]) all_cone[g.component[cov.centre[c]]] = 0;
    for (std::uint32_t c = 0; c < g.num_components; ++c) {
      if (!bad_comp[c]) continue;
      redo = true;
      if (all_cone[c]) {
        fall_back(c, "base mesh χ=" + std::to_string(got[c].chi) + " loops=" +
                         std::to_string(got[c].loops) + " differs from the surfels (χ=" +
                         std::to_string(reference[c].chi) + " loops=" +
                         std::to_string(reference[c].loops) + ")");
      }
    }
    std::vector<std::uint8_t> split(ncell, 0);
    for (std::uint32_t cell = 0; cell < ncell; ++cell)
      if (bad_comp[g.component[cov.centre[cell]]] && !cov.cone[cell]) split[cell] = 1;
    // Zero-area triangles (a projected centre landing on a kept node, or collinear with two):
    // split the dual cells involved; their surfels' fans have no such degeneracy.
    std::vector<std::uint32_t> cell_of_vertex(bm.mesh.num_vertices(), Covering::kNoCell);
    for (std::uint32_t c = 0; c < ncell; ++c)
      if (vertex_of[c] != Covering::kNoCell) cell_of_vertex[vertex_of[c]] = c;
    for (std::size_t f = 0; f < bm.mesh.num_triangles(); ++f) {
      const std::uint32_t* t = &bm.mesh.triangles[3 * f];
      const Vec3 p0 = bm.mesh.vertex(t[0]), p1 = bm.mesh.vertex(t[1]), p2 = bm.mesh.vertex(t[2]);
      if (norm2(cross(p1 - p0, p2 - p0)) > 0) continue;
      for (int k = 0; k < 3; ++k) {
        const auto c = t[k] < cell_of_vertex.size() ? cell_of_vertex[t[k]] : Covering::kNoCell;
        if (c != Covering::kNoCell && !cov.cone[c]) {
          split[c] = 1;
          redo = true;
        }
      }
    }
    split_cells(cov, split, stats);
    if (!redo) break;
  }
  stats.time_dual_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  bm.stats = std::move(stats);
  return bm;
}

BaseMesh simplify(const SurfelComplex& complex, const ScalarField* field,
                  const SimplifyOptions& options, const ExecutionContext& context) {
  const ConnectivityGraph g = build_graph(complex);
  SimplifyStats stats;
  const Covering cov = build_covering(complex, g, options, stats, context);
  if (options.validate) stats.validation = validate_covering(complex, g, cov);
  return build_base_mesh(complex, g, cov, field, options, std::move(stats), context);
}

}  // namespace adamesh
