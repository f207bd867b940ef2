// Test helpers for the surfel / marching cubes tests: volumes sampled from lambdas, small
// self-contained mesh topology (edge map, boundary loops, components, χ, manifoldness,
// orientation) and a validator of the surfel complex's invariants.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "adamesh/mesh.h"
#include "adamesh/surfels.h"
#include "adamesh/volume.h"

namespace adamesh::testutil {

/// float32 volume with samples f(i, j, k) (index coordinates).
template <class F>
Volume sample_volume(std::array<std::int64_t, 3> dims, F&& f, Grid grid = {}) {
  grid.dims = dims;
  Volume v = allocate_volume(grid, ScalarType::f32, "test");
  float* s = v.samples<float>();
  for (std::int64_t k = 0; k < dims[2]; ++k)
    for (std::int64_t j = 0; j < dims[1]; ++j)
      for (std::int64_t i = 0; i < dims[0]; ++i)
        s[grid.linear_index(i, j, k)] = static_cast<float>(f(double(i), double(j), double(k)));
  return v;
}

/// float32 volume with samples f(world position) on `grid`.
template <class F>
Volume sample_world(const Grid& grid, F&& f) {
  return sample_volume(grid.dims, [&](double i, double j, double k) { return f(grid.to_world({i, j, k})); },
                       grid);
}

inline Grid cube_grid(std::int64_t n, double lo, double hi) {
  Grid g;
  g.dims = {n, n, n};
  const double h = (hi - lo) / static_cast<double>(n - 1);
  g.spacing = {h, h, h};
  g.origin = {lo, lo, lo};
  return g;
}

struct UnionFind {
  std::vector<std::int64_t> p;
  explicit UnionFind(std::size_t n) : p(n) { std::iota(p.begin(), p.end(), 0); }
  std::int64_t find(std::int64_t x) {
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
  }
  void unite(std::int64_t a, std::int64_t b) { p[find(a)] = find(b); }
};

struct MeshTopology {
  std::int64_t vertices = 0;  ///< referenced vertices
  std::int64_t edges = 0, triangles = 0, euler = 0;
  std::int64_t components = 0, boundary_edges = 0, boundary_loops = 0;
  std::int64_t nonmanifold_edges = 0, nonmanifold_vertices = 0;
  std::int64_t degenerate = 0, duplicates = 0;
  std::int64_t misoriented_edges = 0;  ///< interior edges not used once in each direction
};

inline MeshTopology mesh_topology(const Mesh& m) {
  MeshTopology t;
  const std::size_t nv = m.num_vertices(), nt = m.num_triangles();
  t.triangles = static_cast<std::int64_t>(nt);
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::array<int, 2>> edges;  // (min,max) -> fwd/back
  std::set<std::array<std::uint32_t, 3>> tris;
  std::vector<char> used(nv, 0);
  UnionFind uf(nv);
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> link(nv);
  for (std::size_t f = 0; f < nt; ++f) {
    std::array<std::uint32_t, 3> v{m.triangles[3 * f], m.triangles[3 * f + 1], m.triangles[3 * f + 2]};
    const Vec3 a = m.vertex(v[0]), b = m.vertex(v[1]), c = m.vertex(v[2]);
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2] || norm2(cross(b - a, c - a)) == 0) ++t.degenerate;
    auto sorted = v;
    std::sort(sorted.begin(), sorted.end());
    if (!tris.insert(sorted).second) ++t.duplicates;
    for (int k = 0; k < 3; ++k) {
      used[v[k]] = 1;
      const std::uint32_t x = v[k], y = v[(k + 1) % 3];
      auto& e = edges[{std::min(x, y), std::max(x, y)}];
      ++e[x < y ? 0 : 1];
      uf.unite(x, y);
      link[v[k]].push_back({v[(k + 1) % 3], v[(k + 2) % 3]});
    }
  }
  std::map<std::uint32_t, std::vector<std::uint32_t>> boundary_adj;
  for (const auto& [key, cnt] : edges) {
    const int n = cnt[0] + cnt[1];
    if (n > 2) ++t.nonmanifold_edges;
    if (n == 2 && (cnt[0] != 1 || cnt[1] != 1)) ++t.misoriented_edges;
    if (n == 1) {
      ++t.boundary_edges;
      boundary_adj[key.first].push_back(key.second);
      boundary_adj[key.second].push_back(key.first);
    }
  }
  t.edges = static_cast<std::int64_t>(edges.size());
  std::set<std::int64_t> roots;
  for (std::size_t v = 0; v < nv; ++v)
    if (used[v]) {
      ++t.vertices;
      roots.insert(uf.find(static_cast<std::int64_t>(v)));
    }
  t.components = static_cast<std::int64_t>(roots.size());
  t.euler = t.vertices - t.edges + t.triangles;
  // Boundary loops: connected components of the boundary edge graph.
  std::set<std::uint32_t> seen;
  for (const auto& [v0, adj] : boundary_adj) {
    if (seen.count(v0)) continue;
    ++t.boundary_loops;
    std::vector<std::uint32_t> stack{v0};
    seen.insert(v0);
    while (!stack.empty()) {
      const auto v = stack.back();
      stack.pop_back();
      for (auto w : boundary_adj[v])
        if (seen.insert(w).second) stack.push_back(w);
    }
  }
  // Vertex links: the opposite edges of the incident triangles must form one cycle or one path.
  for (std::size_t v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    std::map<std::uint32_t, int> deg;
    UnionFind luf(0);
    std::map<std::uint32_t, std::int64_t> idx;
    for (auto [a, b] : link[v]) {
      for (auto x : {a, b})
        if (!idx.count(x)) idx[x] = static_cast<std::int64_t>(idx.size());
    }
    luf.p.resize(idx.size());
    std::iota(luf.p.begin(), luf.p.end(), 0);
    for (auto [a, b] : link[v]) {
      ++deg[a];
      ++deg[b];
      luf.unite(idx[a], idx[b]);
    }
    std::set<std::int64_t> parts;
    bool ok = true;
    for (auto& [x, d] : deg) {
      parts.insert(luf.find(idx[x]));
      if (d > 2) ok = false;
    }
    if (!ok || parts.size() != 1) ++t.nonmanifold_vertices;
  }
  return t;
}

