// The hierarchy: progressive order of the splits, replay, and extraction of conforming cuts
// (ALGORITHM.md 2.8 "an adaptive mesh is a set of leaves closed under the forced-split
// dependency"; docs/HIERARCHY.md).
//
// References: Velho & Zorin, "4-8 subdivision" (2001); Hoppe, "Progressive meshes" (1996) for
// the idea of a coarse base plus a refinement stream whose prefixes are meshes.
//
// Split s depends on the splits that created its two triangles (each a child of an earlier split,
// forced splits included). Its error e(s) = max distance estimate of its two triangles (sampled
// max |d| × kMaxErrorEstimate) is made monotone
// by propagating backwards, eff(dep) = max(e(dep), eff(s)); sorting the splits stably by
// decreasing eff keeps every dependency before its dependants, so every prefix replays, and the
// splits with eff > E form a prefix. Ids are renumbered to the new order (forest.h: split s owns
// vertex V0+s and triangles F0+4s..F0+4s+3), so stored and in-memory hierarchies coincide.
//
// A cut's mesh lists its vertices by increasing hierarchy id and its leaves depth-first, so its
// bytes depend only on the set of splits applied.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "adamesh/error.h"
#include "adamesh/volume.h"
#include "forest.h"
#include "refine_internal.h"

namespace adamesh {

namespace detail {

Hierarchy make_hierarchy(const Forest& forest, const std::vector<std::array<std::uint32_t, 3>>& base,
                         const std::vector<Vec3>& pos, const std::vector<std::uint32_t>& anchor,
                         const std::vector<std::uint8_t>& border,
                         const std::vector<std::uint32_t>& split_tri,
                         const std::vector<TriError>& err) {
  const std::uint32_t F0 = forest.num_base_triangles(), V0 = forest.num_base_vertices();
  const std::size_t S = split_tri.size();
  std::vector<float> eff(S);
  for (std::size_t s = 0; s < S; ++s) {
    const std::uint32_t t = split_tri[s], n = forest.partner(t);
    eff[s] = std::max(err[t].max_estimate(), n == kNone ? 0.0f : err[n].max_estimate());
  }
  for (std::size_t s = S; s-- > 0;) {
    const std::uint32_t t = split_tri[s], n = forest.partner(t);
    for (const std::uint32_t x : {t, n}) {
      if (x == kNone) continue;
      const std::uint32_t d = forest.creator(x);
      if (d != kNone) eff[d] = std::max(eff[d], eff[s]);
    }
  }
  std::vector<std::uint32_t> order(S), perm(S);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return eff[a] > eff[b]; });
  for (std::uint32_t k = 0; k < S; ++k) perm[order[k]] = k;
  auto remap = [&](std::uint32_t t) {
    return t < F0 ? t : F0 + 4 * perm[(t - F0) / 4] + (t - F0) % 4;
  };
  Hierarchy h;
  h.base_positions.assign(pos.begin(), pos.begin() + V0);
  h.base_triangles = base;
  h.base_border.assign(border.begin(), border.begin() + V0);
  h.base_anchor.assign(anchor.begin(), anchor.begin() + V0);
  h.splits.resize(S);
  for (std::uint32_t k = 0; k < S; ++k)
    h.splits[k] = {remap(split_tri[order[k]]), pos[V0 + order[k]], eff[order[k]]};
  return h;
}

}  // namespace detail

