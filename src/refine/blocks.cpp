// Blocks for 4-8 refinement (ALGORITHM.md 2.7): pairs of base triangles sharing their refinement
// edge (the block's diagonal), or single border triangles whose diagonal is a border edge.
//
// References: Velho & Zorin, "4-8 subdivision" (CAGD 2001) for blocks and compatible labelling;
// Edmonds, "Paths, trees, and flowers" (1965) — Boost.Graph's edmonds_augmenting_path_finder
// (Tarjan's formulation); Petersen's theorem (every bridgeless cubic graph has a perfect
// matching).
//
// The dual graph of M0 is doubled: two copies glued along the border, so triangle t and its mirror
// t' are adjacent across each border edge of t. The doubled surface is closed, its dual cubic and
// bridgeless, so a perfect matching exists; t matched to t' is a border half-block. Each dual edge
// is weighted by the shapes its block's children would have (planar estimate). A greedy seed takes
// good blocks (no child angle below 20°) whose shared edge is the longest edge of both triangles
// first (longest-edge labelling gives the best shape bounds), mirrored in both copies; Edmonds'
// augmenting paths make it a maximum matching of the good blocks, then a perfect matching of the
// whole doubled graph. Boost's augmenting-path search scans the whole graph for every path
// (O(n·m) when the seed leaves many vertices unmatched: a 285k-triangle base of the frog ran for
// more than 15 minutes), so every base first augments inside small balls around each unmatched
// vertex (induced subgraphs closed under the matching, so a path found there augments the whole
// graph); only what is left goes to the global search — for the good blocks only on bases under
// `local_from` triangles (a maximal, not maximum, set of good blocks on larger ones).
// Augmenting paths ignore shapes, so the perfect matching is then improved
// locally by alternating chains (≤ 10 exchanges from blocks with a child below 20°, ≤ 6 from good
// ones; ≤ 6 for all on bases of `local_from` triangles or more, frog: matching 26 → 7.5 s, 47 →
// 52 % of its triangles in blocks with a child below 20°) that raise the total block weight: a
// local search for a maximum-weight perfect matching that keeps perfection. Boost headers stay
// inside this file.
//
// Fallback when no perfect matching exists (non-manifold input): three quads per triangle
// (corner, two edge midpoints, centroid), each split along the diagonal that gives the better
// shapes; each quad is a block.
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/max_cardinality_matching.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>

#include "forest.h"
#include "refine_internal.h"

