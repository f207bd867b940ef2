// Topology report (docs/METRICS.md "Topology").
//
// Passes, on the proper triangles (three distinct indices):
//   1. adjacency (metrics/adjacency.h): corners by vertex, sides by undirected edge;
//   2. per edge: valence 1 = boundary, > 2 = non-manifold, 2 with both sides running the same
//      way = inconsistently oriented;
//   3. per vertex: the fans around it (triangles joined through its two-triangle edges), more
//      than one = non-manifold vertex; the *free* sides at the vertex (sides of edges whose
//      valence is not 2) are paired with the other free side at the end of the same fan. This
//      pairing is the boundary of the surface cut along non-manifold edges and split at
//      non-manifold vertices, so tracing it gives boundary cycles even on non-manifold input.
//      Duplicate triangles are counted here too, at their smallest vertex;
//   4. components: lock-free union-find linking the larger root under the smaller, so each root
//      is its component's smallest vertex; components are numbered in that order;
//   5. orientability, only for components with inconsistent edges: union-find with parity;
//   6. boundary cycles traced sequentially over the free sides.
// Every pass is either integer-valued or written to fixed slots: the report does not depend on
// the thread count.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <numeric>

#include "adamesh/metrics.h"
#include "metrics/adjacency.h"
#include "metrics/mesh_check.h"
#include "metrics/parallel.h"

namespace adamesh {

namespace {

using detail::kNone;

/// Lock-free union-find: roots are always the smallest index of their set.
class MinUnionFind {
 public:
  explicit MinUnionFind(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), 0u);
  }
  std::uint32_t find(std::uint32_t x) {
    while (true) {
      const std::uint32_t p = load(x);
      if (p == x) return x;
      const std::uint32_t g = load(p);
      if (g != p) std::atomic_ref<std::uint32_t>(parent_[x]).store(g, std::memory_order_relaxed);
      x = g;
    }
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    while (true) {
      a = find(a);
      b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);  // link the larger root a under b
      std::uint32_t expected = a;
      if (std::atomic_ref<std::uint32_t>(parent_[a]).compare_exchange_strong(expected, b))
        return;
    }
  }

 private:
  std::uint32_t load(std::uint32_t x) {
    return std::atomic_ref<std::uint32_t>(parent_[x]).load(std::memory_order_relaxed);
  }
  detail::RawVector<std::uint32_t> parent_;
};

/// Sequential union-find with parity (odd = the two triangles need opposite flips).
class ParityUnionFind {
 public:
  explicit ParityUnionFind(std::size_t n) : parent_(n), parity_(n, 0) {
    std::iota(parent_.begin(), parent_.end(), 0u);
  }
  /// Root of x; `par` receives the parity of x relative to the root.
  std::uint32_t find(std::uint32_t x, std::uint8_t& par) {
    par = 0;
    std::uint32_t r = x;
    while (parent_[r] != r) {
      par ^= parity_[r];
      r = parent_[r];
    }
    // Compress: point x's path at the root with accumulated parities.
    std::uint8_t acc = par;
    while (parent_[x] != r && parent_[x] != x) {
      const std::uint32_t next = parent_[x];
      const std::uint8_t px = parity_[x];
      parent_[x] = r;
      parity_[x] = acc;
      acc ^= px;
      x = next;
    }
    return r;
  }
  /// Requires parity(a) ^ parity(b) == rel; returns false on a contradiction.
  bool relate(std::uint32_t a, std::uint32_t b, std::uint8_t rel) {
    std::uint8_t pa, pb;
    const std::uint32_t ra = find(a, pa), rb = find(b, pb);
    if (ra == rb) return (pa ^ pb) == rel;
    parent_[ra] = rb;
    parity_[ra] = pa ^ pb ^ rel;
    return true;
  }

 private:
  std::vector<std::uint32_t> parent_;
  std::vector<std::uint8_t> parity_;
};

struct VertexCounts {
  std::int64_t nonmanifold = 0, duplicates = 0, referenced = 0;
};

}  // namespace