namespace {

using namespace detail;

enum class Filter { prefix, level };

/// Replays splits [0, count) (Filter::level: only those whose triangle has level < level).
/// Throws Error(invalid_input, "<where>: ...") when a split does not apply.
Forest replay(const Hierarchy& h, std::size_t count, Filter filter, int level,
              std::vector<std::uint8_t>* applied, const std::string& where) {
  Forest forest(h.base_triangles, static_cast<std::uint32_t>(h.base_positions.size()));
  const std::uint32_t F0 = forest.num_base_triangles();
  std::vector<std::uint8_t> skipped;  // per triangle id: created by a skipped split
  if (filter == Filter::level) skipped.assign(F0 + 4 * count, 0);
  if (applied) applied->assign(h.splits.size(), 0);
  for (std::uint32_t s = 0; s < count; ++s) {
    const std::uint32_t t = h.splits[s].triangle;
    if (filter == Filter::level) {
      const bool skip = t < skipped.size() && (skipped[t] || (forest.exists(t) && forest.tri(t).level >= level));
      if (skip) {
        for (std::uint32_t k = 0; k < 4; ++k) skipped[F0 + 4 * s + k] = 1;
        continue;
      }
    }
    if (t >= F0 + 4 * static_cast<std::size_t>(s) || !forest.split(t, s))
      fail_input(where, "split " + std::to_string(s) + " (triangle " + std::to_string(t) +
                            ") does not apply: triangle missing, already split, or without a "
                            "compatible neighbour");
    if (applied) (*applied)[s] = 1;
  }
  return forest;
}

CutMesh cut_mesh(const Hierarchy& h, const Forest& forest, const std::vector<std::uint8_t>& applied) {
  CutMesh out;
  const std::uint32_t V0 = static_cast<std::uint32_t>(h.base_positions.size());
  const auto leaves = forest.leaves();
  std::vector<std::uint32_t> used;
  used.reserve(3 * leaves.size());
  for (const std::uint32_t t : leaves)
    for (const std::uint32_t v : forest.tri(t).v) used.push_back(v);
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  out.vertex_id = used;
  out.mesh.positions.reserve(3 * used.size());
  out.vertex_border.reserve(used.size());
  for (const std::uint32_t v : used) {
    out.mesh.add_vertex(h.vertex(v));
    out.vertex_border.push_back(v < V0 ? h.base_border[v]
                                       : forest.partner(h.splits[v - V0].triangle) == kNone);
  }
  auto index = [&](std::uint32_t v) {
    return static_cast<std::uint32_t>(std::lower_bound(used.begin(), used.end(), v) - used.begin());
  };
  out.mesh.triangles.reserve(3 * leaves.size());
  out.triangle_id = leaves;
  out.triangle_level.reserve(leaves.size());
  for (const std::uint32_t t : leaves) {
    const auto& x = forest.tri(t);
    out.mesh.add_triangle(index(x.v[0]), index(x.v[1]), index(x.v[2]));
    out.triangle_level.push_back(x.level);
    out.max_level = std::max<int>(out.max_level, x.level);
  }
  out.splits_applied = forest.num_applied();
  for (std::size_t s = 0; s < h.splits.size(); ++s)
    if (!applied[s]) out.max_error = std::max(out.max_error, h.splits[s].error);
  return out;
}

}  // namespace

CutMesh extract_prefix(const Hierarchy& h, std::size_t num_splits) {
  num_splits = std::min(num_splits, h.splits.size());
  std::vector<std::uint8_t> applied;
  const Forest f = replay(h, num_splits, Filter::prefix, 0, &applied, "hierarchy");
  return cut_mesh(h, f, applied);
}

CutMesh extract_all(const Hierarchy& h) { return extract_prefix(h, h.splits.size()); }

CutMesh extract_level(const Hierarchy& h, int level) {
  std::vector<std::uint8_t> applied;
  const Forest f = replay(h, h.splits.size(), Filter::level, std::max(level, 0), &applied, "hierarchy");
  return cut_mesh(h, f, applied);
}

CutMesh extract_max_error(const Hierarchy& h, double max_error) {
  const auto it = std::partition_point(h.splits.begin(), h.splits.end(),
                                       [&](const HierarchySplit& s) { return s.error > max_error; });
  return extract_prefix(h, static_cast<std::size_t>(it - h.splits.begin()));
}

std::vector<std::size_t> prefix_triangle_counts(const Hierarchy& h) {
  const Forest f = replay(h, h.splits.size(), Filter::prefix, 0, nullptr, "hierarchy");
  std::vector<std::size_t> count(h.splits.size() + 1);
  count[0] = h.base_triangles.size();
  for (std::size_t s = 0; s < h.splits.size(); ++s)
    count[s + 1] = count[s] + (f.partner(h.splits[s].triangle) == kNone ? 1 : 2);
  return count;
}

