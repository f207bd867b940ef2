// Separation of intersecting triangles (issue 13, docs/QUALITY.md "Separation"): what the
// untangling leaves on noisy scans is shallow — on the CT head's default mesh the median pair
// pokes 3.6 % of its longest edge through the other. A vertex of one triangle on the wrong side
// of the other's plane goes across that plane, along its normal, to 0.001 voxel past it: when
// all three vertices of a triangle lie strictly on one side of the other's plane, the two meet
// at most in what they share. For each pair, four candidate moves (the vertices of either
// triangle on the minority side of the other's plane, to either side): the cheapest (smallest
// largest displacement) whose vertices may move — not fixed, not on the mesh's boundary, in the
// box, within `max_move` of where they started — and that keeps every triangle around them
// unflipped and at or above min(its smallest angle, 20°). A round plans the pairs in order (a
// vertex moves once per round; pairs already separated by an earlier move are skipped), then
// counts again the pairs around the moved vertices: the moves that made a new pair go back,
// until none is new, and that option is not tried again for its pair (the next round tries
// the next cheapest); a round that neither removes a pair nor sends a move back ends it (at
// most `rounds`). Serial, in pair order, on exact counts: identical for any thread count.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <numbers>
#include <optional>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/improve.h"
#include "adamesh/metrics.h"
#include "remesh/geometry.h"

namespace adamesh {

namespace {

using Tri = std::array<std::uint32_t, 3>;
using PairList = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

using detail::smallest_angle;

class Separator {
 public:
  Separator(Mesh& mesh, const std::vector<std::uint8_t>& fixed, const SeparateOptions& o,
            const ExecutionContext& ctx)
      : mesh_(mesh), o_(o), bounds_(o.box, o.faces), ctx_(ctx), nv_(mesh.num_vertices()),
        nt_(mesh.num_triangles()) {
    p_.resize(nv_);
    for (std::size_t v = 0; v < nv_; ++v) p_[v] = mesh.vertex(v);
    start_ = p_;
    inc_off_.assign(nv_ + 1, 0);
    for (std::size_t t = 0; t < nt_; ++t)
      for (auto v : tri(t)) ++inc_off_[v + 1];
    for (std::size_t v = 0; v < nv_; ++v) inc_off_[v + 1] += inc_off_[v];
    inc_.resize(inc_off_.back());
    {
      std::vector<std::uint32_t> fill(inc_off_.begin(), inc_off_.end() - 1);
      for (std::size_t t = 0; t < nt_; ++t)
        for (auto v : tri(t)) inc_[fill[v]++] = static_cast<std::uint32_t>(t);
    }
    // Vertices on an edge not shared by exactly two triangles (the mesh's boundary,
    // non-manifold edges) and fixed ones stay.
    stays_.assign(nv_, 0);
    for (std::size_t v = 0; v < std::min(nv_, fixed.size()); ++v) stays_[v] = fixed[v];
    std::vector<std::uint64_t> keys;
    keys.reserve(3 * nt_);
    for (std::size_t t = 0; t < nt_; ++t) {
      const Tri c = tri(t);
      for (int k = 0; k < 3; ++k) keys.push_back(edge_key(c[k], c[(k + 1) % 3]));
    }
    std::sort(keys.begin(), keys.end());
    for (std::size_t i = 0; i < keys.size();) {
      std::size_t j = i;
      while (j < keys.size() && keys[j] == keys[i]) ++j;
      if (j - i != 2) stays_[keys[i] >> 32] = stays_[keys[i] & 0xffffffffu] = 1;
      i = j;
    }
    reach_ = o.max_move * o.voxel;
    margin_ = 1e-3 * o.voxel;
    min_angle_ = o.min_angle_deg * std::numbers::pi / 180;
    claimed_.assign(nv_, 0);
    involved_.assign(nt_, 0);
    slot_.assign(nv_, -1);
  }

  SeparateStats run() {
    SeparateStats st;
    {
      IntersectionReport r = self_intersections(mesh_, nt_ * nt_, ctx_);
      if (r.pairs < 0) return st;  // not measured (piles of triangles)
      pairs_ = std::move(r.first_pairs);
    }
    st.intersections_before = pairs_.size();
    for (int r = 0; r < o_.rounds && !pairs_.empty(); ++r)
      if (!run_round(st)) break;
    st.intersections_after = pairs_.size();
    for (std::size_t v = 0; v < nv_; ++v) {
      const double d = distance(p_[v], start_[v]);
      if (d > 0) ++st.moved;
      st.max_move = std::max(st.max_move, d);
    }
    if (st.moved > 0) mesh_.normals.clear();
    return st;
  }

