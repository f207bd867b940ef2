// Hybrid dual/cone triangulation of a partition of the surfel complex into disk cells.
//
// Every cell X becomes a vertex v_X. Walking X's boundary loop (counter-clockwise seen from
// outside) gives the link of v_X: a kept node contributes itself, a boundary segment that is not
// fully kept contributes the neighbour cell across it, consecutive duplicates merge, and a
// 4-cell junction contributes the diagonal cell when X lies on the chosen diagonal. Consecutive
// link entries (p, q) give the triangle (v_X, p, q).
//
// With no kept node this is exactly the dual of the Voronoi covering (ALGORITHM.md 2.6: one
// triangle per junction, quads split along a diagonal). Keeping every boundary node of a cell
// ("cone cell") triangulates it as the cone over its boundary loop, which is valid for any disk
// whatever its neighbours look like; cells whose Voronoi violations could not be repaired are
// meshed that way, so a few stubborn cells cost a few extra vertices instead of falling back for
// their whole component. Each triangle must be produced once per cell vertex it has, always with
// the same orientation; cells where that fails are reported for escalation.
#include <algorithm>
#include <bit>
#include <unordered_set>

#include "voronoi.h"

namespace adamesh::detail {

HybridResult hybrid_triangles(const SurfelComplex& sc, const std::vector<std::uint32_t>& cell,
                              const std::vector<std::uint32_t>& centre,
                              const std::vector<std::uint8_t>& cone) {
  constexpr std::uint32_t kNone = Voronoi::kNone;
  constexpr std::uint32_t kBorder = kNone - 1;
  const std::uint32_t ncell = static_cast<std::uint32_t>(centre.size());
  HybridResult out;

  // Memory (docs/SIMPLIFICATION.md): cell boundary half-edges in a CSR by cell (12 bytes each),
  // counted before they are stored; node sets are bitsets; cell adjacency is read off the
  // half-edges; only each triangle's owner (its smallest cell) stores it.
  struct HalfEdge {
    std::uint32_t a, b, label;
  };
  std::vector<std::uint32_t> first(ncell + 1, 0);  // cell x's half-edges: first[x] .. first[x+1]
  for (std::uint32_t u = 0; u < sc.num_surfels(); ++u) {
    const std::uint32_t c = cell[u];
    if (c == kNone) continue;
    for (const std::int32_t o : sc.opposites_of(u)) first[c + 1] += !(o >= 0 && cell[o] == c);
  }
  for (std::uint32_t c = 0; c < ncell; ++c) first[c + 1] += first[c];
  std::vector<HalfEdge> he(first[ncell]);
  {
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    for (std::uint32_t u = 0; u < sc.num_surfels(); ++u) {
      const std::uint32_t c = cell[u];
      if (c == kNone) continue;
      const auto nodes = sc.nodes_of(u);
      const auto opp = sc.opposites_of(u);
      for (std::size_t e = 0; e < nodes.size(); ++e) {
        const std::int32_t o = opp[e];
        if (o >= 0 && cell[o] == c) continue;
        he[fill[c]++] = {nodes[e], nodes[(e + 1) % nodes.size()], o < 0 ? kBorder : cell[o]};
      }
    }
  }
  for (std::uint32_t c = 0; c < ncell; ++c)
    std::sort(he.begin() + first[c], he.begin() + first[c + 1],
              [](const HalfEdge& p, const HalfEdge& q) { return p.a < q.a; });

  // Kept nodes: every boundary node of a cone cell.
  std::vector<std::uint32_t> kept_list;
  for (std::uint32_t c = 0; c < ncell; ++c)
    if (cone[c])
      for (std::uint32_t i = first[c]; i < first[c + 1]; ++i) kept_list.push_back(he[i].a);

  // Dual edges (cell pairs across a segment), as seen from the smaller cell.
  auto key = [](std::uint32_t x, std::uint32_t y) {
    if (x > y) std::swap(x, y);
    return (std::uint64_t(x) << 32) | y;
  };
  auto adjacent = [&](std::uint32_t x, std::uint32_t y) {
    if (x > y) std::swap(x, y);
    for (std::uint32_t i = first[x]; i < first[x + 1]; ++i)
      if (he[i].label == y) return true;
    return false;
  };

  // 4-cell junctions: choose a diagonal (shorter centre distance, not an existing edge); when
  // both diagonals are edges already, keep the node instead.
  std::sort(kept_list.begin(), kept_list.end());
  kept_list.erase(std::unique(kept_list.begin(), kept_list.end()), kept_list.end());
  // Node → chosen diagonal, in increasing node order (binary search).
  struct Diagonal {
    std::uint32_t node, first, second;
  };
  std::vector<Diagonal> diagonal;
  {
    std::vector<std::uint64_t> candidate((sc.num_nodes() + 63) / 64, 0);  // cell boundary nodes
    for (const auto& h : he) candidate[h.a >> 6] |= std::uint64_t{1} << (h.a & 63);
    std::array<std::int32_t, 4> fan;
    std::unordered_set<std::uint64_t> chosen;
    for (std::size_t word = 0; word < candidate.size(); ++word) {
      for (std::uint64_t bits = candidate[word]; bits != 0; bits &= bits - 1) {
        const auto n = static_cast<std::uint32_t>(64 * word + std::countr_zero(bits));
        if (std::binary_search(kept_list.begin(), kept_list.end(), n)) continue;
        if (!ccw_fan(sc, n, fan)) continue;
        std::array<std::uint32_t, 4> c;
        for (int q = 0; q < 4; ++q) c[q] = cell[static_cast<std::uint32_t>(fan[q])];
        bool distinct = true;
        for (int i = 0; i < 4; ++i)
          for (int j = i + 1; j < 4; ++j) distinct &= c[i] != c[j];
        if (!distinct) continue;
        auto taken = [&](std::uint32_t x, std::uint32_t y) {
          return adjacent(x, y) || chosen.count(key(x, y)) != 0;
        };
        const bool ac = taken(c[0], c[2]), bd = taken(c[1], c[3]);
        if (ac && bd) {
          kept_list.push_back(n);  // both diagonals exist: the node becomes a vertex
          continue;
        }
        bool use_ac = !ac;
        if (!ac && !bd) {
          const double lac = distance(sc.cvertex_position(centre[c[0]]), sc.cvertex_position(centre[c[2]]));
          const double lbd = distance(sc.cvertex_position(centre[c[1]]), sc.cvertex_position(centre[c[3]]));
          use_ac = lac < lbd || (lac == lbd && std::min(c[0], c[2]) < std::min(c[1], c[3]));
        }
        diagonal.push_back(use_ac ? Diagonal{n, c[0], c[2]} : Diagonal{n, c[1], c[3]});
        chosen.insert(use_ac ? key(c[0], c[2]) : key(c[1], c[3]));
      }
    }
  }
  std::sort(kept_list.begin(), kept_list.end());
  kept_list.erase(std::unique(kept_list.begin(), kept_list.end()), kept_list.end());
  // Kept node kept_list[i] is vertex ncell + i.
  // Bitsets over the nodes answer "kept?" and "has a diagonal?" before any binary search.
  std::vector<std::uint64_t> kept_bits((sc.num_nodes() + 63) / 64, 0), diagonal_bits(kept_bits);
  for (const auto n : kept_list) kept_bits[n >> 6] |= std::uint64_t{1} << (n & 63);
  for (const auto& d : diagonal) diagonal_bits[d.node >> 6] |= std::uint64_t{1} << (d.node & 63);
  auto is_kept = [&](std::uint32_t n) { return (kept_bits[n >> 6] >> (n & 63) & 1) != 0; };
  auto kept_vertex = [&](std::uint32_t n) {
    return ncell + static_cast<std::uint32_t>(
                       std::lower_bound(kept_list.begin(), kept_list.end(), n) - kept_list.begin());
  };
  auto find_diagonal = [&](std::uint32_t n) -> const Diagonal* {
    if (!(diagonal_bits[n >> 6] >> (n & 63) & 1)) return nullptr;
    auto it = std::lower_bound(diagonal.begin(), diagonal.end(), n,
                               [](const Diagonal& d, std::uint32_t key) { return d.node < key; });
    return it != diagonal.end() && it->node == n ? &*it : nullptr;
  };

  // Links and triangles, cell by cell: cell_triangles(x, emit) walks x's boundary loop and emits
  // its triangles in canonical rotation (smallest id first); false when the boundary is not one
  // simple loop (then x is not a disk).
  constexpr std::uint32_t kBreak = kNone;
  std::vector<std::uint32_t> link, items;
  auto cell_triangles = [&](std::uint32_t x, auto&& emit) {
    const std::size_t begin = first[x], end = first[x + 1];
    link.clear();
    std::size_t at = begin, steps = 0;
    do {
      const HalfEdge& h = he[at];
      const bool ka = is_kept(h.a), kb = is_kept(h.b);
      if (ka) {
        link.push_back(kept_vertex(h.a));
      } else if (const Diagonal* d = find_diagonal(h.a)) {
        if (d->first == x) link.push_back(d->second);
        else if (d->second == x) link.push_back(d->first);
      }
      if (!(ka && kb)) link.push_back(h.label == kBorder ? kBreak : h.label);
      auto it = std::lower_bound(he.begin() + begin, he.begin() + end, h.b,
                                 [](const HalfEdge& p, std::uint32_t n) { return p.a < n; });
      if (it == he.begin() + end || it->a != h.b || (it + 1 != he.begin() + end && (it + 1)->a == h.b))
        return false;  // the boundary is not one simple loop: not a disk
      at = static_cast<std::size_t>(it - he.begin());
      ++steps;
    } while (at != begin && steps <= end - begin);
    if (steps != end - begin) return false;
    // Merge consecutive duplicates (cyclically), then emit triangles between neighbours.
    items.clear();
    for (auto v : link)
      if (items.empty() || items.back() != v) items.push_back(v);
    while (items.size() > 1 && items.front() == items.back()) items.pop_back();
    const std::size_t m = items.size();
    bool has_break = false;
    for (auto v : items) has_break |= v == kBreak;
    for (std::size_t i = 0; i < m; ++i) {
      const std::uint32_t p = items[i], q = items[(i + 1) % m];
      if (p == kBreak || q == kBreak || p == q) continue;
      if (!has_break && m < 3) continue;
      std::array<std::uint32_t, 3> t{x, p, q};
      const auto r = std::min_element(t.begin(), t.end()) - t.begin();
      std::rotate(t.begin(), t.begin() + r, t.end());
      emit(t);
    }
    return true;
  };
  // Each triangle must be produced once per cell vertex, never reversed. Its owner (the smallest
  // vertex, always a cell: kept nodes come after the cells) stores it; the other cells' copies
  // are counted against the owner's (or kept aside when the owner did not produce it).
  using Tri = std::array<std::uint32_t, 3>;
  std::vector<Tri> owned;
  std::vector<std::uint8_t> problem(ncell, 0);
  {  // counted first: the list is the largest array here, it should not grow by copies
    std::size_t count = 0;
    for (std::uint32_t x = 0; x < ncell; ++x)
      if (first[x] < first[x + 1] &&
          !cell_triangles(x, [&](const Tri& t) { count += t[0] == x; }))
        problem[x] = 1;
    owned.reserve(count);
  }
  for (std::uint32_t x = 0; x < ncell; ++x)
    if (!problem[x] && first[x] < first[x + 1])
      cell_triangles(x, [&](const Tri& t) { if (t[0] == x) owned.push_back(t); });
  std::sort(owned.begin(), owned.end());
  std::vector<std::uint8_t> copies(owned.size(), 0);  // other cells' copies, on the first entry
  std::vector<Tri> orphans;
  for (std::uint32_t x = 0; x < ncell; ++x) {
    if (first[x] == first[x + 1] || problem[x]) continue;
    cell_triangles(x, [&](const Tri& t) {
      if (t[0] == x) return;
      const auto it = std::lower_bound(owned.begin(), owned.end(), t);
      if (it != owned.end() && *it == t) {
        auto& n = copies[static_cast<std::size_t>(it - owned.begin())];
        if (n < 255) ++n;
      } else {
        orphans.push_back(t);
      }
    });
  }
  std::vector<std::uint32_t>().swap(link);
  std::vector<std::uint32_t>().swap(items);
  std::vector<HalfEdge>().swap(he);
  std::vector<Diagonal>().swap(diagonal);
  out.kept_nodes = std::move(kept_list);
  std::sort(orphans.begin(), orphans.end());
  auto produced = [&](const Tri& t) {
    return std::binary_search(owned.begin(), owned.end(), t) ||
           std::binary_search(orphans.begin(), orphans.end(), t);
  };
  auto mark = [&](const Tri& t) {
    for (auto v : t)
      if (v < ncell) problem[v] = 1;
  };
  for (const Tri& t : orphans) mark(t);  // their owner did not produce them
  std::vector<std::uint8_t> keep;  // per distinct owned triangle, in order
  std::size_t valid = 0;
  for (std::size_t i = 0; i < owned.size();) {
    const Tri t = owned[i];
    std::size_t j = i + 1;
    while (j < owned.size() && owned[j] == t) ++j;
    int cells_in = 0;
    for (auto v : t) cells_in += v < ncell;
    const bool ok = static_cast<std::size_t>(cells_in) == j - i + copies[i] &&
                    !produced(Tri{t[0], t[2], t[1]});
    if (!ok) mark(t);
    keep.push_back(ok);
    valid += ok;
    i = j;
  }
  out.triangles.reserve(valid);
  for (std::size_t i = 0, k = 0; i < owned.size(); ++k) {
    const Tri t = owned[i];
    while (i < owned.size() && owned[i] == t) ++i;
    if (keep[k]) out.triangles.push_back(t);
  }
  for (std::uint32_t c = 0; c < ncell; ++c)
    if (problem[c]) out.problem_cells.push_back(c);
  return out;
}

}  // namespace adamesh::detail
