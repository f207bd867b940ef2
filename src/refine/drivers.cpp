// Refinement drivers (ALGORITHM.md 2.10): uniform levels, level-synchronous adaptive refinement
// by threshold or by maximum error, and budgeted refinement worst-first.
//
// References: Duchaineau et al., "ROAMing terrain: real-time optimally adapting meshes" (1997)
// for the split queue and forced splits; Bänsch (1991) / Kossaczký (1994) for recursive
// newest-vertex bisection; Wood et al. (2000) for the variance criterion.
//
// Splits are first made topologically (forest.h), creating vertex ids without positions; the
// vertices of one batch are then placed in parallel, grouped by the level of the split triangle:
// a split of level ℓ reads only vertices of triangles of level ℓ, all created by splits of level
// < ℓ, so each group reads committed positions and writes its own slots — the result does not
// depend on the thread count. The budget driver splits one block at a time (worst first), so it is
// sequential. At the end the splits are put in progressive order (hierarchy.cpp).
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <queue>

#include "adamesh/error.h"
#include "forest.h"
#include "refine_internal.h"

namespace adamesh {

namespace detail {
// hierarchy.cpp
Hierarchy make_hierarchy(const Forest& forest, const std::vector<std::array<std::uint32_t, 3>>& base,
                         const std::vector<Vec3>& pos, const std::vector<std::uint32_t>& anchor,
                         const std::vector<std::uint8_t>& border,
                         const std::vector<std::uint32_t>& split_tri,
                         const std::vector<TriError>& err);
}  // namespace detail

namespace {

using namespace detail;

class Refiner {
 public:
  Refiner(const Surface& surf, const RefineOptions& opt, RefineStats& stats, StageTicker& tick,
          std::vector<std::array<std::uint32_t, 3>> base, std::vector<Vec3> pos,
          std::vector<std::uint32_t> anchor, std::vector<std::uint8_t> border)
      : surf_(surf), opt_(opt), stats_(stats), tick_(tick), base_(std::move(base)),
        forest_(base_, static_cast<std::uint32_t>(pos.size())), pos_(std::move(pos)),
        anchor_(std::move(anchor)), border_(std::move(border)),
        ws_([] { return PathWorkspace::sparse(); }) {
    min_edge_ = opt.min_edge >= 0 ? opt.min_edge : (surf.field.is_analytic() ? 0.25 : 0.5) * surf.h;
    err_.resize(base_.size());
    cap_.resize(base_.size());
    for (std::uint32_t t = 0; t < base_.size(); ++t) {
      // Depth at which uniform bisection brings this base triangle's edges to min_edge: edges
      // halve every two levels. Descendants never go deeper (runaway refinement along creases
      // and noise, where the error cannot converge, stops there).
      const auto& x = base_[t];
      const double e = std::max({distance(pos_[x[0]], pos_[x[1]]), distance(pos_[x[1]], pos_[x[2]]),
                                 distance(pos_[x[0]], pos_[x[2]])});
      const double ratio = min_edge_ > 0 ? e / min_edge_ : 1e30;
      cap_[t] = static_cast<std::uint8_t>(std::clamp(
          2.0 * std::ceil(std::log2(std::max(ratio, 1.0))) + 2.0, 0.0, 250.0));
    }
    std::vector<std::uint32_t> all(base_.size());
    for (std::uint32_t t = 0; t < all.size(); ++t) all[t] = t;
    evaluate(all);
  }

  void uniform(int levels) {
    for (int j = 0; j < levels; ++j) {
      const std::uint32_t first = num_splits();
      const std::uint32_t ntri = static_cast<std::uint32_t>(forest_.num_base_triangles() + 4 * first);
      for (std::uint32_t t = 0; t < ntri; ++t) {
        tick_.tick();
        if (forest_.is_leaf(t) && forest_.tri(t).level == j) split_block(t, false);
      }
      finish_batch(first);
      report_progress(static_cast<double>(j + 1) / levels);
    }
  }

