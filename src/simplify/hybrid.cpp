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

  struct HalfEdge {
    std::uint32_t c, a, b, label;
  };
  // Memory (docs/SIMPLIFICATION.md): the half-edges are counted first and stored once (no
  // regrowth copies); node sets are bitsets; produced triangles are a sorted vector, not a map.
  std::vector<HalfEdge> he;
  {
    std::size_t count = 0;
    for (std::uint32_t u = 0; u < sc.num_surfels(); ++u) {
      const std::uint32_t c = cell[u];
      if (c == kNone) continue;
      for (const std::int32_t o : sc.opposites_of(u)) count += !(o >= 0 && cell[o] == c);
    }
    he.reserve(count);
  }
  for (std::uint32_t u = 0; u < sc.num_surfels(); ++u) {
    const std::uint32_t c = cell[u];
    if (c == kNone) continue;
    const auto nodes = sc.nodes_of(u);
    const auto opp = sc.opposites_of(u);
    for (std::size_t e = 0; e < nodes.size(); ++e) {
      const std::int32_t o = opp[e];
      if (o >= 0 && cell[o] == c) continue;
      he.push_back({c, nodes[e], nodes[(e + 1) % nodes.size()], o < 0 ? kBorder : cell[o]});
    }
  }
  std::sort(he.begin(), he.end(), [](const HalfEdge& p, const HalfEdge& q) {
    return p.c != q.c ? p.c < q.c : p.a < q.a;
  });

  // Kept nodes: every boundary node of a cone cell.
  std::vector<std::uint32_t> kept_list;
  for (const auto& h : he)
    if (cone[h.c]) kept_list.push_back(h.a);

  // Dual edges (cell pairs across a segment) for the quad decisions.
  std::vector<std::uint64_t> pairs;
  auto key = [](std::uint32_t x, std::uint32_t y) {
    if (x > y) std::swap(x, y);
    return (std::uint64_t(x) << 32) | y;
  };
  {
    std::size_t count = 0;
    for (const auto& h : he) count += h.label != kBorder && h.c < h.label;
    pairs.reserve(count);
  }
  for (const auto& h : he)
    if (h.label != kBorder && h.c < h.label) pairs.push_back(key(h.c, h.label));
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  auto adjacent = [&](std::uint32_t x, std::uint32_t y) {
    return std::binary_search(pairs.begin(), pairs.end(), key(x, y));
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
  auto is_kept = [&](std::uint32_t n) {
    return std::binary_search(kept_list.begin(), kept_list.end(), n);
  };
  auto kept_vertex = [&](std::uint32_t n) {
    return ncell + static_cast<std::uint32_t>(
                       std::lower_bound(kept_list.begin(), kept_list.end(), n) - kept_list.begin());
  };
  auto find_diagonal = [&](std::uint32_t n) -> const Diagonal* {
    auto it = std::lower_bound(diagonal.begin(), diagonal.end(), n,
                               [](const Diagonal& d, std::uint32_t key) { return d.node < key; });
    return it != diagonal.end() && it->node == n ? &*it : nullptr;
  };

  // Links and triangles, cell by cell.
  constexpr std::uint32_t kBreak = kNone;
  // Every triangle as produced by each of its cells (canonical rotation: smallest id first).
  std::vector<std::array<std::uint32_t, 3>> produced;
  produced.reserve(he.size());  // about one per boundary half-edge at most, in practice
  std::vector<std::uint32_t> link;
  std::vector<std::uint8_t> problem(ncell, 0);
  for (std::size_t begin = 0; begin < he.size();) {
    std::size_t end = begin;
    while (end < he.size() && he[end].c == he[begin].c) ++end;
    const std::uint32_t x = he[begin].c;
    // Walk the loop from the first half-edge.
    link.clear();
    std::size_t at = begin, steps = 0;
    bool ok = true;
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
      if (it == he.begin() + end || it->a != h.b || (it + 1 != he.begin() + end && (it + 1)->a == h.b)) {
        ok = false;  // the boundary is not one simple loop: not a disk
        break;
      }
      at = static_cast<std::size_t>(it - he.begin());
      ++steps;
    } while (at != begin && steps <= end - begin);
    if (!ok || steps != end - begin) {
      problem[x] = 1;
      begin = end;
      continue;
    }
    // Merge consecutive duplicates (cyclically), then emit triangles between neighbours.
    std::vector<std::uint32_t> items;
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
      produced.push_back(t);
    }
    begin = end;
  }
  std::vector<std::uint32_t>().swap(link);
  std::vector<HalfEdge>().swap(he);
  std::vector<std::uint64_t>().swap(pairs);
  std::vector<Diagonal>().swap(diagonal);
  out.kept_nodes = std::move(kept_list);
  // Each triangle once per cell vertex; the reversed triangle must not occur.
  std::sort(produced.begin(), produced.end());
  std::vector<std::uint8_t> keep;  // per distinct triangle, in order
  std::size_t valid = 0;
  for (std::size_t i = 0; i < produced.size();) {
    const auto t = produced[i];
    std::size_t j = i + 1;
    while (j < produced.size() && produced[j] == t) ++j;
    int cells_in = 0;
    for (auto v : t) cells_in += v < ncell;
    const std::array<std::uint32_t, 3> rev{t[0], t[2], t[1]};
    const bool reversed = std::binary_search(produced.begin(), produced.end(), rev);
    const bool ok = static_cast<std::size_t>(cells_in) == j - i && !reversed;
    if (!ok)
      for (auto v : t)
        if (v < ncell) problem[v] = 1;
    keep.push_back(ok);
    valid += ok;
    i = j;
  }
  out.triangles.reserve(valid);
  for (std::size_t i = 0, k = 0; i < produced.size(); ++k) {
    const auto t = produced[i];
    while (i < produced.size() && produced[i] == t) ++i;
    if (keep[k]) out.triangles.push_back(t);
  }
  for (std::uint32_t c = 0; c < ncell; ++c)
    if (problem[c]) out.problem_cells.push_back(c);
  return out;
}

}  // namespace adamesh::detail
