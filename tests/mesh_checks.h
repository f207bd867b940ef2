// Independent topology oracle for tests: Euler characteristic, components, boundary loops,
// manifoldness and orientation of an index mesh, computed the simple way.
#pragma once

#include <algorithm>
#include <array>
#include <functional>
#include <cstdint>
#include <map>
#include <numeric>
#include <set>
#include <vector>

#include "adamesh/mesh.h"

namespace adamesh::testutil {

struct MeshTopo {
  long vertices = 0, edges = 0, triangles = 0, chi = 0;
  long components = 0, boundary_loops = 0;
  long nonmanifold_edges = 0, nonmanifold_vertices = 0;
  long degenerate = 0, duplicates = 0;
  bool oriented = true;
};

inline MeshTopo mesh_topo(const Mesh& m) {
  MeshTopo t;
  const std::size_t nv = m.num_vertices(), nf = m.num_triangles();
  t.triangles = static_cast<long>(nf);
  std::vector<std::uint8_t> used(nv, 0);
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::pair<std::uint32_t, bool>>> edges;
  std::set<std::array<std::uint32_t, 3>> seen;
  std::vector<std::uint32_t> parent(nv);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t f = 0; f < nf; ++f) {
    const std::uint32_t* v = &m.triangles[3 * f];
    std::array<std::uint32_t, 3> key{v[0], v[1], v[2]};
    std::sort(key.begin(), key.end());
    if (key[0] == key[1] || key[1] == key[2]) {
      ++t.degenerate;
      continue;
    }
    const Vec3 a = m.vertex(v[0]), b = m.vertex(v[1]), c = m.vertex(v[2]);
    if (norm(cross(b - a, c - a)) == 0.0) ++t.degenerate;
    if (!seen.insert(key).second) ++t.duplicates;
    for (int i = 0; i < 3; ++i) {
      used[v[i]] = 1;
      const std::uint32_t p = v[i], q = v[(i + 1) % 3];
      edges[{std::min(p, q), std::max(p, q)}].push_back({static_cast<std::uint32_t>(f), p < q});
      parent[find(p)] = find(q);
    }
  }
  t.vertices = std::count(used.begin(), used.end(), 1);
  t.edges = static_cast<long>(edges.size());
  t.chi = t.vertices - t.edges + t.triangles;
  std::set<std::uint32_t> roots;
  for (std::uint32_t v = 0; v < nv; ++v)
    if (used[v]) roots.insert(find(v));
  t.components = static_cast<long>(roots.size());
  std::map<std::uint32_t, std::vector<std::uint32_t>> bnext;
  for (const auto& [e, fs] : edges) {
    if (fs.size() > 2) ++t.nonmanifold_edges;
    if (fs.size() == 2 && fs[0].second == fs[1].second) t.oriented = false;
    if (fs.size() == 1) {
      // boundary half-edge in the triangle's direction
      const bool forward = fs[0].second;
      const std::uint32_t a = forward ? e.first : e.second, b = forward ? e.second : e.first;
      bnext[a].push_back(b);
    }
  }
  // Boundary loops (count cycles of boundary half-edges).
  std::set<std::pair<std::uint32_t, std::uint32_t>> used_he;
  for (const auto& [a, outs] : bnext) {
    if (outs.size() > 1) ++t.nonmanifold_vertices;
    for (auto b0 : outs) {
      if (used_he.count({a, b0})) continue;
      std::uint32_t x = a, y = b0;
      while (!used_he.count({x, y})) {
        used_he.insert({x, y});
        auto it = bnext.find(y);
        if (it == bnext.end()) break;
        std::uint32_t z = it->second[0];
        for (auto c : it->second)
          if (!used_he.count({y, c})) z = c;
        x = y;
        y = z;
      }
      ++t.boundary_loops;
    }
  }
  // Vertex manifoldness: triangles around each vertex form one fan.
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> link(nv);
  for (std::size_t f = 0; f < nf; ++f) {
    const std::uint32_t* v = &m.triangles[3 * f];
    for (int i = 0; i < 3; ++i) link[v[i]].push_back({v[(i + 1) % 3], v[(i + 2) % 3]});
  }
  for (std::uint32_t v = 0; v < nv; ++v) {
    if (link[v].empty()) continue;
    std::map<std::uint32_t, std::uint32_t> p;
    for (auto& [a, b] : link[v]) p[a] = a, p[b] = b;
    std::function<std::uint32_t(std::uint32_t)> f = [&](std::uint32_t x) {
      return p[x] == x ? x : p[x] = f(p[x]);
    };
    for (auto& [a, b] : link[v]) p[f(a)] = f(b);
    std::set<std::uint32_t> r;
    for (auto& [k, _] : p) r.insert(f(k));
    if (r.size() != 1) ++t.nonmanifold_vertices;
  }
  return t;
}

}  // namespace adamesh::testutil
