// Self-intersections: pairs of triangles that meet other than in what they share (docs/METRICS.md).
//
// Broad phase: a uniform grid of cells about twice the mean triangle box extent; every triangle is
// listed in the cells its box overlaps, and a pair is tested only in the cell that holds the low
// corner of the two boxes' overlap, so each pair is tested once. Narrow phase, by what the two
// triangles share:
//   * nothing: they intersect when an edge of one crosses the other (non-coplanar), or, in a
//     common plane, when edges cross or a vertex lies inside the other;
//   * one vertex p: they intersect elsewhere when the edge of one opposite p crosses the other;
//   * an edge: only a fold onto each other, i.e. coplanar with both far vertices on the same side.
// Signs come from orient3d in double on the (float) coordinates, with zero within a relative
// tolerance; a touching contact counts as an intersection.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "adamesh/metrics.h"
#include "metrics/parallel.h"

namespace adamesh {
namespace {

struct P {
  double x, y, z;
};

inline P sub(const P& a, const P& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }

// Sign of the determinant of (b − a, c − a, d − a): > 0, < 0, or 0 within the tolerance.
inline int orient3d(const P& a, const P& b, const P& c, const P& d) {
  const P u = sub(b, a), v = sub(c, a), w = sub(d, a);
  const double det = u.x * (v.y * w.z - v.z * w.y) - u.y * (v.x * w.z - v.z * w.x) +
                     u.z * (v.x * w.y - v.y * w.x);
  const double mag = (std::abs(u.x) + std::abs(u.y) + std::abs(u.z)) *
                     (std::abs(v.x) + std::abs(v.y) + std::abs(v.z)) *
                     (std::abs(w.x) + std::abs(w.y) + std::abs(w.z));
  if (std::abs(det) <= 1e-12 * mag) return 0;
  return det > 0 ? 1 : -1;
}

// 2D orientation in the plane dropping axis `drop`.
inline int orient2d(const P& a, const P& b, const P& c, int drop) {
  auto uv = [drop](const P& p) {
    return drop == 0 ? std::pair{p.y, p.z} : drop == 1 ? std::pair{p.z, p.x} : std::pair{p.x, p.y};
  };
  const auto [ax, ay] = uv(a);
  const auto [bx, by] = uv(b);
  const auto [cx, cy] = uv(c);
  const double det = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
  const double mag = (std::abs(bx - ax) + std::abs(by - ay)) * (std::abs(cx - ax) + std::abs(cy - ay));
  if (std::abs(det) <= 1e-12 * mag) return 0;
  return det > 0 ? 1 : -1;
}

// Does segment pq meet triangle abc (not coplanar with it)?
bool segment_crosses(const P& p, const P& q, const P& a, const P& b, const P& c) {
  const int sp = orient3d(a, b, c, p), sq = orient3d(a, b, c, q);
  if (sp == sq) return false;  // same side, or both in the plane (the coplanar test handles it)
  const int s1 = orient3d(p, q, a, b), s2 = orient3d(p, q, b, c), s3 = orient3d(p, q, c, a);
  const bool neg = s1 < 0 || s2 < 0 || s3 < 0, pos = s1 > 0 || s2 > 0 || s3 > 0;
  return !(neg && pos);
}

// Proper crossing of segments ab and cd in 2D.
bool segments_cross_2d(const P& a, const P& b, const P& c, const P& d, int drop) {
  const int o1 = orient2d(a, b, c, drop), o2 = orient2d(a, b, d, drop);
  const int o3 = orient2d(c, d, a, drop), o4 = orient2d(c, d, b, drop);
  return o1 * o2 < 0 && o3 * o4 < 0;
}

bool strictly_inside_2d(const P& p, const P* t, int drop) {
  const int a = orient2d(t[0], t[1], p, drop), b = orient2d(t[1], t[2], p, drop),
            c = orient2d(t[2], t[0], p, drop);
  return (a > 0 && b > 0 && c > 0) || (a < 0 && b < 0 && c < 0);
}

int dominant_axis(const P* t) {
  const P u = sub(t[1], t[0]), v = sub(t[2], t[0]);
  const double n[3] = {std::abs(u.y * v.z - u.z * v.y), std::abs(u.z * v.x - u.x * v.z),
                       std::abs(u.x * v.y - u.y * v.x)};
  return n[0] >= n[1] && n[0] >= n[2] ? 0 : n[1] >= n[2] ? 1 : 2;
}

bool coplanar_overlap(const P* s, const P* t) {
  const int drop = dominant_axis(s);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segments_cross_2d(s[i], s[(i + 1) % 3], t[j], t[(j + 1) % 3], drop)) return true;
  for (int i = 0; i < 3; ++i)
    if (strictly_inside_2d(s[i], t, drop) || strictly_inside_2d(t[i], s, drop)) return true;
  return false;
}

bool coplanar(const P* s, const P* t) {
  return orient3d(s[0], s[1], s[2], t[0]) == 0 && orient3d(s[0], s[1], s[2], t[1]) == 0 &&
         orient3d(s[0], s[1], s[2], t[2]) == 0;
}

bool disjoint_pair_intersects(const P* s, const P* t) {
  if (coplanar(s, t)) return coplanar_overlap(s, t);
  for (int i = 0; i < 3; ++i)
    if (segment_crosses(s[i], s[(i + 1) % 3], t[0], t[1], t[2]) ||
        segment_crosses(t[i], t[(i + 1) % 3], s[0], s[1], s[2]))
      return true;
  return false;
}

// s[0] == t[0] is the shared vertex.
bool vertex_pair_intersects(const P* s, const P* t) {
  if (coplanar(s, t)) {
    // Overlap beyond the shared corner: an edge of one strictly inside the other's angle.
    const int drop = dominant_axis(s);
    for (int i = 1; i < 3; ++i)
      if (strictly_inside_2d(s[i], t, drop) || strictly_inside_2d(t[i], s, drop)) return true;
    return segments_cross_2d(s[1], s[2], t[0], t[1], drop) ||
           segments_cross_2d(s[1], s[2], t[0], t[2], drop) ||
           segments_cross_2d(t[1], t[2], s[0], s[1], drop) ||
           segments_cross_2d(t[1], t[2], s[0], s[2], drop);
  }
  return segment_crosses(s[1], s[2], t[0], t[1], t[2]) ||
         segment_crosses(t[1], t[2], s[0], s[1], s[2]);
}

// s[0], s[1] == t[0], t[1] is the shared edge.
bool edge_pair_intersects(const P* s, const P* t) {
  if (orient3d(s[0], s[1], s[2], t[2]) != 0) return false;
  const int drop = dominant_axis(s);
  return orient2d(s[0], s[1], s[2], drop) == orient2d(s[0], s[1], t[2], drop);
}

}  // namespace