namespace adamesh::detail {

namespace {

std::array<std::uint32_t, 3> rotate_to(const std::array<std::uint32_t, 3>& t, int i) {
  return {t[i], t[(i + 1) % 3], t[(i + 2) % 3]};
}

double edge_length(const std::vector<Vec3>& p, const std::array<std::uint32_t, 3>& t, int i) {
  return distance(p[t[(i + 1) % 3]], p[t[(i + 2) % 3]]);
}

int longest_edge(const std::vector<Vec3>& p, const std::array<std::uint32_t, 3>& t) {
  int best = 0;
  for (int i = 1; i < 3; ++i)
    if (edge_length(p, t, i) > edge_length(p, t, best)) best = i;
  return best;
}

/// Smallest angle of a triangle, degrees.
double min_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  auto angle = [](const Vec3& u, const Vec3& v) {
    const double d = norm(u) * norm(v);
    return d > 0 ? std::acos(std::clamp(dot(u, v) / d, -1.0, 1.0)) * (180 / M_PI) : 0.0;
  };
  return std::min({angle(b - a, c - a), angle(a - b, c - b), angle(a - c, b - c)});
}

/// Block weight = min(smallest child angle, kGoodAngle) + kGoodBonus when that angle is at least
/// kSliverAngle: the number of blocks without slivers counts first, then the angles below 32°.
constexpr double kGoodAngle = 32;
constexpr double kSliverAngle = 20;
constexpr double kGoodBonus = 100;

double radius_ratio(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double la = distance(b, c), lb = distance(a, c), lc = distance(a, b);
  const double area = 0.5 * norm(cross(b - a, c - a));
  const double s = 0.5 * (la + lb + lc);
  const double den = s * la * lb * lc;
  return den > 0 ? 8 * area * area / den : 0;
}

/// Edge of t across which u lies, or -1.
int edge_to(const Forest& adj, std::uint32_t t, std::uint32_t u) {
  for (int i = 0; i < 3; ++i)
    if (adj.tri(t).nbr[i] == u) return i;
  return -1;
}

/// Per triangle and edge: the block weight (kGoodAngle above) of the children that bisecting that
/// edge as a block diagonal makes (planar estimate, midpoint on the edge); border edges: a
/// half-block.
std::vector<std::array<double, 3>> block_weights(const std::vector<Vec3>& pos, const Forest& adj) {
  std::vector<std::array<double, 3>> w(adj.num_base_triangles());
  for (std::uint32_t t = 0; t < w.size(); ++t) {
    const auto& x = adj.tri(t);
    for (int i = 0; i < 3; ++i) {
      const Vec3 &c = pos[x.v[i]], &a = pos[x.v[(i + 1) % 3]], &b = pos[x.v[(i + 2) % 3]];
      const Vec3 m = 0.5 * (a + b);
      double q = std::min(min_angle(m, c, a), min_angle(m, b, c));
      if (x.nbr[i] != kNone) {
        const auto& y = adj.tri(x.nbr[i]);
        const Vec3& d = pos[y.v[edge_to(adj, x.nbr[i], t)]];
        q = std::min({q, min_angle(m, d, b), min_angle(m, a, d)});
      }
      w[t][i] = std::min(q, kGoodAngle) + (q >= kSliverAngle ? kGoodBonus : 0.0);
    }
  }
  return w;
}

/// Local improvement of a block partition (part[t] = partner, or t for a border half-block) by
/// alternating chains of at most `depth` pair exchanges that raise the total block weight, started
/// from the blocks below the saturated weight — the completion by augmenting paths ignores
/// shapes; this restores good pairs. On a 1300-triangle sphere base it leaves 73 blocks with a
/// child below 20° where the exact maximum-weight perfect matching (Boost, O(n³), 5 s) has 65.
class Improver {
 public:
  Improver(const Forest& adj, const std::vector<std::array<double, 3>>& w,
           std::vector<std::uint32_t>& part, int depth, StageTicker* ticker)
      : ticker_(ticker),
        depth_(depth),
        reach_(2 * depth + 2),
        adj_(adj),
        w_(w),
        part_(part),
        in_chain_(part.size(), 0),
        failed_at_(part.size(), 0),
        dirty_(part.size(), 0) {}

  /// Passes in index order until one improves nothing. A block whose search failed is searched
  /// again only when a pair within its reach has changed since: the search reads the
  /// partition there only, so skipping it gives the same result as searching, at a fraction of
  /// the cost on large bases (frog: 285k triangles, most of them never good).
  void run() {
    for (int pass = 0; pass < 50; ++pass) {
      bool improved = false;
      for (std::uint32_t x = 0; x < part_.size(); ++x) {
        if (ticker_) ticker_->tick();
        if (!(weight_of(x) < kGoodAngle + kGoodBonus)) continue;
        if (failed_at_[x] != 0 && dirty_[x] <= failed_at_[x]) continue;
        const std::uint32_t now = clock_;
        if (improve(x)) {
          improved = true;
          failed_at_[x] = 0;
        } else {
          failed_at_[x] = now;
        }
      }
      if (!improved) break;
    }
  }