  /// Level-synchronous: key(t) > threshold marks t; the marked leaves are split (with forced
  /// splits), the batch placed and its triangles evaluated; repeat on the new leaves.
  template <class Key>
  void adaptive(Key&& key, double threshold) {
    std::vector<std::uint32_t> candidates(forest_.num_base_triangles());
    for (std::uint32_t t = 0; t < candidates.size(); ++t) candidates[t] = t;
    bool budget_hit = false;
    for (int round = 0; !candidates.empty() && !budget_hit; ++round) {
      const std::uint32_t first = num_splits();
      for (const std::uint32_t t : candidates) {
        tick_.tick();
        if (!forest_.is_leaf(t) || !(key(err_[t]) > threshold) || !refinable(t)) continue;
        if (opt_.max_triangles > 0 &&
            forest_.num_leaves() + added_by_split(t) > opt_.max_triangles) {
          budget_hit = true;
          break;
        }
        split_block(t, false);
      }
      candidates = finish_batch(first);
      report_progress(std::min(1.0, (round + 1) / 12.0));
    }
    count_at_limit(key, threshold);
  }

  /// Worst first until the budget: ROAM's split queue (stale entries skipped). Only leaves that
  /// `wanted` accepts enter the queue (all of them for the plain budget).
  template <class Key, class Wanted>
  void budget(Key&& key, std::size_t max_triangles, Wanted&& wanted) {
    using Entry = std::pair<float, std::uint32_t>;  // (key, -id order via comparator)
    auto cmp = [](const Entry& a, const Entry& b) {
      return a.first != b.first ? a.first < b.first : a.second > b.second;
    };
    std::priority_queue<Entry, std::vector<Entry>, decltype(cmp)> heap(cmp);
    for (std::uint32_t t = 0; t < forest_.num_base_triangles(); ++t)
      if (refinable(t) && wanted(err_[t])) heap.push({key(err_[t]), t});
    // Batches of the worst leaves (issue 14): up to 1/64 of the leaves (at least one) are split
    // in queue order, then their vertices are placed and their children evaluated together, in
    // parallel; a child enters the queue after its batch. The batch size depends on the mesh
    // only, so the result is the same for any thread count; the budget check is per split.
    bool full = false;
    while (!heap.empty() && !full) {
      // The placements' and evaluations' ticks report this fraction.
      tick_.set_fraction(static_cast<double>(forest_.num_leaves()) /
                         static_cast<double>(max_triangles));
      const std::uint32_t first = num_splits();
      const std::size_t cap = std::max<std::size_t>(1, forest_.num_leaves() / kBudgetBatch);
      std::size_t batch = 0;
      while (!heap.empty() && batch < cap) {
        const std::uint32_t t = heap.top().second;
        heap.pop();
        if (!forest_.is_leaf(t)) continue;
        if (forest_.num_leaves() + added_by_split(t) > max_triangles) {
          full = true;
          break;
        }
        split_block(t, false);
        ++batch;
      }
      for (const std::uint32_t c : finish_batch(first))
        if (forest_.is_leaf(c) && refinable(c) && wanted(err_[c])) heap.push({key(err_[c]), c});
      // A split with its forced splits, placed and evaluated: tens of microseconds.
      tick_.tick_with(
          [&] { return static_cast<double>(forest_.num_leaves()) / static_cast<double>(max_triangles); },
          static_cast<std::uint32_t>(64 * std::max<std::size_t>(batch, 1)));
    }
  }

  /// Leaves whose key still exceeds threshold (stopped by a limit or the cap): stats.
  template <class Key>
  void count_leaves_above(Key&& key, double threshold) {
    count_at_limit(key, threshold);
  }

  Hierarchy result() {
    stats_.splits = num_splits();
    for (const std::uint32_t t : forest_.leaves())
      stats_.max_level = std::max<int>(stats_.max_level, forest_.tri(t).level);
    return make_hierarchy(forest_, base_, pos_, anchor_, border_, split_tri_, err_);
  }

 private:
  std::uint32_t num_splits() const { return static_cast<std::uint32_t>(split_tri_.size()); }