TopologyReport topology(const Mesh& mesh, const ExecutionContext& context) {
  detail::check_mesh(mesh);
  return detail::with_threads(context, [&] {
    const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();
    const std::uint32_t* tri = mesh.triangles.data();
    const detail::Adjacency adj = detail::build_adjacency(mesh);
    const std::size_t ne = adj.num_edges();
    TopologyReport r;
    r.triangles = static_cast<std::int64_t>(nt);

    // Collapsed and zero-area triangles.
    struct TriCounts {
      std::int64_t collapsed = 0, degenerate = 0;
    };
    const TriCounts tc = detail::chunked_reduce(
        nt, TriCounts{},
        [&](std::size_t b, std::size_t e) {
          TriCounts c;
          for (std::size_t t = b; t < e; ++t) {
            if (!adj.proper[t]) {
              ++c.collapsed;
              ++c.degenerate;
              continue;
            }
            const Vec3 p = mesh.vertex(tri[3 * t]);
            if (norm2(cross(mesh.vertex(tri[3 * t + 1]) - p, mesh.vertex(tri[3 * t + 2]) - p)) == 0)
              ++c.degenerate;
          }
          return c;
        },
        [](TriCounts a, const TriCounts& b) {
          a.collapsed += b.collapsed;
          a.degenerate += b.degenerate;
          return a;
        });
    r.collapsed_triangles = tc.collapsed;
    r.degenerate_triangles = tc.degenerate;

    // Edges.
    struct EdgeCounts {
      std::int64_t boundary = 0, nonmanifold = 0, inconsistent = 0;
    };
    const EdgeCounts ec = detail::chunked_reduce(
        ne, EdgeCounts{},
        [&](std::size_t b, std::size_t e) {
          EdgeCounts c;
          for (std::size_t i = b; i < e; ++i) {
            const std::uint32_t val = adj.edge_valence(i);
            if (val == 1) ++c.boundary;
            else if (val > 2) ++c.nonmanifold;
            else if (tri[adj.edge_sides[adj.edge_offset[i]]] == tri[adj.edge_sides[adj.edge_offset[i] + 1]])
              ++c.inconsistent;  // both sides start at the same vertex
          }
          return c;
        },
        [](EdgeCounts a, const EdgeCounts& b) {
          a.boundary += b.boundary;
          a.nonmanifold += b.nonmanifold;
          a.inconsistent += b.inconsistent;
          return a;
        });
    r.edges = static_cast<std::int64_t>(ne);
    r.boundary_edges = ec.boundary;
    r.nonmanifold_edges = ec.nonmanifold;
    r.inconsistent_edges = ec.inconsistent;
    r.oriented = ec.inconsistent == 0;

    // Free sides (sides of edges whose valence is not 2), numbered edge by edge: free_edges
    // lists those edges in increasing order, free_base[k] the number of free sides before
    // free_edges[k].
    std::vector<std::uint32_t> free_edges, free_base;
    std::uint32_t num_free = 0;
    for (std::size_t e = 0; e < ne; ++e)
      if (adj.edge_valence(e) != 2) {
        free_edges.push_back(static_cast<std::uint32_t>(e));
        free_base.push_back(num_free);
        num_free += adj.edge_valence(e);
      }
    auto free_index = [&](std::uint32_t s) {
      const std::uint32_t e = adj.side_edge[s];
      const auto k = std::lower_bound(free_edges.begin(), free_edges.end(), e) - free_edges.begin();
      // An edge's sides are in increasing id: a binary search, not a scan (a triangle repeated
      // n times gives edges of valence n, and every side asks once: n² with a scan).
      const std::uint32_t* first = adj.edge_sides.data() + adj.edge_offset[e];
      const std::uint32_t* at = std::lower_bound(first, first + adj.edge_valence(e), s);
      return free_base[static_cast<std::size_t>(k)] + static_cast<std::uint32_t>(at - first);
    };
    // partner[2f + end] = 2g + end_g: at the vertex where free side f has its end `end`
    // (0 = start, 1 = end), the boundary continues along free side g.
    std::vector<std::uint32_t> partner(2 * static_cast<std::size_t>(num_free), kNone);
    std::vector<std::uint8_t> nonmanifold_vertex(nv, 0);

    const VertexCounts vc = detail::chunked_reduce(
        nv, VertexCounts{},
        [&](std::size_t b, std::size_t e) {
          VertexCounts c;
          std::vector<std::uint32_t> parent;
          std::vector<std::array<std::uint32_t, 3>> ends;  // (fan root, side, end)
          std::vector<std::pair<std::uint32_t, std::uint32_t>> keys;
          for (std::size_t v = b; v < e; ++v) {
            const std::uint32_t* L = adj.vertex_corners.data() + adj.corner_offset[v];
            const std::uint32_t n = adj.corners_of(v);
            if (n == 0) continue;
            ++c.referenced;
            parent.resize(n);
            std::iota(parent.begin(), parent.end(), 0u);
            auto root = [&](std::uint32_t x) {
              while (parent[x] != x) x = parent[x] = parent[parent[x]];
              return x;
            };
            auto local = [&](std::uint32_t t) {  // position of triangle t in L
              return static_cast<std::uint32_t>(std::lower_bound(L, L + n, 3 * t) - L);
            };
            for (std::uint32_t i = 0; i < n; ++i) {
              const std::uint32_t cn = L[i], base = cn - cn % 3;
              for (const std::uint32_t s : {cn, base + (cn % 3 + 2) % 3}) {
                const std::uint32_t ed = adj.side_edge[s];
                if (adj.edge_valence(ed) != 2) continue;
                const std::uint32_t* es = adj.edge_sides.data() + adj.edge_offset[ed];
                const std::uint32_t other = es[0] == s ? es[1] : es[0];
                const std::uint32_t a = root(i), o = root(local(other / 3));
                if (a != o) parent[std::max(a, o)] = std::min(a, o);
              }
            }
            std::uint32_t fans = 0;
            ends.clear();
            for (std::uint32_t i = 0; i < n; ++i) {
              const std::uint32_t ri = root(i);
              fans += ri == i;
              const std::uint32_t cn = L[i], base = cn - cn % 3;
              const std::uint32_t out = cn, in = base + (cn % 3 + 2) % 3;
              if (adj.edge_valence(adj.side_edge[out]) != 2) ends.push_back({ri, out, 0});
              if (adj.edge_valence(adj.side_edge[in]) != 2) ends.push_back({ri, in, 1});
            }
            if (fans > 1) {
              ++c.nonmanifold;
              nonmanifold_vertex[v] = 1;
            }
            std::sort(ends.begin(), ends.end());
            for (std::size_t i = 0; i + 1 < ends.size(); ++i) {
              if (ends[i][0] != ends[i + 1][0]) continue;
              const std::uint32_t x = 2 * free_index(ends[i][1]) + ends[i][2];
              const std::uint32_t y = 2 * free_index(ends[i + 1][1]) + ends[i + 1][2];
              partner[x] = y;
              partner[y] = x;
              ++i;
            }
            // Duplicates among the triangles whose smallest vertex is v.
            keys.clear();
            for (std::uint32_t i = 0; i < n; ++i) {
              const std::uint32_t* t = tri + (L[i] - L[i] % 3);
              const std::uint32_t lo = std::min({t[0], t[1], t[2]});
              if (lo != v) continue;
              const std::uint32_t hi = std::max({t[0], t[1], t[2]});
              keys.emplace_back(t[0] + t[1] + t[2] - lo - hi, hi);
            }
            std::sort(keys.begin(), keys.end());
            for (std::size_t i = 1; i < keys.size(); ++i) c.duplicates += keys[i] == keys[i - 1];
          }
          return c;
        },
        [](VertexCounts a, const VertexCounts& b) {
          a.nonmanifold += b.nonmanifold;
          a.duplicates += b.duplicates;
          a.referenced += b.referenced;
          return a;
        },
        1024);
    r.vertices = vc.referenced;
    r.unreferenced_vertices = static_cast<std::int64_t>(nv) - vc.referenced;
    r.nonmanifold_vertices = vc.nonmanifold;
    r.duplicate_triangles = vc.duplicates;
    r.euler = r.vertices - r.edges + (r.triangles - r.collapsed_triangles);
    r.closed = nt > static_cast<std::size_t>(r.collapsed_triangles) && ec.boundary == 0 &&
               ec.nonmanifold == 0;

    // Components.
    MinUnionFind uf(nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 1 << 14), [&](const auto& rg) {
      for (std::size_t t = rg.begin(); t != rg.end(); ++t)
        if (adj.proper[t]) {
          uf.unite(tri[3 * t], tri[3 * t + 1]);
          uf.unite(tri[3 * t], tri[3 * t + 2]);
        }
    });
    std::vector<std::uint32_t> comp(nv, kNone);
    std::uint32_t nc = 0;
    for (std::size_t v = 0; v < nv; ++v)
      if (adj.corners_of(v) > 0) {
        const std::uint32_t root = uf.find(static_cast<std::uint32_t>(v));
        comp[v] = root == v ? nc++ : comp[root];  // roots are the smallest vertex: seen first
      }
    r.components = nc;
    auto& cl = r.component_list;
    cl.assign(nc, ComponentTopology{});
    for (auto& c : cl) c.closed = c.manifold = c.orientable = c.oriented = true;
    for (std::size_t v = 0; v < nv; ++v)
      if (comp[v] != kNone) {
        ++cl[comp[v]].vertices;
        if (nonmanifold_vertex[v]) cl[comp[v]].manifold = false;
      }
    for (std::size_t t = 0; t < nt; ++t)
      if (adj.proper[t]) ++cl[comp[tri[3 * t]]].triangles;
    std::vector<std::uint8_t> has_inconsistent(nc, 0);
    for (std::size_t e = 0; e < ne; ++e) {
      const std::uint32_t* es = adj.edge_sides.data() + adj.edge_offset[e];
      auto& c = cl[comp[tri[es[0]]]];
      ++c.edges;
      const std::uint32_t val = adj.edge_valence(e);
      if (val != 2) c.closed = false;
      if (val > 2) c.manifold = false;
      if (val == 2 && tri[es[0]] == tri[es[1]]) {
        c.oriented = false;
        has_inconsistent[comp[tri[es[0]]]] = 1;
      }
    }
    // Orientability where the given orientation is inconsistent.
    if (ec.inconsistent > 0) {
      ParityUnionFind pf(nt);
      for (std::size_t e = 0; e < ne; ++e) {
        if (adj.edge_valence(e) != 2) continue;
        const std::uint32_t* es = adj.edge_sides.data() + adj.edge_offset[e];
        const std::uint32_t c = comp[tri[es[0]]];
        if (!has_inconsistent[c] || !cl[c].orientable) continue;
        const std::uint8_t same_way = tri[es[0]] == tri[es[1]];
        if (!pf.relate(es[0] / 3, es[1] / 3, same_way)) cl[c].orientable = false;
      }
    }

    // Boundary cycles.
    std::vector<std::uint8_t> visited(num_free, 0);
    std::vector<std::uint32_t> free_side(num_free);
    for (std::size_t k = 0; k < free_edges.size(); ++k)
      for (std::uint32_t i = 0; i < adj.edge_valence(free_edges[k]); ++i)
        free_side[free_base[k] + i] = adj.edge_sides[adj.edge_offset[free_edges[k]] + i];
    for (std::uint32_t f0 = 0; f0 < num_free; ++f0) {
      if (visited[f0]) continue;
      bool has_boundary_edge = false;
      std::uint32_t slot = 2 * f0 + 1;  // leave f0 through its end vertex
      for (std::size_t guard = 0; guard <= 2 * std::size_t{num_free}; ++guard) {
        const std::uint32_t f = slot / 2;
        if (visited[f]) break;
        visited[f] = 1;
        if (adj.edge_valence(adj.side_edge[free_side[f]]) == 1) has_boundary_edge = true;
        const std::uint32_t q = partner[slot];
        if (q == kNone) break;  // cannot happen on fans; ends an open chain
        slot = q ^ 1u;           // continue through the partner side's other end
      }
      if (has_boundary_edge) {
        ++r.boundary_loops;
        ++cl[comp[tri[free_side[f0]]]].boundary_loops;
      }
    }

    for (auto& c : cl) {
      c.euler = c.vertices - c.edges + c.triangles;
      if (c.manifold && c.orientable) {  // χ = 2 − 2g − b
        c.genus = (2 - c.euler - c.boundary_loops) / 2;
        r.genus += *c.genus;
      }
    }
    return r;
  });
}

}  // namespace adamesh
