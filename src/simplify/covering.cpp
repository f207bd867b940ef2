// Driver of the simplification stage: disk covering → Voronoi covering → local repair of violated
// cells (ALGORITHM.md 2.4–2.5). Violated cells and their neighbours get their disks halved; the
// uncovered surfels get new, smaller disks; the new centres enter the Voronoi covering by an
// incremental multi-source Dijkstra, and only the cells it touched are checked again. A component
// whose violations survive at r_min is meshed from its surfels instead (fallback).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <utility>

#include "adamesh/context.h"
#include "adamesh/simplify.h"
#include "disk_cover.h"
#include "voronoi.h"

namespace adamesh {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double surfel_area(const SurfelComplex& sc, std::size_t s) {
  const Vec3 c = sc.cvertex_position(s);
  const auto nodes = sc.nodes_of(s);
  double a = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i)
    a += 0.5 * norm(cross(sc.node_position(nodes[i]) - c,
                          sc.node_position(nodes[(i + 1) % nodes.size()]) - c));
  return a;
}

/// Components dropped by min_component_surfels.
std::vector<std::uint8_t> dropped_components(const ConnectivityGraph& g, const SimplifyOptions& opt) {
  std::vector<std::size_t> comp_size(g.num_components, 0);
  for (std::size_t v = 0; v < g.num_vertices(); ++v) ++comp_size[g.component[v]];
  std::vector<std::uint8_t> dropped(g.num_components, 0);
  for (std::uint32_t c = 0; c < g.num_components; ++c)
    dropped[c] = opt.min_component_surfels > 0 && comp_size[c] < opt.min_component_surfels;
  return dropped;
}

}  // namespace

double active_surface_area(const SurfelComplex& sc, const ConnectivityGraph& g,
                           const SimplifyOptions& opt) {
  const auto dropped = dropped_components(g, opt);
  double area = 0;
  for (std::size_t v = 0; v < g.num_vertices(); ++v)
    if (!dropped[g.component[v]]) area += surfel_area(sc, v);
  return area;
}