  /// Below the level caps (options, and the base triangle's depth cap), refinement edge ≥
  /// min_edge, and smallest altitude ≥ min_edge/2 (a right isosceles triangle with that hypotenuse
  /// has altitude hypotenuse/2), so slivers along creases or noise stop too.
  bool refinable(std::uint32_t t) const {
    const auto& x = forest_.tri(t);
    if (x.level >= opt_.levels || x.level >= cap_[t]) return false;
    const Vec3 &a = pos_[x.v[0]], &b = pos_[x.v[1]], &c = pos_[x.v[2]];
    const double e = distance(b, c);
    const double longest = std::max({e, distance(a, b), distance(a, c)});
    return e >= min_edge_ && norm(cross(b - a, c - a)) >= 0.5 * min_edge_ * longest;
  }

  /// Triangles a split of t adds, forced splits included.
  std::size_t added_by_split(std::uint32_t t) const {
    std::size_t added = 0;
    for (std::uint32_t x = t;;) {
      const std::uint32_t n = forest_.partner(x);
      added += n == kNone ? 1 : 2;
      if (n == kNone || forest_.compatible(x)) break;
      x = n;
    }
    return added;
  }

  /// Splits t's block, splitting incompatible coarser neighbours first (recursively).
  void split_block(std::uint32_t t, bool forced) {
    if (!forest_.compatible(t)) {
      split_block(forest_.partner(t), true);
      if (!forest_.compatible(t))
        fail(Status::internal, "refine: forced split did not make a block compatible");
    }
    const std::uint32_t s = num_splits();
    if (!forest_.split(t, s)) fail(Status::internal, "refine: block split failed");
    split_tri_.push_back(t);
    pos_.emplace_back();
    anchor_.push_back(0);
    border_.push_back(forest_.partner(t) == kNone ? 1 : 0);
    stats_.forced_splits += forced ? 1 : 0;
    err_.resize(forest_.num_base_triangles() + 4 * static_cast<std::size_t>(num_splits()));
    cap_.resize(err_.size());
    const std::uint32_t c = forest_.num_base_triangles() + 4 * s;
    const std::uint32_t n = forest_.partner(t);
    cap_[c] = cap_[c + 1] = cap_[t];
    if (n != kNone) cap_[c + 2] = cap_[c + 3] = cap_[n];
  }

  EdgeInput edge_input(std::uint32_t s) const {
    const std::uint32_t t = split_tri_[s];
    const auto& x = forest_.tri(t);
    const std::uint32_t n = x.nbr[0];
    EdgeInput in;
    in.p1 = pos_[x.v[1]];
    in.p2 = pos_[x.v[2]];
    in.a1 = anchor_[x.v[1]];
    in.a2 = anchor_[x.v[2]];
    in.border = n == kNone;
    if (in.border) {
      in.ring = {pos_[x.v[2]], pos_[x.v[0]], pos_[x.v[1]], Vec3{}};
      in.ring_size = 3;
    } else {
      in.ring = {pos_[x.v[0]], pos_[x.v[1]], pos_[forest_.tri(n).v[0]], pos_[x.v[2]]};
      in.ring_size = 4;
    }
    return in;
  }

