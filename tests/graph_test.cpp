// The connectivity graph (ALGORITHM.md 2.3): CSR rows in link order, compact (16-bit offset) and
// absolute columns, weights, border flags, components — checked against the surfel complex.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "adamesh/graph.h"
#include "adamesh/surfels.h"
#include "graph/shortest_paths.h"
#include "surfel_test_util.h"

using namespace adamesh;
using testutil::sample_volume;

namespace {

/// Neighbours of s from the fans: every other surfel around any of its nodes.
std::set<std::uint32_t> fan_neighbours(const SurfelComplex& sc, std::uint32_t s) {
  std::set<std::uint32_t> out;
  for (const auto n : sc.nodes_of(s))
    for (const auto f : sc.node_fan[n])
      if (f >= 0 && static_cast<std::uint32_t>(f) != s) out.insert(static_cast<std::uint32_t>(f));
  return out;
}

/// Every structural fact of G against the complex; returns the number of components found by
/// an independent flood fill.
std::uint32_t check_graph(const SurfelComplex& sc, const ConnectivityGraph& g) {
  const std::size_t n = sc.num_surfels();
  EXPECT_EQ(g.num_vertices(), n);
  EXPECT_EQ(g.row.size(), n + 1);
  EXPECT_EQ(g.row.back() % 2, 0u);
  std::size_t directed = 0;
  for (std::uint32_t v = 0; v < n; ++v) {
    const auto row = g.neighbours(v);
    directed += row.size();
    std::vector<std::uint32_t> got(row.begin(), row.end());
    EXPECT_EQ(got.size(), row.size());
    for (std::size_t i = 0; i < got.size() && i < row.size(); ++i) {
      EXPECT_EQ(got[i], row[i]);
      EXPECT_EQ(got[i], g.neighbour(v, g.row[v] + i));
    }
    // Each neighbour once, exactly the surfels sharing a node.
    const std::set<std::uint32_t> unique(got.begin(), got.end());
    EXPECT_EQ(unique.size(), got.size()) << "vertex " << v;
    EXPECT_EQ(unique, fan_neighbours(sc, v)) << "vertex " << v;
    // Link order: the row starts with the surfel across the first polygon edge (if any), and
    // every edge neighbour (opposite) appears in polygon-edge order.
    const auto opp = sc.opposites_of(v);
    std::vector<std::uint32_t> edge_order;
    for (const auto o : opp)
      if (o >= 0) edge_order.push_back(static_cast<std::uint32_t>(o));
    std::vector<std::uint32_t> in_row;
    for (const auto u : got)
      if (std::find(edge_order.begin(), edge_order.end(), u) != edge_order.end()) in_row.push_back(u);
    EXPECT_EQ(in_row, edge_order) << "vertex " << v;
    if (opp[0] >= 0 && !got.empty()) {
      EXPECT_EQ(got.front(), static_cast<std::uint32_t>(opp[0]));
    }
    // Border flag = a polygon edge on the volume border; weights = c-vertex distances.
    bool border = false;
    for (const auto o : opp) border |= o < 0;
    EXPECT_EQ(g.border[v] != 0, border);
    for (std::size_t k = g.row[v]; k < g.row[v + 1]; ++k) {
      const std::uint32_t u = g.neighbour(v, k);
      EXPECT_FLOAT_EQ(g.edge_weight(v, k),
                      static_cast<float>(distance(sc.cvertex_position(v), sc.cvertex_position(u))));
      // Symmetric.
      const auto back = g.neighbours(u);
      EXPECT_NE(std::find(back.begin(), back.end(), v), back.end());
    }
  }
  EXPECT_EQ(directed, 2 * g.num_edges());
  // Components: flood fill over the fans, numbered by smallest vertex.
  std::vector<std::uint32_t> comp(n, UINT32_MAX);
  std::uint32_t count = 0;
  for (std::uint32_t s = 0; s < n; ++s) {
    if (comp[s] != UINT32_MAX) continue;
    std::vector<std::uint32_t> stack{s};
    comp[s] = count;
    while (!stack.empty()) {
      const auto x = stack.back();
      stack.pop_back();
      for (const auto y : fan_neighbours(sc, x))
        if (comp[y] == UINT32_MAX) {
          comp[y] = count;
          stack.push_back(y);
        }
    }
    ++count;
  }
  EXPECT_EQ(g.num_components, count);
  EXPECT_EQ(g.component, comp);
  return count;
}

}  // namespace

