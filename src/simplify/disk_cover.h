// Internal: the geodesic disk covering C_G (ALGORITHM.md 2.4) as an incremental state machine,
// so that the Voronoi repair loop (2.5) can halve disks and grow new ones locally.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "adamesh/simplify.h"
#include "graph/shortest_paths.h"

namespace adamesh::detail {

/// True when adding surfel u to the disk `in_disk` keeps it a topological disk (the exact,
/// local event test of ALGORITHM.md 2.4): on u's polygon the edges whose opposite surfel is in
/// the disk and the nodes whose fan has a disk surfel other than u must form one path that
/// contains an edge and is not the whole polygon boundary.
template <class InDisk>
bool keeps_disk(const SurfelComplex& sc, std::uint32_t u, InDisk&& in_disk) {
  const auto nodes = sc.nodes_of(u);
  const auto opp = sc.opposites_of(u);
  const std::size_t k = nodes.size();
  bool mark[2 * 16];
  bool any_edge = false;
  std::size_t marked = 0;
  for (std::size_t e = 0; e < k; ++e) {
    const bool em = opp[e] >= 0 && in_disk(static_cast<std::uint32_t>(opp[e]));
    mark[2 * e + 1] = em;
    any_edge |= em;
    bool nm = false;
    for (std::int32_t f : sc.node_fan[nodes[e]])
      if (f >= 0 && static_cast<std::uint32_t>(f) != u && in_disk(static_cast<std::uint32_t>(f)))
        nm = true;
    mark[2 * e] = nm;
    marked += em + nm;
  }
  const std::size_t m = 2 * k;
  if (marked == m || !any_edge) return false;  // closes the surface / touches at a corner only
  std::size_t runs = 0;
  for (std::size_t i = 0; i < m; ++i)
    if (mark[i] && !mark[(i + m - 1) % m]) ++runs;
  return runs == 1;
}

class DiskCover {
 public:
  static constexpr std::uint32_t kNil = 0xffffffffu;
  /// Voronoi repair may halve disks this many levels below the growth floor r_max/2^K.
  static constexpr int kRepairLevels = 2;
  static constexpr int kDeepestLevel = 40;

  DiskCover(const SurfelComplex& sc, const ConnectivityGraph& g, std::vector<std::uint8_t> active,
            double r_max, double r_min, SimplifyStats& stats);

  /// Makes every active vertex an A_0 candidate.
  void seed();
  /// Grows disks until every active vertex is covered (candidate heap empty).
  void run();
  /// Halves disk d (and cascades to keep the grading); false when d is already at the floor
  /// (repairs: kRepairLevels below r_max/2^K; grading cascades: kDeepestLevel).
  bool halve(std::uint32_t d, bool grading = false);
  void process_halvings();

  std::size_t num_disks() const { return centre_.size(); }
  std::uint32_t centre(std::uint32_t d) const { return centre_[d]; }
  double radius(std::uint32_t d) const { return radius_[d]; }
  int level(std::uint32_t d) const { return level_[d]; }
  bool covered(std::uint32_t v) const { return head_[v] != kNil; }
  bool active(std::uint32_t v) const { return (flags_[v] & kActive) != 0; }
  /// Disks covering v.
  template <class F>
  void for_each_cover(std::uint32_t v, F&& f) const {
    for (std::uint32_t l = head_[v]; l != kNil; l = link(l).next) f(link(l).disk);
  }
  /// Disks accepted since the last call.
  std::vector<std::uint32_t> take_new_disks();
  /// Called after every disk growth with the covered fraction of the active vertices.
  std::function<void(double)> on_progress;

 private:
  struct Grown {
    double radius;
    int level;
  };
  static constexpr float kInfF = 3.0e38f;
  static constexpr std::uint8_t kActive = 1, kCentre = 2;  // flags_ bits
  double radius_of(int level) const;
  double rlo(std::uint32_t v) const;
  Grown grow(std::uint32_t x, int level);
  /// Dijkstra from x to radius R tracking the topology of the growing ball: valid_[j − first]
  /// tells whether the ball of radius r_max/2^j (first ≤ j ≤ last) is a topological disk; caps_
  /// collects the grading limits of covered vertices. Returns the distance of the first other
  /// centre met (infinity if none).
  double explore(std::uint32_t x, double R, int first, int last);
  void accept(std::uint32_t x, const Grown& g);
  /// Candidate priority: smaller label, then finite dnear, then farther, then smaller id.
  bool before(std::uint32_t a, std::uint32_t b) const {
    if (label_[a] != label_[b]) return label_[a] < label_[b];
    const bool fa = dnear_[a] < kInfF, fb = dnear_[b] < kInfF;
    if (fa != fb) return fa;
    if (dnear_[a] != dnear_[b]) return dnear_[a] > dnear_[b];
    return a < b;
  }
  /// Inserts v into the candidate heap, or restores its place after its key changed.
  void push(std::uint32_t v);
  std::uint32_t pop();
  std::uint32_t sift_up(std::uint32_t i);
  void sift_down(std::uint32_t i);
  struct Link {
    std::uint32_t disk, next;
  };
  static constexpr unsigned kChunkBits = 14;  // links live in chunks of 2^14 (no regrowth copies)
  Link& link(std::uint32_t l) { return link_chunks_[l >> kChunkBits][l & ((1u << kChunkBits) - 1)]; }
  const Link& link(std::uint32_t l) const {
    return link_chunks_[l >> kChunkBits][l & ((1u << kChunkBits) - 1)];
  }
  void add_cover(std::uint32_t v, std::uint32_t d);
  void remove_cover(std::uint32_t v, std::uint32_t d);
  void queue_halving(std::uint32_t d);

  const SurfelComplex& sc_;
  const ConnectivityGraph& g_;
  std::vector<std::uint8_t> flags_;  ///< per vertex: kActive, kCentre
  double r_max_, r_min_;
  int max_level_;
  SimplifyStats& stats_;

  std::vector<std::int8_t> label_;
  std::vector<float> dnear_;
  std::vector<std::uint32_t> head_;  ///< per vertex: its first cover link, or kNil
  std::vector<std::unique_ptr<Link[]>> link_chunks_;
  std::uint32_t num_links_ = 0;
  std::uint32_t free_ = kNil;
  std::size_t covered_count_ = 0, active_count_ = 0;

  std::vector<std::uint32_t> centre_;
  std::vector<double> radius_;
  std::vector<std::int8_t> level_;
  std::vector<std::uint8_t> halving_queued_;
  std::vector<std::uint32_t> halving_;
  std::vector<std::uint32_t> new_disks_;

  // Candidate heap: uncovered vertices (covered ones are skipped when popped), each at most once,
  // ordered by before() on their current label and dnear.
  std::vector<std::uint32_t> heap_;
  ZeroedArray<std::uint32_t> slot_;  ///< per vertex: 1 + its index in heap_, or 0
  PathWorkspace ws_;
  std::vector<std::pair<double, double>> caps_;
  std::vector<std::uint8_t> valid_;
  std::vector<double> prefixes_;  ///< radii (settled distances) whose ball is a topological disk
};

}  // namespace adamesh::detail