  /// Places the vertices of splits [first, end), evaluates their children; returns the children.
  std::vector<std::uint32_t> finish_batch(std::uint32_t first) {
    const std::uint32_t end = num_splits();
    std::vector<std::uint32_t> order(end - first);
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = first + i;
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return forest_.tri(split_tri_[a]).level < forest_.tri(split_tri_[b]).level;
    });
    std::vector<Placed> placed(order.size());
    for (std::size_t g0 = 0; g0 < order.size();) {
      std::size_t g1 = g0 + 1;
      const int level = forest_.tri(split_tri_[order[g0]]).level;
      while (g1 < order.size() && forest_.tri(split_tri_[order[g1]]).level == level) ++g1;
      // In chunks, cancellation checked between them on this thread: the placements of a level
      // are independent of each other (committed below, in a fixed order).
      for (std::size_t c0 = g0; c0 < g1; c0 += kChunk) {
        const std::size_t c1 = std::min(g1, c0 + kChunk);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(c0, c1, 1),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                            PathWorkspace& ws = ws_.local();
                            for (std::size_t i = r.begin(); i != r.end(); ++i)
                              placed[i] = place_vertex(surf_, edge_input(order[i]), ws);
                          });
        tick_.tick(static_cast<std::uint32_t>(16 * (c1 - c0)));
      }
      for (std::size_t i = g0; i < g1; ++i) {  // commit in a fixed order
        const std::uint32_t v = forest_.vertex_of_split(order[i]);
        pos_[v] = placed[i].position;
        anchor_[v] = placed[i].anchor;
        ++(placed[i].kind == PlacementKind::normal_line ? stats_.line_placements
           : placed[i].kind == PlacementKind::geodesic  ? stats_.geodesic_placements
           : placed[i].kind == PlacementKind::euclidean ? stats_.euclidean_placements
                                                        : stats_.border_placements);
        stats_.unconverged_projections += placed[i].converged ? 0 : 1;
      }
      g0 = g1;
    }
    std::vector<std::uint32_t> children;
    for (std::uint32_t s = first; s < end; ++s) {
      const std::uint32_t c = forest_.num_base_triangles() + 4 * s;
      for (std::uint32_t k = 0; k < 4; ++k)
        if (forest_.exists(c + k)) children.push_back(c + k);
    }
    evaluate(children);
    return children;
  }

  void evaluate(const std::vector<std::uint32_t>& tris) {
    for (std::size_t c0 = 0; c0 < tris.size(); c0 += 4 * kChunk) {
      const std::size_t c1 = std::min(tris.size(), c0 + 4 * kChunk);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(c0, c1, 64),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                            const auto& x = forest_.tri(tris[i]);
                            err_[tris[i]] = evaluate_triangle(surf_.field, surf_.iso, pos_[x.v[0]],
                                                              pos_[x.v[1]], pos_[x.v[2]]);
                          }
                        });
      tick_.tick(static_cast<std::uint32_t>(c1 - c0));
    }
  }

  template <class Key>
  void count_at_limit(Key&& key, double threshold) {
    for (const std::uint32_t t : forest_.leaves())
      if (key(err_[t]) > threshold) ++stats_.at_limit_leaves;
  }

  void report_progress(double f) { tick_.poll(f); }

  /// Vertex placements per parallel batch between two cancellation checks.
  static constexpr std::size_t kChunk = 2048;
  /// The budget driver splits at most leaves / kBudgetBatch blocks per batch.
  static constexpr std::size_t kBudgetBatch = 64;

  const Surface& surf_;
  const RefineOptions& opt_;
  RefineStats& stats_;
  StageTicker& tick_;
  std::vector<std::array<std::uint32_t, 3>> base_;
  Forest forest_;
  std::vector<Vec3> pos_;
  std::vector<std::uint32_t> anchor_;
  std::vector<std::uint8_t> border_;
  std::vector<std::uint32_t> split_tri_;
  std::vector<TriError> err_;
  std::vector<std::uint8_t> cap_;  ///< per triangle: deepest level its base triangle allows
  double min_edge_ = 0;
  tbb::enumerable_thread_specific<PathWorkspace> ws_;
};