 private:
  Mesh& mesh_;
  SeparateOptions o_;
  detail::VolumeBounds bounds_;
  const ExecutionContext& ctx_;
  std::size_t nv_, nt_;
  std::vector<Vec3> p_, start_;
  std::vector<std::uint32_t> inc_off_, inc_;
  std::vector<std::uint8_t> stays_, claimed_, involved_;
  std::vector<std::int32_t> slot_;  // vertex -> its group this round (-1: not moved)
  double reach_ = 0, margin_ = 0, min_angle_ = 0;
  PairList pairs_;
  // This round's moves: (vertex, where it was), and per move its group (one pair's push).
  std::vector<std::pair<std::uint32_t, Vec3>> moves_;
  std::vector<std::uint32_t> group_of_move_;
  std::uint32_t groups_ = 0;
  // Per group of this round: its pair and option (which triangle moves, to which side); the
  // options whose moves went back are not tried again for that pair.
  std::vector<std::tuple<std::uint32_t, std::uint32_t, int>> group_option_;
  std::set<std::tuple<std::uint32_t, std::uint32_t, int>> rejected_;

  static std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
    return a < b ? (std::uint64_t{a} << 32) | b : (std::uint64_t{b} << 32) | a;
  }
  Tri tri(std::size_t t) const {
    return Tri{mesh_.triangles[3 * t], mesh_.triangles[3 * t + 1], mesh_.triangles[3 * t + 2]};
  }
  void set(std::uint32_t v, const Vec3& q) {
    p_[v] = q;
    for (int k = 0; k < 3; ++k) mesh_.positions[3 * v + k] = static_cast<float>(q[k]);
  }
  bool may_move(std::uint32_t v, const Vec3& q) const {
    return !stays_[v] && !claimed_[v] && bounds_.contains(q) && distance(q, start_[v]) <= reach_;
  }
  /// The triangles around v keep min(their smallest angle, the floor) and their orientation
  /// with the current positions p_ against `ref` (the positions before the move).
  bool ring_ok(std::uint32_t v, const std::vector<std::pair<std::uint32_t, Vec3>>& ref) const {
    for (std::uint32_t i = inc_off_[v]; i < inc_off_[v + 1]; ++i) {
      const Tri c = tri(inc_[i]);
      Vec3 x[3] = {p_[c[0]], p_[c[1]], p_[c[2]]};
      for (int k = 0; k < 3; ++k)
        for (const auto& [w, q] : ref)
          if (c[k] == w) x[k] = q;
      const double before = smallest_angle(x[0], x[1], x[2]);
      const double after = smallest_angle(p_[c[0]], p_[c[1]], p_[c[2]]);
      if (after < min_angle_ && after < before) return false;
      const Vec3 n0 = cross(x[1] - x[0], x[2] - x[0]);
      const Vec3 n1 = cross(p_[c[1]] - p_[c[0]], p_[c[2]] - p_[c[0]]);
      if (dot(n0, n1) <= 0) return false;
    }
    return true;
  }
  /// Makes the moves `to` (vertex, new position) as one group when every ring keeps its shape;
  /// else leaves everything where it was. Returns whether they were made.
  bool try_group(const std::vector<std::pair<std::uint32_t, Vec3>>& to) {
    std::vector<std::pair<std::uint32_t, Vec3>> was;
    was.reserve(to.size());
    for (const auto& [v, q] : to) {
      was.push_back({v, p_[v]});
      set(v, q);
    }
    bool ok = true;
    for (const auto& [v, q] : to)
      if (!ring_ok(v, was)) {
        ok = false;
        break;
      }
    if (!ok) {
      for (auto it = was.rbegin(); it != was.rend(); ++it) set(it->first, it->second);
      return false;
    }
    for (const auto& [v, q] : was) {
      claimed_[v] = 1;
      moves_.push_back({v, q});
      group_of_move_.push_back(groups_);
    }
    ++groups_;
    return true;
  }