/// Checks every documented invariant of the complex; returns the number of violations (and
/// reports the first few through gtest).
inline int validate_complex(const SurfelComplex& cx) {
  int errors = 0;
  auto bad = [&](const std::string& what) {
    if (errors++ < 5) ADD_FAILURE() << what;
  };
  const std::size_t nn = cx.num_nodes(), ns = cx.num_surfels();
  if (cx.node_pos.size() != 3 * nn || cx.node_fan.size() != nn || cx.node_turn.size() != nn)
    bad("node array sizes");
  for (const auto t : cx.node_turn)
    if (t != 1 && t != 3) {
      bad("node_turn not 1 or 3");
      break;
    }
  if (cx.surfel_offset.size() != ns + 1 || cx.cvertex.size() != 3 * ns) bad("surfel array sizes");
  if (cx.surfel_offset.back() != cx.surfel_nodes.size()) bad("CSR sizes");
  for (std::size_t n = 1; n < nn; ++n)
    if (cx.node_key[n - 1] >= cx.node_key[n]) bad("node keys not increasing");
  for (std::size_t s = 1; s < ns; ++s)
    if (cx.surfel_voxel[s - 1] > cx.surfel_voxel[s]) bad("surfels not in voxel order");
  const auto& d = cx.grid.dims;
  // Surfels containing each node.
  std::vector<std::vector<std::int32_t>> users(nn);
  for (std::size_t s = 0; s < ns; ++s) {
    const auto nodes = cx.nodes_of(s);
    if (nodes.size() < 3 || nodes.size() > 12) bad("surfel size " + std::to_string(nodes.size()));
    std::set<std::uint32_t> uniq(nodes.begin(), nodes.end());
    if (uniq.size() != nodes.size()) bad("repeated node in surfel");
    Vec3 avg{};
    for (auto n : nodes) {
      users[n].push_back(static_cast<std::int32_t>(s));
      avg += cx.node_position(n);
    }
    avg /= static_cast<double>(nodes.size());
    if (distance(avg, cx.cvertex_position(s)) > 1e-4 * (1 + norm(avg))) bad("c-vertex");
    // Each node's edge must be an edge of the surfel's voxel.
    const auto v = static_cast<std::int64_t>(cx.surfel_voxel[s]);
    const std::int64_t vi = v % d[0], vj = (v / d[0]) % d[1], vk = v / (d[0] * d[1]);
    for (auto n : nodes) {
      const std::int64_t lin = static_cast<std::int64_t>(cx.node_key[n] / 3);
      const int axis = static_cast<int>(cx.node_key[n] % 3);
      const std::int64_t p[3] = {lin % d[0], (lin / d[0]) % d[1], lin / (d[0] * d[1])};
      const std::int64_t q[3] = {vi, vj, vk};
      for (int a = 0; a < 3; ++a) {
        const std::int64_t o = p[a] - q[a];
        if (o < 0 || o > (a == axis ? 0 : 1)) bad("node edge not on surfel voxel");
      }
    }
  }
  // Fans: exactly the surfels containing the node, in the documented quadrant slots.
  for (std::size_t n = 0; n < nn; ++n) {
    std::vector<std::int32_t> fan;
    const std::int64_t lin = static_cast<std::int64_t>(cx.node_key[n] / 3);
    const int axis = static_cast<int>(cx.node_key[n] % 3);
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    const std::int64_t p[3] = {lin % d[0], (lin / d[0]) % d[1], lin / (d[0] * d[1])};
    static const int du[4] = {-1, 0, 0, -1}, dv[4] = {-1, -1, 0, 0};
    for (int q = 0; q < 4; ++q) {
      std::int64_t c[3] = {p[0], p[1], p[2]};
      c[u] += du[q];
      c[w] += dv[q];
      const bool exists = c[u] >= 0 && c[u] <= d[u] - 2 && c[w] >= 0 && c[w] <= d[w] - 2;
      const std::int32_t s = cx.node_fan[n][q];
      if (exists != (s >= 0)) bad("fan slot existence, node " + std::to_string(n));
      if (s >= 0) {
        fan.push_back(s);
        const std::uint64_t vox =
            static_cast<std::uint64_t>(c[0] + d[0] * (c[1] + d[1] * c[2]));
        if (cx.surfel_voxel[s] != vox) bad("fan slot holds a surfel of another voxel");
      }
    }
    std::sort(fan.begin(), fan.end());
    auto u2 = users[n];
    std::sort(u2.begin(), u2.end());
    if (fan != u2) bad("fan != surfels containing node " + std::to_string(n));
  }
  // Opposites: symmetric, reversed traversal, -1 exactly on the border.
  for (std::size_t s = 0; s < ns; ++s) {
    const auto nodes = cx.nodes_of(s);
    const auto opp = cx.opposites_of(s);
    for (std::size_t k = 0; k < nodes.size(); ++k) {
      const std::uint32_t a = nodes[k], b = nodes[(k + 1) % nodes.size()];
      const std::int32_t t = opp[k];
      if (t < 0) {
        for (const auto f : cx.node_fan[a])
          if (f >= 0 && f != static_cast<std::int32_t>(s))
            for (const auto h : cx.node_fan[b])
              if (h == f) bad("border segment whose nodes share another surfel");
        // Border segment: both nodes on one boundary face of the grid.
        bool on_face = false;
        for (int ax = 0; ax < 3; ++ax) {
          std::int64_t c[2];
          bool ok = true;
          for (int e = 0; e < 2; ++e) {
            const std::uint64_t key = cx.node_key[e == 0 ? a : b];
            const std::int64_t lin = static_cast<std::int64_t>(key / 3);
            const std::int64_t pc[3] = {lin % d[0], (lin / d[0]) % d[1], lin / (d[0] * d[1])};
            c[e] = pc[ax];
            if (static_cast<int>(key % 3) == ax) ok = false;
          }
          if (ok && c[0] == c[1] && (c[0] == 0 || c[0] == d[ax] - 1)) on_face = true;
        }
        if (!on_face) bad("border segment not on a boundary face");
        continue;
      }
      // Independently of node_turn: the surfel across the segment is the one fan member other
      // than s that both end nodes' fans hold.
      std::int32_t both = -1;
      for (const auto f : cx.node_fan[a])
        if (f >= 0 && f != static_cast<std::int32_t>(s))
          for (const auto h : cx.node_fan[b]) both = h == f ? f : both;
      if (both != t) bad("opposite differs from the common fan member");
      const auto tn = cx.nodes_of(t);
      const auto to = cx.opposites_of(t);
      bool found = false;
      for (std::size_t m = 0; m < tn.size(); ++m)
        if (tn[m] == b && tn[(m + 1) % tn.size()] == a && to[m] == static_cast<std::int32_t>(s))
          found = true;
      if (!found) bad("opposite not symmetric / not reversed");
    }
  }
  return errors;
}

/// Newell normal of a surfel polygon.
inline Vec3 newell_normal(const SurfelComplex& cx, std::size_t s) {
  const auto nodes = cx.nodes_of(s);
  Vec3 n{};
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const Vec3 a = cx.node_position(nodes[k]), b = cx.node_position(nodes[(k + 1) % nodes.size()]);
    n.x += (a.y - b.y) * (a.z + b.z);
    n.y += (a.z - b.z) * (a.x + b.x);
    n.z += (a.x - b.x) * (a.y + b.y);
  }
  return n;
}

}  // namespace adamesh::testutil