 private:
  /// Longest chain (pair exchanges) searched, and the dual-graph distance within which a search
  /// from x reads the partition: the chain's k-th vertex lies within 1 + 2k of x and reads its
  /// neighbours' partners (k < depth).
  /// Good blocks that are not saturated search chains of at most kGoodDepth exchanges; only the
  /// blocks with a child below 20° search `depth` (issue 14: half the matching time on a
  /// 15k-triangle MRI base, 0.75 → 0.38 s, with as many sub-20° triangles after refinement:
  /// CT head 20k 0.92 → 0.75 %, MRI 1.87 → 1.89 %, gyroid@128 0.01 → 0.03 %).
  static constexpr int kGoodDepth = 6;
  StageTicker* ticker_;
  const int depth_, reach_;
  static constexpr double kEps = 1e-9;
  using Ops = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

  double pair_w(std::uint32_t t, std::uint32_t u) const { return w_[t][edge_to(adj_, t, u)]; }
  double weight_of(std::uint32_t t) const { return part_[t] == t ? single_w(t) : pair_w(t, part_[t]); }
  bool border(std::uint32_t t) const {
    const auto& n = adj_.tri(t).nbr;
    return n[0] == kNone || n[1] == kNone || n[2] == kNone;
  }
  double single_w(std::uint32_t t) const {
    double best = -1;
    for (int i = 0; i < 3; ++i)
      if (adj_.tri(t).nbr[i] == kNone) best = std::max(best, w_[t][i]);
    return best;
  }
  void apply(const Ops& ops) {
    changed_.clear();
    for (const auto& [a, b] : ops) changed_.insert(changed_.end(), {a, b, part_[a], part_[b]});
    for (const auto& [a, b] : ops) part_[a] = b, part_[b] = a;
    mark_dirty();
  }

  /// Stamps every triangle within reach of a changed one with the new clock.
  void mark_dirty() {
    ++clock_;
    frontier_.clear();
    for (const std::uint32_t t : changed_)
      if (dirty_[t] != clock_) dirty_[t] = clock_, frontier_.push_back(t);
    for (int r = 0; r < reach_ && !frontier_.empty(); ++r) {
      next_.clear();
      for (const std::uint32_t t : frontier_)
        for (const std::uint32_t u : adj_.tri(t).nbr)
          if (u != kNone && dirty_[u] != clock_) dirty_[u] = clock_, next_.push_back(u);
      frontier_.swap(next_);
    }
  }

  bool improve(std::uint32_t x) {
    cur_depth_ = weight_of(x) >= kGoodBonus ? std::min(depth_, kGoodDepth) : depth_;
    Ops ops;
    const std::uint32_t y = part_[x];
    bool done;
    in_chain_[x] = in_chain_[y] = 1;
    if (y == x) done = extend(x, kNone, -single_w(x), 0, ops);
    else done = extend(y, x, -pair_w(x, y), 0, ops);
    in_chain_[x] = in_chain_[y] = 0;
    return done;
  }

  /// `y` needs a partner; `pending` (or kNone) must end paired with the chain's last vertex or
  /// become a half-block. Applies the first chain with positive gain.
  bool extend(std::uint32_t y, std::uint32_t pending, double gain, int depth, Ops& ops) {
    auto finish = [&](double g, std::size_t mark) {
      if (pending != kNone) {
        if (!border(pending)) {
          ops.resize(mark);
          return false;
        }
        g += single_w(pending);
        ops.push_back({pending, pending});
      }
      if (g > kEps) {
        apply(ops);
        return true;
      }
      ops.resize(mark);
      return false;
    };
    const std::size_t mark = ops.size();
    if (border(y) && !(pending == kNone && depth == 0)) {
      ops.push_back({y, y});
      if (finish(gain + single_w(y), mark)) return true;
    }
    if (pending != kNone && depth > 0 && edge_to(adj_, y, pending) >= 0) {
      ops.push_back({y, pending});
      if (gain + pair_w(y, pending) > kEps) {
        apply(ops);
        return true;
      }
      ops.resize(mark);
    }
    if (depth >= cur_depth_) return false;
    for (const std::uint32_t z : adj_.tri(y).nbr) {
      if (z == kNone || in_chain_[z] || z == pending) continue;
      const std::uint32_t z2 = part_[z];
      ops.push_back({y, z});
      if (z2 == z) {
        if (finish(gain + pair_w(y, z) - single_w(z), mark)) return true;
        continue;
      }
      if (in_chain_[z2] || z2 == pending) {
        ops.resize(mark);
        continue;
      }
      in_chain_[z] = in_chain_[z2] = 1;
      const bool ok = extend(z2, pending, gain + pair_w(y, z) - pair_w(z, z2), depth + 1, ops);
      in_chain_[z] = in_chain_[z2] = 0;
      if (ok) return true;
      ops.resize(mark);
    }
    return false;
  }

