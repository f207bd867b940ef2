// Connectivity graph G of the surfel complex (Peixoto & Velho 2002, section 2; ALGORITHM.md 2.3).
//
// Two surfels are neighbours when they share a node, so every node contributes a clique on its
// fan (up to four surfels). Rows are emitted in link order: walking a surfel's polygon, each
// edge contributes the surfel across it, each node the fan members not yet seen (the corner
// neighbour, then any other surfel of that fan), so a row is the ring of neighbours around the
// surfel on the surface. Count → prefix sum → fill keeps the construction parallel and the result
// independent of the thread count.
#include "adamesh/graph.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <numeric>

namespace adamesh {

namespace {

/// Appends the link-ordered, de-duplicated neighbours of surfel s to out (max a few dozen).
template <class Out>
void link_of(const SurfelComplex& sc, std::uint32_t s, Out& out) {
  const auto nodes = sc.nodes_of(s);
  const auto opp = sc.opposites_of(s);
  const std::size_t k = nodes.size();
  auto push = [&](std::int32_t t) {
    if (t < 0 || static_cast<std::uint32_t>(t) == s) return;
    for (std::size_t i = 0; i < out.size(); ++i)
      if (out[i] == static_cast<std::uint32_t>(t)) return;
    out.push_back(static_cast<std::uint32_t>(t));
  };
  for (std::size_t e = 0; e < k; ++e) {
    push(opp[e]);
    // At the node ending edge e the fan holds s, opp[e], the corner (diagonal) neighbour and
    // opp[e+1]: the corner neighbour comes between the two edge neighbours.
    const auto& fan = sc.node_fan[nodes[(e + 1) % k]];
    for (int q = 0; q < 4; ++q)
      if (fan[q] == static_cast<std::int32_t>(s)) push(fan[(q + 2) % 4]);
  }
}

bool delta_fits(std::size_t v, std::uint32_t u) {
  const std::int64_t d = std::int64_t{u} - static_cast<std::int64_t>(v);
  return d >= -32767 && d <= 32767;
}

}  // namespace

void ConnectivityGraph::release_adjacency() {
  std::vector<std::uint32_t>().swap(row);
  std::vector<std::uint32_t>().swap(col);
  std::vector<std::int16_t>().swap(delta);
  std::vector<float>().swap(weight);
}

ConnectivityGraph build_graph(const SurfelComplex& sc) {
  const std::size_t n = sc.num_surfels();
  ConnectivityGraph g;
  g.row.assign(n + 1, 0);
  g.border.assign(n, 0);

  struct Small {
    std::uint32_t v[48];
    std::size_t n = 0;
    void push_back(std::uint32_t x) { if (n < 48) v[n++] = x; }
    std::size_t size() const { return n; }
    std::uint32_t operator[](std::size_t i) const { return v[i]; }
  };

  std::atomic<bool> fits{true};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
    Small tmp;
    for (std::size_t s = r.begin(); s != r.end(); ++s) {
      tmp.n = 0;
      link_of(sc, static_cast<std::uint32_t>(s), tmp);
      g.row[s + 1] = static_cast<std::uint32_t>(tmp.size());
      for (std::size_t i = 0; i < tmp.size(); ++i)
        if (!delta_fits(s, tmp[i])) fits.store(false, std::memory_order_relaxed);
      for (auto o : sc.opposites_of(s))
        if (o < 0) g.border[s] = 1;
    }
  });
  std::partial_sum(g.row.begin(), g.row.end(), g.row.begin());
  g.position = sc.cvertex.data();
  // Columns: compact 16-bit offsets unless some neighbour is too far in id (then absolute ids),
  // written directly in their final form.
  const bool compact = fits.load();
  if (compact) g.delta.resize(g.row[n]);
  else g.col.resize(g.row[n]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
    Small tmp;
    for (std::size_t s = r.begin(); s != r.end(); ++s) {
      tmp.n = 0;
      link_of(sc, static_cast<std::uint32_t>(s), tmp);
      for (std::size_t i = 0; i < tmp.size(); ++i) {
        if (compact) g.delta[g.row[s] + i] = static_cast<std::int16_t>(std::int64_t{tmp[i]} - std::int64_t(s));
        else g.col[g.row[s] + i] = tmp[i];
      }
    }
  });

  // Components: label propagation by union-find (sequential, linear).
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t s = 0; s < n; ++s)
    for (auto t : g.neighbours(s)) {
      std::uint32_t a = find(static_cast<std::uint32_t>(s)), b = find(t);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  g.component.resize(n);
  std::vector<std::uint32_t> id_of_root(n, UINT32_MAX);
  for (std::size_t s = 0; s < n; ++s) {
    const std::uint32_t r = find(static_cast<std::uint32_t>(s));
    if (id_of_root[r] == UINT32_MAX) id_of_root[r] = g.num_components++;
    g.component[s] = id_of_root[r];
  }
  return g;
}

}  // namespace adamesh
