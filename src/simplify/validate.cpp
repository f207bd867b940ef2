// Debug validator of the covering (ALGORITHM.md section 4, "Covering"): coverage, independence,
// grading ≤ 2, every disk a topological disk, and no violated Voronoi cell left. Slow (one
// Dijkstra per disk); used by tests and by `--validate`.
#include <algorithm>
#include <unordered_map>

#include "adamesh/simplify.h"
#include "disk_cover.h"
#include "voronoi.h"

namespace adamesh {

CoveringValidation validate_covering(const SurfelComplex& sc, const ConnectivityGraph& g,
                                     const Covering& cov) {
  using namespace detail;
  CoveringValidation out;
  out.ran = true;
  const std::size_t n = g.num_vertices();
  auto active = [&](std::uint32_t v) {
    const auto c = g.component[v];
    return !cov.dropped[c] && !cov.fallback[c];
  };
  std::vector<float> rlo(n, 3e38f), rhi(n, 0.f);
  std::vector<std::uint8_t> is_centre(n, 0);
  for (auto x : cov.centre) is_centre[x] = 1;
  PathWorkspace ws(n);
  std::vector<std::uint32_t> members;
  for (std::size_t d = 0; d < cov.centre.size(); ++d) {
    const std::uint32_t x = cov.centre[d];
    const double r = cov.radius[d];
    members.clear();
    dijkstra(
        g, ws, x, r,
        [&](std::uint32_t v, double) {
          members.push_back(v);
          if (v != x && is_centre[v]) ++out.independence;
          rlo[v] = std::min(rlo[v], cov.radius[d]);
          rhi[v] = std::max(rhi[v], cov.radius[d]);
          return Visit::expand;
        },
        [&](std::uint32_t v) { return active(v); });
    // Topological disk: χ = 1 with one boundary loop, or (whole open component) χ = 1.
    std::unordered_map<std::uint32_t, std::uint8_t> in;
    for (auto v : members) in[v] = 1;
    std::vector<std::uint32_t> nodes;
    std::unordered_map<std::uint32_t, std::uint32_t> next;
    long half = 0;
    bool pinched = false;
    for (auto u : members) {
      const auto nd = sc.nodes_of(u);
      const auto op = sc.opposites_of(u);
      for (std::size_t e = 0; e < nd.size(); ++e) {
        nodes.push_back(nd[e]);
        if (op[e] >= 0 && in.count(static_cast<std::uint32_t>(op[e]))) {
          ++half;
        } else {
          half += 2;
          if (!next.emplace(nd[e], nd[(e + 1) % nd.size()]).second) pinched = true;
        }
      }
    }
    std::sort(nodes.begin(), nodes.end());
    const long v_count = static_cast<long>(std::unique(nodes.begin(), nodes.end()) - nodes.begin());
    const long chi = v_count - half / 2 + static_cast<long>(members.size());
    std::size_t loops = 0;
    std::unordered_map<std::uint32_t, std::uint8_t> seen;
    for (const auto& [s, t] : next) {
      if (seen.count(s)) continue;
      for (std::uint32_t a = s; !seen.count(a);) {
        seen[a] = 1;
        auto it = next.find(a);
        if (it == next.end()) break;
        a = it->second;
      }
      ++loops;
    }
    if (chi != 1 || loops != 1 || pinched) ++out.non_disks;
  }
  for (std::uint32_t v = 0; v < n; ++v) {
    if (!active(v)) continue;
    if (rhi[v] == 0.f) ++out.uncovered;
    else if (rhi[v] > 2.0f * rlo[v] * (1 + 1e-6f)) ++out.grading;
  }
  // Violated cells: the closed-ball checks on the final assignment.
  Voronoi vor(sc, g);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> cells;
  for (std::uint32_t c = 0; c < cov.centre.size(); ++c)
    if (active(cov.centre[c])) cells.push_back({c, cov.centre[c]});
  vor.set_assignment(cov.cell, cov.centre);
  std::vector<std::uint32_t> nb;
  for (const auto& [c, x] : cells)
    if (vor.check_cell(c, nb) != kOk) ++out.violated_cells;
  std::vector<std::array<std::uint32_t, 3>> tris;
  std::vector<std::uint32_t> bad;
  dual_triangles(sc, vor.cells(), cov.centre, tris, bad, nullptr);
  out.violated_cells += bad.size();
  return out;
}

}  // namespace adamesh