  const Forest& adj_;
  const std::vector<std::array<double, 3>>& w_;
  std::vector<std::uint32_t>& part_;
  std::vector<std::uint8_t> in_chain_;
  std::vector<std::uint32_t> failed_at_;  ///< clock of the last failed search (0: none since)
  std::vector<std::uint32_t> dirty_;      ///< clock of the last change within reach
  std::uint32_t clock_ = 1;               ///< 1 + chains applied
  int cur_depth_ = 0;
  std::vector<std::uint32_t> changed_, frontier_, next_;
};


using MatchGraph = boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS>;
using MatchVertex = boost::graph_traits<MatchGraph>::vertex_descriptor;

/// Edmonds' augmenting paths (Boost) on g from the matching `mate` until none is left; `mate`
/// receives the result. Returns the number of augmentations. `ticker` (optional) is polled after
/// every augmentation (one search over the graph: milliseconds on large bases).
std::size_t augment(const MatchGraph& g, std::vector<MatchVertex>& mate,
                    StageTicker* ticker = nullptr) {
  using IndexMap = boost::property_map<MatchGraph, boost::vertex_index_t>::type;
  using MateMap = boost::iterator_property_map<std::vector<MatchVertex>::iterator, IndexMap>;
  const IndexMap index = boost::get(boost::vertex_index, g);
  MateMap mate_map(mate.begin(), index);
  boost::edmonds_augmenting_path_finder<MatchGraph, MateMap, IndexMap> augmentor(g, mate_map,
                                                                                 index);
  std::size_t found = 0;
  while (augmentor.augment_matching()) {
    ++found;
    if (ticker) ticker->tick(1024);
  }
  augmentor.get_current_matching(mate_map);
  return found;
}

/// The doubled dual graph without storing it: vertex t < F is base triangle t, t + F its mirror.
/// Edge weights: block_weights from the smaller triangle's side; t–t' carries t's best border
/// weight. good_only keeps the edges of good blocks (weight ≥ kGoodBonus).
struct DoubledDual {
  const Forest& adj;
  const std::vector<std::array<double, 3>>& w;
  std::uint32_t F;
  std::vector<double> border_w;  ///< per triangle: best border half-block weight, or -1

  template <class Fn>
  void for_each_neighbour(std::uint32_t v, bool good_only, Fn&& fn) const {
    const std::uint32_t t = v < F ? v : v - F, off = v < F ? 0 : F;
    const auto& x = adj.tri(t);
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t u = x.nbr[i];
      if (u == kNone) continue;
      const double weight = t < u ? w[t][i] : w[u][edge_to(adj, u, t)];
      if (!good_only || weight >= kGoodBonus) fn(u + off);
    }
    if (border_w[t] >= 0 && (!good_only || border_w[t] >= kGoodBonus)) fn(v < F ? v + F : v - F);
  }
};

