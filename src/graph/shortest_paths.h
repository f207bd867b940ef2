// Dijkstra and A* on the connectivity graph with a reusable workspace.
//
// Local searches (disks, geodesic midpoints) touch few vertices of a large graph, so the
// workspace never clears its O(N) arrays: a generation stamp marks which entries are valid.
// The heap is a lazy binary heap of (distance, vertex) — ties broken by vertex id, so every
// search is deterministic.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <new>
#include <utility>
#include <vector>

#include "adamesh/graph.h"

namespace adamesh::detail {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Array of n trivially copyable T, zero-filled by calloc. Large blocks come from fresh mappings,
/// so a page becomes resident only when first written: a local search in a large graph costs
/// resident memory for the pages it touches, not for the whole array.
template <class T>
class ZeroedArray {
 public:
  ZeroedArray() = default;
  explicit ZeroedArray(std::size_t n) : n_(n) {
    if (n == 0) return;
    p_ = static_cast<T*>(std::calloc(n, sizeof(T)));
    if (!p_) throw std::bad_alloc();
  }
  ZeroedArray(const ZeroedArray& o) : ZeroedArray(o.n_) {
    if (n_) std::memcpy(p_, o.p_, n_ * sizeof(T));
  }
  ZeroedArray(ZeroedArray&& o) noexcept : p_(std::exchange(o.p_, nullptr)), n_(std::exchange(o.n_, 0)) {}
  ZeroedArray& operator=(ZeroedArray o) noexcept {
    std::swap(p_, o.p_);
    std::swap(n_, o.n_);
    return *this;
  }
  ~ZeroedArray() { std::free(p_); }
  T& operator[](std::size_t i) noexcept { return p_[i]; }
  const T& operator[](std::size_t i) const noexcept { return p_[i]; }
  std::size_t size() const noexcept { return n_; }
  bool empty() const noexcept { return n_ == 0; }
  void clear_all() noexcept {
    if (n_) std::memset(static_cast<void*>(p_), 0, n_ * sizeof(T));
  }

 private:
  T* p_ = nullptr;
  std::size_t n_ = 0;
};

class PathWorkspace {
 public:
  /// Workspace for graphs of n vertices: 12 bytes per vertex, 16 with predecessors (needed by
  /// astar's path, and pred()). Resident only where searches have been (ZeroedArray).
  explicit PathWorkspace(std::size_t n, bool predecessors = true)
      : dist_(n), pred_(predecessors ? n : 0), stamp_(n), with_pred_(predecessors) {}

  /// A workspace without per-vertex arrays: the search state lives in a hash table sized to the
  /// largest search so far (24 bytes per reached vertex, load ≤ 1/2). For many local searches
  /// spread over a large graph, where the dense arrays would end up resident everywhere. Same
  /// results as the dense workspace, bit for bit; lookups cost a hash probe.
  static PathWorkspace sparse(bool predecessors = true) {
    PathWorkspace ws(0, predecessors);
    ws.sparse_ = true;
    ws.table_.resize(kFirstCapacity);
    ws.mask_ = kFirstCapacity - 1;
    return ws;
  }

  /// Starts a new search: every vertex becomes unseen in O(1).
  void begin() {
    if (++gen_ > kMaxGen) {  // wrapped: clear once every 2^31 searches
      stamp_.clear_all();
      for (auto& e : table_) e = Entry{};
      gen_ = 1;
    }
    heap_.clear();
    used_ = 0;
  }
  double dist(std::uint32_t v) const {
    if (sparse_) {
      const Entry* e = find(v);
      return e ? e->dist : kInf;
    }
    return seen(v) ? dist_[v] : kInf;
  }
  bool settled(std::uint32_t v) const {
    if (sparse_) {
      const Entry* e = find(v);
      return e && e->stamp == (gen_ << 1 | 1);
    }
    return stamp_[v] == (gen_ << 1 | 1);
  }
  std::uint32_t pred(std::uint32_t v) const {
    if (sparse_) {
      const Entry* e = find(v);
      return e ? e->pred : 0;
    }
    return pred_[v];
  }