namespace {

using PairList = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

/// The intersecting pairs (sorted), restricted to pairs with at least one triangle t where
/// involved[t] != 0 when `involved` is given; nullopt when the pair tests exceed the budget.
std::optional<PairList> find_pairs(const Mesh& mesh, const std::vector<std::uint8_t>* involved,
                                   const ExecutionContext& context) {
  const std::size_t nt = mesh.num_triangles();
  if (nt < 2) return PairList{};
  // Cancellation (a count over a million triangles takes about a second): checked between the
  // phases on the calling thread; the pair-test workers stop early and the throw comes after.
  context.check_cancelled();
  auto tri = [&](std::size_t t) -> std::array<std::uint32_t, 3> {
    return {mesh.triangles[3 * t], mesh.triangles[3 * t + 1], mesh.triangles[3 * t + 2]};
  };
  auto point = [&](std::uint32_t v) {
    const Vec3 p = mesh.vertex(v);
    return P{p.x, p.y, p.z};
  };
  auto box_of = [&](std::size_t t) {
    const auto v = tri(t);
    Vec3 a = mesh.vertex(v[0]), b = a;
    for (int i = 1; i < 3; ++i) {
      const Vec3 p = mesh.vertex(v[i]);
      for (int k = 0; k < 3; ++k) a[k] = std::min(a[k], p[k]), b[k] = std::max(b[k], p[k]);
    }
    std::array<float, 6> bx{};
    for (int k = 0; k < 3; ++k) bx[k] = static_cast<float>(a[k]), bx[k + 3] = static_cast<float>(b[k]);
    return bx;
  };
  // The grid: over every triangle's box, or with `involved` over the involved triangles' boxes
  // (a pair with an involved triangle overlaps inside its box) — each pair is tested in the one
  // cell holding its boxes' overlap's low corner, so the pairs found do not depend on the grid,
  // and a query about a few triangles costs one pass over the mesh's vertices, not a grid of it.
  // Chunked: the extent sums in a fixed order for any thread count.
  struct Extent {
    double sum = 0;
    std::size_t count = 0;
    Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  };
  const Extent ext = detail::with_threads(context, [&] {
    return detail::chunked_reduce(
        nt, Extent{},
        [&](std::size_t t0, std::size_t t1) {
          Extent e;
          for (std::size_t t = t0; t < t1; ++t) {
            if (involved && !(*involved)[t]) continue;
            const auto b = box_of(t);
            ++e.count;
            for (int k = 0; k < 3; ++k) {
              e.sum += static_cast<double>(b[k + 3]) - static_cast<double>(b[k]);
              e.lo[k] = std::min(e.lo[k], static_cast<double>(b[k]));
              e.hi[k] = std::max(e.hi[k], static_cast<double>(b[k + 3]));
            }
          }
          return e;
        },
        [](Extent acc, const Extent& e) {
          acc.sum += e.sum;
          acc.count += e.count;
          for (int k = 0; k < 3; ++k)
            acc.lo[k] = std::min(acc.lo[k], e.lo[k]), acc.hi[k] = std::max(acc.hi[k], e.hi[k]);
          return acc;
        });
  });
  if (ext.count == 0) return PairList{};
  const double extent = ext.sum;
  const Vec3 lo = ext.lo, hi = ext.hi;
  const Box all{lo, hi};
  const double cell_size = std::max(2 * extent / (3 * static_cast<double>(ext.count)), 1e-30);
  std::array<std::int64_t, 3> dims{};
  for (int k = 0; k < 3; ++k)
    dims[k] = std::clamp<std::int64_t>(
        static_cast<std::int64_t>((all.hi[k] - all.lo[k]) / cell_size) + 1, 1, 1024);
  auto cell_of = [&](double x, int k) {
    const double c = (x - all.lo[k]) / (all.hi[k] - all.lo[k] + 1e-300) * static_cast<double>(dims[k]);
    return std::clamp<std::int64_t>(static_cast<std::int64_t>(c), 0, dims[k] - 1);
  };
  auto for_each_cell_of_box = [&](const std::array<float, 6>& b, auto&& f) {
    const std::int64_t x0 = cell_of(b[0], 0), x1 = cell_of(b[3], 0), y0 = cell_of(b[1], 1),
                       y1 = cell_of(b[4], 1), z0 = cell_of(b[2], 2), z1 = cell_of(b[5], 2);
    for (std::int64_t z = z0; z <= z1; ++z)
      for (std::int64_t y = y0; y <= y1; ++y)
        for (std::int64_t x = x0; x <= x1; ++x)
          if (f(static_cast<std::uint64_t>((z * dims[1] + y) * dims[0] + x))) return;
  };
  // Restricted to `involved`: only the cells the involved triangles cover, and the triangles
  // that reach into one of them (the candidates).
  // Membership: a bitmap over the grid when it is small enough (up to 2^27 cells, 16 MB), else
  // a sorted list.
  std::vector<std::uint64_t> active, bits;
  const std::uint64_t grid_cells = static_cast<std::uint64_t>(dims[0] * dims[1] * dims[2]);
  const bool use_bits = grid_cells <= (std::uint64_t{1} << 27);
  auto is_active = [&](std::uint64_t c) {
    return use_bits ? (bits[c >> 6] >> (c & 63) & 1) != 0
                    : std::binary_search(active.begin(), active.end(), c);
  };
  // Candidates (ascending) and their boxes: box[i] is the box of triangle candidates[i].
  std::vector<std::uint32_t> candidates;
  std::vector<std::array<float, 6>> box;
  if (involved) {
    if (use_bits) bits.assign((grid_cells + 63) / 64, 0);
    for (std::size_t t = 0; t < nt; ++t)
      if ((*involved)[t])
        for_each_cell_of_box(box_of(t), [&](std::uint64_t c) {
          if (use_bits) bits[c >> 6] |= std::uint64_t{1} << (c & 63);
          else active.push_back(c);
          return false;
        });
    std::sort(active.begin(), active.end());
    active.erase(std::unique(active.begin(), active.end()), active.end());
    std::vector<std::uint8_t> hit(nt, 0);
    detail::with_threads(context, [&] {
      detail::for_chunks(nt, [&](std::size_t t0, std::size_t t1) {
        if (context.cancelled()) return;
        for (std::size_t t = t0; t < t1; ++t) {
          bool h = (*involved)[t] != 0;
          if (!h) {
            const auto b = box_of(t);
            bool near = true;  // within the involved triangles' extent
            for (int k = 0; k < 3; ++k) near &= b[k] <= all.hi[k] && all.lo[k] <= b[k + 3];
            if (near) for_each_cell_of_box(b, [&](std::uint64_t c) { return h = is_active(c); });
          }
          hit[t] = h;
        }
      });
    });
    for (std::size_t t = 0; t < nt; ++t)
      if (hit[t]) candidates.push_back(static_cast<std::uint32_t>(t));
  } else {
    candidates.resize(nt);
    for (std::size_t t = 0; t < nt; ++t) candidates[t] = static_cast<std::uint32_t>(t);
  }
  box.resize(candidates.size());
  detail::with_threads(context, [&] {
    detail::for_chunks(candidates.size(), [&](std::size_t i0, std::size_t i1) {
      for (std::size_t i = i0; i < i1; ++i) box[i] = box_of(candidates[i]);
    });
  });
  auto for_each_cell = [&](std::uint32_t i, auto&& f) { for_each_cell_of_box(box[i], f); };
  // Duplicate triangles (same vertex set) are listed once: they are a topology finding, and a
  // pile of copies would make the pair tests quadratic. Copies share their box, so a candidate's
  // copies are candidates too.
  context.check_cancelled();
  std::vector<std::uint32_t> listed;
  {
    std::vector<std::pair<std::array<std::uint32_t, 3>, std::uint32_t>> keys(candidates.size());
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      auto k = tri(candidates[i]);
      std::sort(k.begin(), k.end());
      keys[i] = {k, static_cast<std::uint32_t>(i)};  // candidates ascend: the same order
    }
    tbb::parallel_sort(keys.begin(), keys.end());  // distinct (index): a total order
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (i == 0 || keys[i].first != keys[i - 1].first) listed.push_back(keys[i].second);
    std::sort(listed.begin(), listed.end());
  }
  // Cell lists (sorted by cell).
  std::vector<std::pair<std::uint64_t, std::uint32_t>> entries;
  for (const std::uint32_t t : listed)
    for_each_cell(t, [&](std::uint64_t c) {
      if (!involved || is_active(c)) entries.push_back({c, t});
      return false;
    });
  context.check_cancelled();
  tbb::parallel_sort(entries.begin(), entries.end());
  std::vector<std::size_t> starts;
  for (std::size_t i = 0; i < entries.size(); ++i)
    if (i == 0 || entries[i].first != entries[i - 1].first) starts.push_back(i);
  starts.push_back(entries.size());
  const std::size_t cells = starts.size() - 1;