/// Augments `mate` inside balls of graph radius `radius` around every unmatched vertex, in index
/// order: the ball is closed under the matching, so Edmonds' augmenting paths in its induced
/// subgraph are augmenting paths of the whole graph. Cost ~ (unmatched vertices) × (ball size).
std::size_t augment_locally(const DoubledDual& d, bool good_only, int radius,
                            std::vector<MatchVertex>& mate, StageTicker* ticker) {
  const MatchVertex null = boost::graph_traits<MatchGraph>::null_vertex();
  std::vector<std::int32_t> local(mate.size(), -1);
  std::vector<std::uint32_t> ball, frontier, next;
  std::vector<MatchVertex> lmate;
  std::size_t augmentations = 0;
  for (std::uint32_t s = 0; s < mate.size(); ++s) {
    if (mate[s] != null) continue;
    // One ball search and an Edmonds run on the ball: weighed by the ball's size (radius²).
    if (ticker) ticker->tick(static_cast<std::uint32_t>(8 * radius * radius));
    ball.assign(1, s);
    local[s] = 0;
    frontier.assign(1, s);
    std::size_t unmatched = 1;
    auto visit = [&](std::uint32_t u) {
      if (local[u] >= 0) return;
      local[u] = static_cast<std::int32_t>(ball.size());
      ball.push_back(u);
      next.push_back(u);
      unmatched += mate[u] == null ? 1 : 0;
    };
    for (int r = 0; r < radius && !frontier.empty(); ++r) {
      next.clear();
      for (const std::uint32_t v : frontier) d.for_each_neighbour(v, good_only, visit);
      frontier.swap(next);
    }
    for (std::size_t i = 0; i < ball.size(); ++i) {  // close under the matching
      const MatchVertex m = mate[ball[i]];
      if (m != null && local[m] < 0) {
        local[m] = static_cast<std::int32_t>(ball.size());
        ball.push_back(static_cast<std::uint32_t>(m));
      }
    }
    if (unmatched >= 2) {
      MatchGraph g(ball.size());
      for (std::size_t i = 0; i < ball.size(); ++i)
        d.for_each_neighbour(ball[i], good_only, [&](std::uint32_t u) {
          if (local[u] > static_cast<std::int32_t>(i)) boost::add_edge(i, local[u], g);
        });
      lmate.resize(ball.size());
      for (std::size_t i = 0; i < ball.size(); ++i)
        lmate[i] = mate[ball[i]] == null ? null : static_cast<MatchVertex>(local[mate[ball[i]]]);
      const std::size_t found = augment(g, lmate);
      if (found > 0) {
        for (std::size_t i = 0; i < ball.size(); ++i)
          mate[ball[i]] = lmate[i] == null ? null : ball[lmate[i]];
        augmentations += found;
      }
    }
    for (const std::uint32_t v : ball) local[v] = -1;
  }
  return augmentations;
}

}  // namespace