CutMesh extract_triangles(const Hierarchy& h, std::size_t max_triangles) {
  const auto count = prefix_triangle_counts(h);
  const std::size_t k = static_cast<std::size_t>(
      std::upper_bound(count.begin(), count.end(), max_triangles) - count.begin());
  return extract_prefix(h, k == 0 ? 0 : k - 1);
}

std::vector<std::array<std::uint32_t, 3>> split_edges(const Hierarchy& h) {
  const Forest f = replay(h, h.splits.size(), Filter::prefix, 0, nullptr, "hierarchy");
  std::vector<std::array<std::uint32_t, 3>> out(h.splits.size());
  for (std::uint32_t s = 0; s < h.splits.size(); ++s) {
    const auto& x = f.tri(h.splits[s].triangle);
    out[s] = {x.v[1], x.v[2], f.vertex_of_split(s)};
  }
  return out;
}

void validate_hierarchy(const Hierarchy& h, const std::string& where) {
  const std::size_t V0 = h.base_positions.size();
  if (h.base_triangles.empty()) fail_input(where, "the base mesh has no triangles");
  if (h.base_border.size() != V0) fail_input(where, "border flags do not match the base vertices");
  if (!h.base_anchor.empty() && h.base_anchor.size() != V0)
    fail_input(where, "anchors do not match the base vertices");
  if (!std::isfinite(h.iso)) fail_input(where, "the iso-value is not finite");
  if (!(h.voxel >= kMinVoxelEdge && h.voxel <= kMaxWorldCoordinate))
    fail_input(where, "the voxel size is not a positive length within 1e-18..1e18");
  for (int a = 0; a < 3; ++a)
    if (!(std::abs(h.bounds.lo[a]) <= kMaxWorldCoordinate &&
          std::abs(h.bounds.hi[a]) <= kMaxWorldCoordinate && h.bounds.lo[a] <= h.bounds.hi[a]))
      fail_input(where, "the domain bounds are not finite, ordered and within ±1e18");
  const auto in_range = [](const Vec3& p) {
    return std::abs(p.x) <= kMaxWorldCoordinate && std::abs(p.y) <= kMaxWorldCoordinate &&
           std::abs(p.z) <= kMaxWorldCoordinate;  // false for NaN and inf
  };
  for (std::size_t v = 0; v < V0; ++v) {
    if (!in_range(h.base_positions[v]))
      fail_input(where, "base vertex " + std::to_string(v) +
                            " has a non-finite position or one beyond ±1e18");
    if (h.base_border[v] > 1)
      fail_input(where, "base vertex " + std::to_string(v) + " has border flag " +
                            std::to_string(h.base_border[v]) + " (0 or 1 expected)");
  }
  for (std::size_t t = 0; t < h.base_triangles.size(); ++t) {
    const auto& x = h.base_triangles[t];
    if (x[0] >= V0 || x[1] >= V0 || x[2] >= V0 || x[0] == x[1] || x[1] == x[2] || x[0] == x[2])
      fail_input(where, "base triangle " + std::to_string(t) + " has invalid vertex indices");
  }
  const Forest base(h.base_triangles, static_cast<std::uint32_t>(V0));
  if (base.nonmanifold_edges() > 0) fail_input(where, "the base mesh has non-manifold edges");
  for (std::uint32_t t = 0; t < base.num_base_triangles(); ++t)
    if (!base.compatible(t))
      fail_input(where, "base triangle " + std::to_string(t) +
                            ": refinement edge not shared with its neighbour's (labelling not "
                            "compatible)");
  for (std::size_t s = 0; s < h.splits.size(); ++s) {
    const auto& sp = h.splits[s];
    if (!in_range(sp.position) || !std::isfinite(sp.error) || sp.error < 0)
      fail_input(where, "split " + std::to_string(s) + " has a non-finite position or error");
    if (s > 0 && sp.error > h.splits[s - 1].error)
      fail_input(where, "split " + std::to_string(s) + ": errors are not in decreasing order");
  }
  replay(h, h.splits.size(), Filter::prefix, 0, nullptr, where);
}

}  // namespace adamesh