  // Pair tests are bounded: a pile of triangles over one spot (a fan of 100,000 slivers) would
  // be quadratic; beyond the budget the count is unknown (pairs = −1).
  std::size_t tests = 0;
  for (std::size_t c = 0; c < cells; ++c) {
    const std::size_t m = starts[c + 1] - starts[c];
    tests += m * (m - 1) / 2;
  }
  if (tests > 64 * nt + 10'000'000) return std::nullopt;
  context.check_cancelled();
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> found(cells);
  detail::with_threads(context, [&] {
    detail::for_chunks(cells, [&](std::size_t c0, std::size_t c1) {
      if (context.cancelled()) return;
      for (std::size_t c = c0; c < c1; ++c) {
        const std::uint64_t id = entries[starts[c]].first;
        const std::int64_t cx = static_cast<std::int64_t>(id % dims[0]),
                           cy = static_cast<std::int64_t>(id / dims[0] % dims[1]),
                           cz = static_cast<std::int64_t>(id / (dims[0] * dims[1]));
        for (std::size_t i = starts[c]; i < starts[c + 1]; ++i)
          for (std::size_t j = i + 1; j < starts[c + 1]; ++j) {
            const std::uint32_t ia = entries[i].second, ib = entries[j].second;
            const std::uint32_t a = candidates[ia], b = candidates[ib];
            if (involved && !(*involved)[a] && !(*involved)[b]) continue;
            const auto &ba = box[ia], &bb = box[ib];
            float lo[3];
            bool overlap = true;
            for (int k = 0; k < 3; ++k) {
              overlap &= ba[k] <= bb[k + 3] && bb[k] <= ba[k + 3];
              lo[k] = std::max(ba[k], bb[k]);
            }
            if (!overlap || cell_of(lo[0], 0) != cx || cell_of(lo[1], 1) != cy ||
                cell_of(lo[2], 2) != cz)
              continue;
            auto ta = tri(a), tb = tri(b);
            // Shared vertices first, in the same order in both.
            int shared = 0;
            std::array<std::uint32_t, 3> sa{}, sb{};
            for (int u = 0; u < 3; ++u)
              for (int w = 0; w < 3; ++w)
                if (ta[u] == tb[w]) sa[shared] = ta[u], sb[shared] = tb[w], ++shared;
            if (shared > 3) continue;  // collapsed triangles (repeated indices)
            {
              int ka = shared, kb = shared;
              for (int u = 0; u < 3; ++u)
                if (std::find(sa.begin(), sa.begin() + shared, ta[u]) == sa.begin() + shared && ka < 3)
                  sa[ka++] = ta[u];
              for (int w = 0; w < 3; ++w)
                if (std::find(sb.begin(), sb.begin() + shared, tb[w]) == sb.begin() + shared && kb < 3)
                  sb[kb++] = tb[w];
              ta = sa;
              tb = sb;
            }
            if (shared == 3) continue;  // duplicate triangles: a topology matter, not counted
            if (ta[0] == ta[1] || ta[1] == ta[2] || ta[0] == ta[2] || tb[0] == tb[1] ||
                tb[1] == tb[2] || tb[0] == tb[2])
              continue;  // collapsed triangles
            const P s[3] = {point(ta[0]), point(ta[1]), point(ta[2])};
            const P t[3] = {point(tb[0]), point(tb[1]), point(tb[2])};
            const bool hit = shared == 0   ? disjoint_pair_intersects(s, t)
                             : shared == 1 ? vertex_pair_intersects(s, t)
                                           : edge_pair_intersects(s, t);
            if (hit) found[c].push_back({std::min(a, b), std::max(a, b)});
          }
      }
    }, 64);
  });
  context.check_cancelled();
  PairList pairs;
  for (auto& f : found) pairs.insert(pairs.end(), f.begin(), f.end());
  tbb::parallel_sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace

IntersectionReport self_intersections(const Mesh& mesh, std::size_t keep_pairs,
                                      const ExecutionContext& context) {
  IntersectionReport rep;
  std::optional<PairList> pairs = find_pairs(mesh, nullptr, context);
  if (!pairs) {
    rep.pairs = -1;
    return rep;
  }
  rep.pairs = static_cast<std::int64_t>(pairs->size());
  if (keep_pairs > 0) {
    pairs->resize(std::min(pairs->size(), keep_pairs));
    rep.first_pairs = std::move(*pairs);
  }
  return rep;
}

std::optional<std::vector<std::pair<std::uint32_t, std::uint32_t>>> intersecting_pairs_involving(
    const Mesh& mesh, const std::vector<std::uint8_t>& involved, const ExecutionContext& context) {
  if (involved.size() != mesh.num_triangles())
    throw std::invalid_argument("intersecting_pairs_involving: one flag per triangle");
  return find_pairs(mesh, &involved, context);
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs_after_change(
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& pairs,
    const std::vector<std::uint8_t>& changed,
    const std::vector<std::pair<std::uint32_t, std::uint32_t>>& near) {
  PairList merged;
  for (const auto& pr : pairs)
    if (!changed[pr.first] && !changed[pr.second]) merged.push_back(pr);
  const std::size_t kept = merged.size();
  merged.insert(merged.end(), near.begin(), near.end());
  std::inplace_merge(merged.begin(), merged.begin() + static_cast<std::ptrdiff_t>(kept), merged.end());
  return merged;
}

}  // namespace adamesh