  /// One round: plan every pair, count again, send back the groups that made new pairs. False
  /// when the round removed no pair (or could not count).
  bool run_round(SeparateStats& st) {
    ctx_.check_cancelled();
    moves_.clear();
    group_of_move_.clear();
    group_option_.clear();
    groups_ = 0;
    for (const auto& [s, t] : pairs_) plan_push(s, t);
    for (const auto& mv : moves_) claimed_[mv.first] = 0;
    if (moves_.empty()) return false;
    std::fill(involved_.begin(), involved_.end(), 0);
    for (std::size_t i = 0; i < moves_.size(); ++i) {
      const std::uint32_t v = moves_[i].first;
      slot_[v] = static_cast<std::int32_t>(i);
      for (std::uint32_t k = inc_off_[v]; k < inc_off_[v + 1]; ++k) involved_[inc_[k]] = 1;
    }
    auto clear_slots = [&] {
      for (const auto& mv : moves_) slot_[mv.first] = -1;
    };
    std::optional<PairList> near = intersecting_pairs_involving(mesh_, involved_, ctx_);
    if (!near) {
      for (auto it = moves_.rbegin(); it != moves_.rend(); ++it) set(it->first, it->second);
      clear_slots();
      return false;
    }
    PairList now = pairs_after_change(pairs_, involved_, *near);
    std::vector<std::uint8_t> back(groups_, 0);
    for (int iter = 0; iter < 32; ++iter) {
      PairList added;
      std::set_difference(now.begin(), now.end(), pairs_.begin(), pairs_.end(),
                          std::back_inserter(added));
      std::vector<std::uint32_t> groups;
      for (const auto& pr : added)
        for (auto x : {pr.first, pr.second})
          for (auto v : tri(x))
            if (slot_[v] >= 0 && !back[group_of_move_[slot_[v]]])
              groups.push_back(group_of_move_[slot_[v]]);
      if (groups.empty()) break;
      for (auto g : groups) {
        back[g] = 1;
        rejected_.insert(group_option_[g]);
      }
      std::fill(involved_.begin(), involved_.end(), 0);
      for (std::size_t i = moves_.size(); i-- > 0;) {
        if (!back[group_of_move_[i]] || !(p_[moves_[i].first] != moves_[i].second)) continue;
        const std::uint32_t v = moves_[i].first;
        set(v, moves_[i].second);
        ++st.undone;
        for (std::uint32_t k = inc_off_[v]; k < inc_off_[v + 1]; ++k) involved_[inc_[k]] = 1;
      }
      const std::optional<PairList> again = intersecting_pairs_involving(mesh_, involved_, ctx_);
      if (!again) break;
      now = pairs_after_change(now, involved_, *again);
    }
    for (std::size_t i = 0; i < moves_.size(); ++i) st.moves += !back[group_of_move_[i]];
    clear_slots();
    // Undone pushes get their next option in the next round.
    const bool progress = now.size() < pairs_.size() ||
                          std::find(back.begin(), back.end(), 1) != back.end();
    pairs_.swap(now);
    return progress;
  }

  /// A push separating s and t (see the file comment); false when none may be made.
  bool plan_push(std::uint32_t s, std::uint32_t t) {
    struct Option {
      double cost = 0;
      int id = 0;
      std::vector<std::pair<std::uint32_t, Vec3>> to;
    };
    std::vector<Option> options;
    for (int which = 0; which < 2; ++which) {
      const Tri a = tri(which ? t : s), b = tri(which ? s : t);
      const Vec3 nb = cross(p_[b[1]] - p_[b[0]], p_[b[2]] - p_[b[0]]);
      const double len = norm(nb);
      if (!(len > 0)) continue;
      const Vec3 n = (1.0 / len) * nb;
      for (int side : {1, -1}) {
        Option opt;
        opt.id = 2 * which + (side > 0 ? 0 : 1);
        bool ok = true, none = true;
        for (int k = 0; k < 3 && ok; ++k) {
          if (a[k] == b[0] || a[k] == b[1] || a[k] == b[2]) continue;
          const double d = dot(p_[a[k]] - p_[b[0]], n);
          if (side * d >= margin_) continue;
          none = false;
          const Vec3 q = p_[a[k]] + (side * margin_ - d) * n;
          if (!may_move(a[k], q)) {
            ok = false;
            break;
          }
          opt.cost = std::max(opt.cost, std::abs(side * margin_ - d));
          opt.to.push_back({a[k], q});
        }
        if (none) return false;  // already apart (an earlier move of this round)
        if (ok && !rejected_.count({s, t, opt.id})) options.push_back(std::move(opt));
      }
    }
    std::stable_sort(options.begin(), options.end(),
                     [](const Option& x, const Option& y) { return x.cost < y.cost; });
    for (const Option& opt : options)
      if (try_group(opt.to)) {
        group_option_.push_back({s, t, opt.id});
        return true;
      }
    return false;
  }
};

}  // namespace

SeparateStats separate_crossings(Mesh& mesh, const std::vector<std::uint8_t>& fixed,
                                 const SeparateOptions& o, const ExecutionContext& context) {
  if (mesh.num_triangles() == 0) return {};
  if (!(o.voxel > 0) || !std::isfinite(o.voxel) || !(o.max_move >= 0))
    fail(Status::usage, "separate_crossings: voxel must be positive and max_move not negative");
  return Separator(mesh, fixed, o, context).run();
}

}  // namespace adamesh