Covering build_covering(const SurfelComplex& sc, const ConnectivityGraph& g,
                        const SimplifyOptions& opt, SimplifyStats& stats,
                        const ExecutionContext& ctx) {
  using namespace detail;
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = g.num_vertices();
  const double h = sc.grid.min_spacing();
  const double unit = opt.unit == LengthUnit::voxels ? h : 1.0;

  // Components: sizes, dropped ones.
  Covering cov;
  cov.dropped = dropped_components(g, opt);
  cov.fallback.assign(g.num_components, 0);
  for (auto d : cov.dropped) stats.dropped_components += d;
  std::vector<std::uint8_t> active(n, 1);
  for (std::size_t v = 0; v < n; ++v)
    if (cov.dropped[g.component[v]]) active[v] = 0;
  const double area = opt.surface_area >= 0 ? opt.surface_area
                      : opt.r_max > 0      ? 0.0
                                           : active_surface_area(sc, g, opt);
  stats.components = g.num_components - stats.dropped_components;

  const double r_min = opt.r_min > 0 ? opt.r_min * unit : 2.0 * h;
  double r_max = opt.r_max > 0 ? opt.r_max * unit : std::sqrt(area / std::max(1.0, opt.target_cells));
  r_max = std::max(r_max, r_min);
  stats.r_min = r_min;
  stats.r_max = r_max;

  DiskCover cover(sc, g, std::move(active), r_max, r_min, stats);
  // Cancellation and progress inside the loops: every few thousand vertices of the Voronoi
  // updates and checks, every 8 disk growths (one Dijkstra each, weighed 512). The repair
  // rounds' growths count as "voronoi".
  StageTicker cover_tick(ctx, "disk cover", 4096);
  StageTicker vor_tick(ctx, "voronoi", 4096);
  bool repairing = false;
  cover.on_progress = [&](double f) {
    if (repairing) vor_tick.tick(512);
    else cover_tick.tick_with([f] { return f; }, 512);
  };
  cover.seed();
  cover.run();
  stats.time_disk_cover_s += seconds_since(t0);
  ctx.report("disk cover", 1);

  ctx.report("voronoi", 0);
  repairing = true;
  const auto t1 = std::chrono::steady_clock::now();
  Voronoi vor(sc, g);
  vor.ticker = &vor_tick;
  auto add_new_cells = [&] {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> cells;
    for (auto d : cover.take_new_disks()) cells.push_back({d, cover.centre(d)});
    vor.add_cells(cells);
    return cells.size();
  };
  add_new_cells();
  stats.regularized += vor.regularize();

  std::vector<std::uint32_t> centre_of_cell;
  auto refresh_centres = [&] {
    centre_of_cell.resize(cover.num_disks());
    for (std::uint32_t d = 0; d < cover.num_disks(); ++d) centre_of_cell[d] = cover.centre(d);
  };
  std::vector<std::uint32_t> nbrs;
  std::vector<std::uint32_t> recheck;
  // Cells whose violations could not be repaired (their component made no progress): they are
  // meshed as cones (or split into single surfels) by the hybrid triangulation.
  std::map<std::uint32_t, int> stuck;
  std::size_t round = 0;
  auto check_all = [&](const std::vector<std::uint32_t>& cells, std::vector<std::uint32_t>& bad,
                       std::map<std::uint32_t, int>& kinds) {
    for (auto c : cells) {
      vor_tick.tick();
      if (!vor.cell_alive(c)) {
        stuck.erase(c);
        continue;
      }
      const int kind = vor.check_cell(c, nbrs);
      if (kind == kOk) {
        stuck.erase(c);
        continue;
      }
      bad.push_back(c);
      kinds[c] = kind;
      ++stats.violations_by_kind[kind];
    }
    refresh_centres();
    std::vector<std::uint32_t> global_bad;
    dual_violations(sc, vor.cells(), centre_of_cell, global_bad, &stats.violations_by_kind,
                    &vor_tick);
    for (auto c : global_bad) {
      bad.push_back(c);
      if (!kinds.count(c)) kinds[c] = kFanPinch;
    }
    std::sort(bad.begin(), bad.end());
    bad.erase(std::unique(bad.begin(), bad.end()), bad.end());
  };
  for (;; ++round) {
    vor_tick.poll(1.0 - 1.0 / (round + 2));  // the rounds' count is unknown: 1/2, 2/3, 3/4, ...
    std::vector<std::uint32_t> bad;
    std::map<std::uint32_t, int> kinds;
    auto to_check = vor.take_touched();
    to_check.insert(to_check.end(), recheck.begin(), recheck.end());
    std::sort(to_check.begin(), to_check.end());
    to_check.erase(std::unique(to_check.begin(), to_check.end()), to_check.end());
    check_all(to_check, bad, kinds);
    std::vector<std::uint32_t> violated;
    for (auto c : bad) {
      if (stuck.count(c)) stuck[c] = kinds[c];
      else violated.push_back(c);
    }
    if (violated.empty()) break;
    stats.violated_cells_repaired += violated.size();
    if (round >= static_cast<std::size_t>(opt.max_rounds)) {
      for (auto c : violated) stuck[c] = kinds[c];
      stats.warnings.push_back("violated cells left after " + std::to_string(round) +
                               " repair rounds are meshed as cones");
      break;
    }
    // Halve the disks of the violated cells and of their neighbour cells.
    std::vector<std::uint32_t> to_halve = violated;
    for (auto c : violated) {
      vor.neighbour_cells(c, nbrs);
      to_halve.insert(to_halve.end(), nbrs.begin(), nbrs.end());
    }
    std::sort(to_halve.begin(), to_halve.end());
    to_halve.erase(std::unique(to_halve.begin(), to_halve.end()), to_halve.end());
    std::vector<std::uint8_t> progress(g.num_components, 0);
    for (auto d : to_halve)
      if (cover.halve(d)) progress[g.component[cover.centre(d)]] = 1;
    cover.process_halvings();
    cover.run();
    const auto fresh = cover.take_new_disks();
    for (auto d : fresh) progress[g.component[cover.centre(d)]] = 1;
    {
      std::vector<std::pair<std::uint32_t, std::uint32_t>> cells;
      for (auto d : fresh) cells.push_back({d, cover.centre(d)});
      vor.add_cells(cells);
    }
    stats.regularized += vor.regularize();
    // Violated cells are checked again next round even if nothing reached them; those of a
    // component that made no progress are stuck at r_min.
    recheck.clear();
    for (auto c : violated) {
      recheck.push_back(c);
      if (!progress[g.component[cover.centre(c)]]) stuck[c] = kinds[c];
    }
  }
  // Final word on the stuck cells (repairs nearby may have fixed some).
  {
    std::vector<std::uint32_t> cells, bad;
    for (const auto& [c, k] : stuck) cells.push_back(c);
    std::map<std::uint32_t, int> kinds;
    check_all(cells, bad, kinds);
    std::map<std::uint32_t, int> still;
    for (auto c : bad) still[c] = kinds[c];
    stuck.swap(still);
  }
  stats.repair_rounds = round;
  stats.time_voronoi_s += seconds_since(t1);

  // Compact: keep the cells that own vertices, in disk order. Stuck cells are split into one
  // cell per surfel, each triangulated as the fan of its polygon (a cone over its nodes).
  std::vector<std::uint32_t> remap(cover.num_disks(), Covering::kNoCell);
  for (std::uint32_t d = 0; d < cover.num_disks(); ++d) {
    if (!vor.cell_alive(d)) continue;
    // A split cell keeps its disk (it is part of the covering) but owns no surfel: every one of
    // its surfels becomes a cell of its own below (a cone = the fan of its polygon).
    const bool split = stuck.count(d) != 0;
    if (!split) remap[d] = static_cast<std::uint32_t>(cov.centre.size());
    stats.split_cells += split;
    cov.centre.push_back(cover.centre(d));
    cov.radius.push_back(cover.radius(d));
    cov.cone.push_back(0);
  }
  cov.cell.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    const auto c = vor.cell(static_cast<std::uint32_t>(v));
    if (c == Voronoi::kNone) {
      cov.cell[v] = Covering::kNoCell;
    } else if (remap[c] == Covering::kNoCell) {  // split: the surfel is a cell of its own
      cov.cell[v] = static_cast<std::uint32_t>(cov.centre.size());
      cov.centre.push_back(static_cast<std::uint32_t>(v));
      cov.radius.push_back(0.0);
      cov.cone.push_back(1);
      ++stats.cone_cells;
    } else {
      cov.cell[v] = remap[c];
    }
  }
  stats.disks = cov.centre.size();
  return cov;
}

}  // namespace adamesh