Blocks match_blocks(const std::vector<Vec3>& pos,
                    const std::vector<std::array<std::uint32_t, 3>>& tris, std::size_t local_from,
                    StageTicker* ticker) {
  const std::uint32_t F = static_cast<std::uint32_t>(tris.size());
  const Forest adj(tris, static_cast<std::uint32_t>(pos.size()));
  Blocks out;
  if (adj.nonmanifold_edges() > 0) return out;
  const auto w = block_weights(pos, adj);
  DoubledDual dual{adj, w, F, std::vector<double>(F, -1.0)};
  struct Candidate {
    int score;         // edges that are the longest of their triangle (0..2)
    double weight;     // block_weights
    std::uint32_t t, u;  // u = t + F for a border half-block
    int i;             // t's edge
  };
  std::vector<Candidate> cand;
  for (std::uint32_t t = 0; t < F; ++t) {
    const auto& x = adj.tri(t);
    const int lt = longest_edge(pos, x.v);
    for (int i = 0; i < 3; ++i)
      if (x.nbr[i] == kNone) dual.border_w[t] = std::max(dual.border_w[t], w[t][i]);
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t u = x.nbr[i];
      if (u == kNone) {
        cand.push_back({2 * (i == lt), w[t][i], t, t + F, i});
      } else if (t < u) {
        cand.push_back({(i == lt) + (longest_edge(pos, adj.tri(u).v) == edge_to(adj, u, t)),
                        w[t][i], t, u, i});
      }
    }
  }
  std::sort(cand.begin(), cand.end(), [](const Candidate& a, const Candidate& b) {
    if ((a.weight >= kGoodBonus) != (b.weight >= kGoodBonus)) return a.weight >= kGoodBonus;
    if (a.score != b.score) return a.score > b.score;
    if (a.weight != b.weight) return a.weight > b.weight;
    if (a.t != b.t) return a.t < b.t;
    return a.i < b.i;
  });

  const MatchVertex null = boost::graph_traits<MatchGraph>::null_vertex();
  std::vector<MatchVertex> mate(2 * static_cast<std::size_t>(F), null);
  for (const auto& c : cand) {
    if (c.weight < kGoodBonus || mate[c.t] != null || mate[c.u] != null) continue;
    mate[c.t] = c.u;
    mate[c.u] = c.t;
    if (c.u < F) {
      mate[c.t + F] = c.u + F;
      mate[c.u + F] = c.t + F;
    }
    ++out.greedy_pairs;
  }
  cand = {};
  // The doubled dual graph (or its good edges) for Boost, edges in a fixed order: per triangle,
  // its border edge to the mirror, then its edges to larger neighbours in both copies.
  auto whole_graph = [&](bool good_only) {
    MatchGraph g(2 * static_cast<std::size_t>(F));
    for (std::uint32_t t = 0; t < F; ++t) {
      const auto& x = adj.tri(t);
      if (dual.border_w[t] >= 0 && (!good_only || dual.border_w[t] >= kGoodBonus))
        boost::add_edge(t, t + F, g);
      for (int i = 0; i < 3; ++i) {
        const std::uint32_t u = x.nbr[i];
        if (u == kNone || u < t || (good_only && w[t][i] < kGoodBonus)) continue;
        boost::add_edge(t, u, g);
        boost::add_edge(t + F, u + F, g);
      }
    }
    return g;
  };
  auto augment_globally = [&](bool good_only) {
    out.augmentations += augment(whole_graph(good_only), mate, ticker);
  };
  auto unmatched = [&] { return std::count(mate.begin(), mate.end(), null); };
  // Maximum matching of good blocks first, then completed to a perfect matching of all. Short
  // augmenting paths are found inside balls first (each global search scans the whole graph: on
  // a 15k-triangle base 4,200 global augmentations took 1.4 s, issue 14); below `local_from`
  // triangles a global search then finds the long paths, so the good blocks still form a
  // maximum matching; above it the good blocks keep the local (maximal) result, and balls up to
  // radius 160 leave only the longest paths to the global search (the frog's 75k base: 306
  // global searches of ~20 ms each with radii up to 24).
  for (const bool good_only : {true, false}) {
    for (const int radius : {3, 8, 24, 64, 160}) {
      // Beyond radius 24 only on large bases, in the phase a global search finishes, and while
      // many vertices are left: a ball of radius 160 that finds nothing costs more than a
      // global search (~20 ms) — the embryo's 525k base has 2 left after radius 24 and spent
      // 9 s in the big balls; the frog's 75k base had 306 and they find all but one.
      if (unmatched() == 0 ||
          (radius > 24 && (F < local_from || good_only || unmatched() <= 32)))
        break;
      const std::size_t found = augment_locally(dual, good_only, radius, mate, ticker);
      out.augmentations += found;
      out.local_augmentations += found;
    }
    if (unmatched() > 0 && (!good_only || F < local_from)) augment_globally(good_only);
  }
  out.perfect = std::none_of(mate.begin(), mate.end(), [&](MatchVertex v) { return v == null; });
  if (!out.perfect) return out;

  // Copy 1 of the doubled matching: pairs, and border triangles matched to their mirror.
  std::vector<std::uint32_t> part(F);
  for (std::uint32_t t = 0; t < F; ++t)
    part[t] = mate[t] == t + F ? t : static_cast<std::uint32_t>(mate[t]);
  Improver(adj, w, part, F < local_from ? 10 : 6, ticker).run();

  out.labelled.resize(F);
  for (std::uint32_t t = 0; t < F; ++t) {
    const auto& x = adj.tri(t);
    int i = -1;
    if (part[t] == t) {  // half-block: the border edge with the best children
      for (int k = 0; k < 3; ++k)
        if (x.nbr[k] == kNone && (i < 0 || w[t][k] > w[t][i])) i = k;
      ++out.border_half_blocks;
      ++out.blocks;
    } else {
      i = edge_to(adj, t, part[t]);
      if (t < part[t]) ++out.blocks;
    }
    if (i < 0) {  // never expected: the matching only uses dual edges
      out.perfect = false;
      out.labelled.clear();
      return out;
    }
    out.labelled[t] = rotate_to(x.v, i);
  }
  return out;
}