TEST(Graph, TorusCompactColumns) {
  const Volume v = sample_volume({24, 24, 24}, [](double i, double j, double k) {
    const double x = i - 11.5, y = j - 11.5, z = k - 11.3;
    const double q = std::sqrt(x * x + y * y) - 6.0;
    return std::sqrt(q * q + z * z) - 2.5;
  });
  const SurfelComplex sc = build_surfels(v, 0.0);
  const ConnectivityGraph g = build_graph(sc);
  EXPECT_TRUE(g.col.empty());  // compact: ids of neighbours are close on a small grid
  EXPECT_EQ(g.delta.size(), g.row.back());
  EXPECT_EQ(check_graph(sc, g), 1u);
  for (const auto b : g.border) EXPECT_EQ(b, 0);  // closed surface
}

TEST(Graph, CutSurfaceHasBorderFlags) {
  // A tilted plane through the box: one component, its rim on the volume border.
  const Volume v = sample_volume({12, 10, 9}, [](double i, double j, double k) {
    return 0.3 * i + 0.2 * j - k + 4.1;
  });
  const SurfelComplex sc = build_surfels(v, 0.0);
  const ConnectivityGraph g = build_graph(sc);
  EXPECT_EQ(check_graph(sc, g), 1u);
  EXPECT_GT(std::count(g.border.begin(), g.border.end(), 1), 10);
}

TEST(Graph, WideLayersFallBackToAbsoluteColumns) {
  // A 200 x 200 checkerboard: every voxel of a layer holds surfels, so a neighbour in the next
  // layer is more than 32767 ids away and the columns must be absolute. Same facts hold.
  const Volume v = sample_volume({200, 200, 3}, [](double i, double j, double k) {
    return ((static_cast<int>(i) + static_cast<int>(j) + static_cast<int>(k)) % 2) ? 1.0 : -1.0;
  });
  const SurfelComplex sc = build_surfels(v, 0.0);
  ASSERT_GT(sc.num_surfels(), 70000u);
  const ConnectivityGraph g = build_graph(sc);
  EXPECT_FALSE(g.col.empty());
  EXPECT_TRUE(g.delta.empty());
  check_graph(sc, g);
}

TEST(Graph, ReleasedAdjacencyKeepsVertexData) {
  const Volume v = sample_volume({10, 10, 10}, [](double i, double j, double k) {
    return std::hypot(i - 4.5, j - 4.4, k - 4.6) - 3.2;
  });
  const SurfelComplex sc = build_surfels(v, 0.0);
  ConnectivityGraph g = build_graph(sc);
  const std::size_t n = g.num_vertices();
  const auto comp = g.component;
  g.release_adjacency();
  EXPECT_EQ(g.num_vertices(), n);
  EXPECT_EQ(g.component, comp);
  EXPECT_TRUE(g.row.empty() && g.col.empty() && g.delta.empty());
  EXPECT_EQ(g.num_edges(), 0u);
}

TEST(Graph, SparseWorkspaceSearchesLikeTheDenseOne) {
  // Dijkstra balls and A* paths with the hash-table workspace: same order, distances and
  // predecessors as with the per-vertex arrays, over many searches (table reuse and growth).
  const Volume v = sample_volume({28, 28, 28}, [](double i, double j, double k) {
    return std::sin(0.45 * i) * std::cos(0.4 * j) + std::sin(0.4 * j) * std::cos(0.45 * k) +
           std::sin(0.45 * k) * std::cos(0.4 * i);
  });
  const SurfelComplex sc = build_surfels(v, 0.1);
  const ConnectivityGraph g = build_graph(sc);
  const auto n = static_cast<std::uint32_t>(g.num_vertices());
  ASSERT_GT(n, 5000u);
  detail::PathWorkspace dense(n), sparse = detail::PathWorkspace::sparse();
  std::size_t settled_total = 0;
  for (std::uint32_t src = 0; src < n; src += 97) {
    const double limit = 1.0 + (src % 7) * 2.5;  // radii from 1 to 16 voxels: the table grows
    std::vector<std::pair<std::uint32_t, double>> a, b;
    detail::dijkstra(g, dense, src, limit, [&](std::uint32_t u, double d) {
      a.push_back({u, d});
      return detail::Visit::expand;
    });
    detail::dijkstra(g, sparse, src, limit, [&](std::uint32_t u, double d) {
      b.push_back({u, d});
      return detail::Visit::expand;
    });
    ASSERT_EQ(a, b) << "source " << src;
    for (const auto& [u, d] : a) {
      EXPECT_TRUE(sparse.settled(u));
      EXPECT_EQ(sparse.dist(u), d);
      EXPECT_EQ(sparse.pred(u), dense.pred(u));
    }
    settled_total += a.size();
    const std::uint32_t target = (src * 7919u) % n;
    double la = 0, lb = 0;
    const auto pa = detail::astar(g, sc, dense, src, target, la, [](std::uint32_t) { return true; });
    const auto pb = detail::astar(g, sc, sparse, src, target, lb, [](std::uint32_t) { return true; });
    EXPECT_EQ(pa, pb);
    EXPECT_EQ(la, lb);
  }
  EXPECT_GT(settled_total, 10000u);
}