  /// Lowers v's tentative distance (and remembers its predecessor); returns true if it improved.
  bool relax(std::uint32_t v, double d, std::uint32_t from, double key) {
    if (sparse_) {
      Entry& e = insert(v);
      if (e.stamp >> 1 == gen_ && e.dist <= d) return false;
      if (e.stamp >> 1 != gen_) e.stamp = gen_ << 1;
      e.dist = d;
      e.pred = from;
    } else {
      if (seen(v)) {
        if (dist_[v] <= d) return false;
      } else {
        stamp_[v] = gen_ << 1;
      }
      dist_[v] = d;
      if (with_pred_) pred_[v] = from;
    }
    heap_.push_back({key, v});
    std::push_heap(heap_.begin(), heap_.end(), Greater{});
    return true;
  }
  /// Pops the next unsettled vertex in (key, id) order and settles it; false when empty.
  bool pop(std::uint32_t& v) {
    while (!heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), Greater{});
      const auto e = heap_.back();
      heap_.pop_back();
      std::uint32_t& stamp = sparse_ ? find(e.second)->stamp : stamp_[e.second];
      if (stamp != gen_ << 1) continue;  // settled already (or not seen)
      stamp = gen_ << 1 | 1;
      v = e.second;
      return true;
    }
    return false;
  }
  /// Smallest key still in the heap (stale entries included), or infinity.
  double peek_key() const { return heap_.empty() ? kInf : heap_.front().first; }

 private:
  struct Greater {
    bool operator()(const std::pair<double, std::uint32_t>& a,
                    const std::pair<double, std::uint32_t>& b) const {
      return a > b;
    }
  };
  /// Sparse mode: open addressing, linear probing. Entries of older searches (stamp of another
  /// generation) count as free, so begin() clears nothing: within one search nothing is removed,
  /// hence a vertex's probe chain never crosses a free slot.
  struct Entry {
    std::uint32_t v = 0, stamp = 0;
    double dist = 0;
    std::uint32_t pred = 0;
  };
  static constexpr std::size_t kFirstCapacity = 1024;
  static std::size_t home(std::uint32_t v) {
    return static_cast<std::size_t>((std::uint64_t{v} * 0x9E3779B97F4A7C15ull) >> 32);
  }
  Entry* find(std::uint32_t v) const {
    for (std::size_t i = home(v) & mask_;; i = (i + 1) & mask_) {
      Entry& e = table_[i];
      if (e.stamp >> 1 != gen_) return nullptr;
      if (e.v == v) return &e;
    }
  }
  Entry& insert(std::uint32_t v) {
    if (Entry* e = find(v)) return *e;
    if (2 * (used_ + 1) > table_.size()) grow();
    std::size_t i = home(v) & mask_;
    while (table_[i].stamp >> 1 == gen_) i = (i + 1) & mask_;
    ++used_;
    table_[i] = Entry{v, 0, 0, 0};  // the caller stamps it
    return table_[i];
  }
  void grow() {
    std::vector<Entry> old(2 * table_.size());
    old.swap(table_);
    mask_ = table_.size() - 1;
    for (const Entry& e : old) {
      if (e.stamp >> 1 != gen_) continue;
      std::size_t i = home(e.v) & mask_;
      while (table_[i].stamp >> 1 == gen_) i = (i + 1) & mask_;
      table_[i] = e;
    }
  }
  static constexpr std::uint32_t kMaxGen = 0x7fffffffu;
  bool seen(std::uint32_t v) const { return stamp_[v] >> 1 == gen_; }
  ZeroedArray<double> dist_;  ///< valid where seen
  ZeroedArray<std::uint32_t> pred_;
  /// 2·generation while seen in the current search, 2·generation + 1 once settled.
  ZeroedArray<std::uint32_t> stamp_;
  bool with_pred_ = true;
  bool sparse_ = false;
  mutable std::vector<Entry> table_;
  std::size_t mask_ = 0, used_ = 0;
  std::vector<std::pair<double, std::uint32_t>> heap_;
  std::uint32_t gen_ = 0;
};

enum class Visit { expand, skip, stop };

/// Dijkstra from `source` over vertices with distance ≤ limit. visit(v, d) is called when v is
/// settled, in (distance, id) order; it returns expand (relax v's edges), skip (keep v settled
/// but don't expand it) or stop (end the search). `allowed(v)` filters vertices (e.g. one
/// component, or border vertices only).
template <class Visitor, class Allowed>
void dijkstra(const ConnectivityGraph& g, PathWorkspace& ws, std::uint32_t source, double limit,
              Visitor&& visit, Allowed&& allowed) {
  ws.begin();
  ws.relax(source, 0.0, source, 0.0);
  std::uint32_t v;
  while (ws.pop(v)) {
    const double d = ws.dist(v);
    if (d > limit) break;
    const Visit what = visit(v, d);
    if (what == Visit::stop) return;
    if (what == Visit::skip) continue;
    for (std::size_t k = g.row[v]; k < g.row[v + 1]; ++k) {
      const std::uint32_t u = g.neighbour(v, k);
      if (ws.settled(u) || !allowed(u)) continue;
      const double nd = d + g.edge_weight(v, k);
      if (nd <= limit) ws.relax(u, nd, v, nd);
    }
  }
}

template <class Visitor>
void dijkstra(const ConnectivityGraph& g, PathWorkspace& ws, std::uint32_t source, double limit,
              Visitor&& visit) {
  dijkstra(g, ws, source, limit, std::forward<Visitor>(visit), [](std::uint32_t) { return true; });
}

/// A* shortest path from source to target with the Euclidean distance to the target's c-vertex
/// as heuristic (admissible: no graph path is shorter than the straight segment). Returns the
/// path source..target (empty when unreachable under `allowed`) and its length in `length`.
template <class Allowed>
std::vector<std::uint32_t> astar(const ConnectivityGraph& g, const SurfelComplex& sc,
                                 PathWorkspace& ws, std::uint32_t source, std::uint32_t target,
                                 double& length, Allowed&& allowed) {
  const Vec3 t = sc.cvertex_position(target);
  // Weights are floats: shrink the heuristic a hair so rounding never makes it inadmissible.
  auto h = [&](std::uint32_t v) { return distance(sc.cvertex_position(v), t) * (1.0 - 1e-6); };
  ws.begin();
  ws.relax(source, 0.0, source, h(source));
  std::uint32_t v;
  length = kInf;
  while (ws.pop(v)) {
    const double d = ws.dist(v);
    if (v == target) {
      length = d;
      break;
    }
    for (std::size_t k = g.row[v]; k < g.row[v + 1]; ++k) {
      const std::uint32_t u = g.neighbour(v, k);
      if (ws.settled(u) || !allowed(u)) continue;
      const double nd = d + g.edge_weight(v, k);
      ws.relax(u, nd, v, nd + h(u));
    }
  }
  std::vector<std::uint32_t> path;
  if (length == kInf) return path;
  for (std::uint32_t x = target;; x = ws.pred(x)) {
    path.push_back(x);
    if (x == source) break;
  }
  std::reverse(path.begin(), path.end());
  return path;
}

}  // namespace adamesh::detail