std::vector<std::array<std::uint32_t, 3>> quad_blocks(
    const Surface& s, const std::vector<std::array<std::uint32_t, 3>>& tris,
    std::vector<Vec3>& pos, std::vector<std::uint32_t>& anchor, std::vector<std::uint8_t>& border) {
  PathWorkspace ws = PathWorkspace::sparse();
  // Edge midpoints, in (min, max) order; an edge with one triangle is a border edge when both
  // its ends are border vertices.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const auto& t : tris)
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = t[(i + 1) % 3], b = t[(i + 2) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
  auto add_vertex = [&](const Placed& p, bool on_border) {
    pos.push_back(p.position);
    anchor.push_back(p.anchor);
    border.push_back(on_border ? 1 : 0);
    return static_cast<std::uint32_t>(pos.size() - 1);
  };
  for (const auto& [e, count] : uses) {
    EdgeInput in;
    in.p1 = pos[e.first];
    in.p2 = pos[e.second];
    in.a1 = anchor[e.first];
    in.a2 = anchor[e.second];
    in.border = count == 1 && border[e.first] && border[e.second];
    mid[e] = add_vertex(place_vertex(s, in, ws), in.border);
  }
  auto m = [&](std::uint32_t a, std::uint32_t b) { return mid.at({std::min(a, b), std::max(a, b)}); };
  std::vector<std::array<std::uint32_t, 3>> out;
  out.reserve(6 * tris.size());
  for (const auto& t : tris) {
    // Centroid: two thirds along the geodesic from a corner to the opposite edge's midpoint.
    const std::uint32_t mbc = m(t[1], t[2]);
    EdgeInput in;
    in.p1 = pos[t[0]];
    in.p2 = pos[mbc];
    in.a1 = anchor[t[0]];
    in.a2 = anchor[mbc];
    in.fraction = 2.0 / 3.0;
    const std::uint32_t g = add_vertex(place_vertex(s, in, ws), false);
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = t[i], mab = m(t[i], t[(i + 1) % 3]), mca = m(t[(i + 2) % 3], t[i]);
      // Quad (a, mab, g, mca), counter-clockwise; diagonal (a, g) or (mab, mca).
      const double q_ag = std::min(radius_ratio(pos[mab], pos[g], pos[a]),
                                   radius_ratio(pos[mca], pos[a], pos[g]));
      const double q_mm = std::min(radius_ratio(pos[a], pos[mab], pos[mca]),
                                   radius_ratio(pos[g], pos[mca], pos[mab]));
      if (q_ag >= q_mm) {
        out.push_back({mab, g, a});
        out.push_back({mca, a, g});
      } else {
        out.push_back({a, mab, mca});
        out.push_back({g, mca, mab});
      }
    }
  }
  return out;
}

}  // namespace adamesh::detail
