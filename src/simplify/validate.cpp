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
  std::vector<double> rlo(n, 1e300), rhi(n, 0.0);
  std::vector<std::uint8_t> is_centre(n, 0), covered(n, 0);
  auto singleton = [&](std::size_t c) { return !cov.cone.empty() && cov.cone[c] && cov.radius[c] == 0.0; };
  for (std::size_t c = 0; c < cov.centre.size(); ++c) {
    if (singleton(c)) covered[cov.centre[c]] = 1;  // split cells: not disks of the covering
    else is_centre[cov.centre[c]] = 1;
  }
  PathWorkspace ws(n);
  std::vector<std::uint32_t> members;
  for (std::size_t d = 0; d < cov.centre.size(); ++d) {
    if (singleton(d)) continue;
    const std::uint32_t x = cov.centre[d];
    const double r = cov.radius[d];
    members.clear();
    dijkstra(
        g, ws, x, r,
        [&](std::uint32_t v, double) {
          members.push_back(v);
          if (v != x && is_centre[v]) ++out.independence;
          covered[v] = 1;
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
    if (!covered[v]) ++out.uncovered;
    else if (rhi[v] > 2.0 * rlo[v] * (1 + 1e-9)) ++out.grading;
  }
  // Violated cells: the closed-ball checks on the final assignment.
  Voronoi vor(sc, g);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> cells;
  for (std::uint32_t c = 0; c < cov.centre.size(); ++c)
    if (active(cov.centre[c])) cells.push_back({c, cov.centre[c]});
  vor.set_assignment(cov.cell, cov.centre);
  std::vector<std::uint32_t> nb;
  auto is_cone = [&](std::uint32_t c) { return !cov.cone.empty() && cov.cone[c]; };
  for (const auto& [c, x] : cells)
    if (!is_cone(c) && vor.check_cell(c, nb) != kOk) ++out.violated_cells;
  std::vector<std::uint32_t> bad;
  dual_violations(sc, vor.cells(), cov.centre, bad, nullptr);
  for (auto c : bad) out.violated_cells += !is_cone(c);
  return out;
}

}  // namespace adamesh