RefineResult refine_impl(const SurfelComplex& sc, const BaseMesh& bm, const ScalarField& field,
                         const RefineOptions& opt, const ConnectivityGraph& g,
                         const ExecutionContext& ctx) {
  StageTicker tick(ctx, "refine", 4096);
  using clock = std::chrono::steady_clock;
  RefineResult res;
  RefineStats& st = res.stats;
  const auto t0 = clock::now();
  const Surface surf(sc, g, field, opt);
  const std::size_t nv = bm.mesh.num_vertices();
  std::vector<Vec3> pos(nv);
  for (std::size_t v = 0; v < nv; ++v) pos[v] = bm.mesh.vertex(v);
  std::vector<std::uint32_t> anchor = bm.anchor;
  std::vector<std::uint8_t> border = bm.border;
  std::vector<std::array<std::uint32_t, 3>> tris(bm.mesh.num_triangles());
  for (std::size_t f = 0; f < tris.size(); ++f)
    tris[f] = {bm.mesh.triangles[3 * f], bm.mesh.triangles[3 * f + 1], bm.mesh.triangles[3 * f + 2]};
  st.base_triangles = tris.size();

  Blocks blocks;
  if (!opt.force_quad_blocks) blocks = match_blocks(pos, tris, opt.local_matching_from, &tick);
  std::vector<std::array<std::uint32_t, 3>> labelled;
  if (blocks.perfect) {
    labelled = std::move(blocks.labelled);
    st.greedy_pairs = blocks.greedy_pairs;
    st.augmentations = blocks.augmentations;
    st.local_augmentations = blocks.local_augmentations;
    st.blocks = blocks.blocks;
    st.border_half_blocks = blocks.border_half_blocks;
  } else {
    if (!opt.force_quad_blocks)
      st.warnings.push_back("no perfect matching of the base triangles (non-manifold base mesh?): "
                            "blocks built from three quads per triangle");
    st.quad_fallback = true;
    labelled = quad_blocks(surf, tris, pos, anchor, border);
    st.blocks = labelled.size() / 2;
  }
  st.time_blocks_s = std::chrono::duration<double>(clock::now() - t0).count();

  Refiner r(surf, opt, st, tick, std::move(labelled), std::move(pos), std::move(anchor),
            std::move(border));
  const double delta = opt.delta > 0 ? opt.delta : 0.1 * surf.h;
  auto variance_key = [](const TriError& e) {
    return std::max(e.sqrt_var, 0.25f * e.max_abs);
  };
  // Integrated variance: the squared key times the area, so big triangles go first and a crease,
  // whose error shrinks only linearly with the triangles, does not take the budget.
  auto integrated_variance = [&](const TriError& e) {
    return variance_key(e) * variance_key(e) * e.area;
  };
  switch (opt.mode) {
    case RefineMode::uniform:
      r.uniform(opt.levels);
      break;
    case RefineMode::threshold:
      r.adaptive(variance_key, delta);
      break;
    case RefineMode::max_error:
      // With a triangle cap: the leaves above E, worst (integrated variance, as for the budget)
      // first, so that the cap stops the least useful splits; without one, level-synchronous
      // batches (placed in parallel).
      if (opt.max_triangles > 0) {
        r.budget(integrated_variance, opt.max_triangles,
                 [&](const TriError& e) { return e.max_estimate() > opt.max_error; });
        r.count_leaves_above([](const TriError& e) { return e.max_estimate(); }, opt.max_error);
      } else {
        r.adaptive([](const TriError& e) { return e.max_estimate(); }, opt.max_error);
      }
      break;
    case RefineMode::budget:
      r.budget(integrated_variance, opt.max_triangles, [](const TriError&) { return true; });
      break;
  }
  res.hierarchy = r.result();
  res.hierarchy.iso = sc.iso;
  res.hierarchy.bounds = sc.grid.world_bounds();
  res.hierarchy.voxel = surf.h;
  st.time_refine_s = std::chrono::duration<double>(clock::now() - t0).count() - st.time_blocks_s;
  return res;
}

}  // namespace

RefineResult refine(const SurfelComplex& sc, const BaseMesh& bm, const ScalarField& field,
                    const RefineOptions& opt, const ConnectivityGraph* graph,
                    const ExecutionContext& ctx) {
  if (bm.mesh.num_triangles() == 0) fail_input("refine", "the base mesh has no triangles");
  if (bm.anchor.size() != bm.mesh.num_vertices() || bm.border.size() != bm.mesh.num_vertices())
    fail_input("refine", "the base mesh has no anchor or border flag for every vertex");
  if (opt.levels < 0 || opt.levels > 60) fail_input("refine", "levels must be in 0..60");
  if (opt.mode == RefineMode::max_error && !(opt.max_error > 0))
    fail_input("refine", "max_error must be > 0");
  if (opt.mode == RefineMode::budget && opt.max_triangles == 0)
    fail_input("refine", "max_triangles must be > 0");
  if (!(opt.tau >= 0 && opt.tau <= 1)) fail_input("refine", "tau must be in [0, 1]");
  auto run = [&] {
    if (graph) return refine_impl(sc, bm, field, opt, *graph, ctx);
    const ConnectivityGraph g = build_graph(sc);
    return refine_impl(sc, bm, field, opt, g, ctx);
  };
  if (ctx.threads <= 0) return run();
  tbb::task_arena arena(ctx.threads);
  return arena.execute(run);
}

}  // namespace adamesh
