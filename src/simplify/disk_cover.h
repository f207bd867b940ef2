// Internal: the geodesic disk covering C_G (ALGORITHM.md 2.4) as an incremental state machine,
// so that the Voronoi repair loop (2.5) can halve disks and grow new ones locally.
#pragma once

#include <cstdint>
#include <functional>
#include <queue>
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
  bool active(std::uint32_t v) const { return active_[v] != 0; }
  /// Disks covering v.
  template <class F>
  void for_each_cover(std::uint32_t v, F&& f) const {
    for (std::uint32_t l = head_[v]; l != kNil; l = links_[l].next) f(links_[l].disk);
  }
  /// Disks accepted since the last call.
  std::vector<std::uint32_t> take_new_disks();
  /// Called every few hundred disks with the covered fraction of the active vertices.
  std::function<void(double)> on_progress;

 private:
  struct Grown {
    double radius;
    int level;
  };
  struct Candidate {
    std::int8_t label;
    float dnear;
    std::uint32_t v;
  };
  struct After {  // priority: smaller label, then finite dnear, then farther, then smaller id
    bool operator()(const Candidate& a, const Candidate& b) const {
      if (a.label != b.label) return a.label > b.label;
      const bool fa = a.dnear < kInfF, fb = b.dnear < kInfF;
      if (fa != fb) return fb;
      if (a.dnear != b.dnear) return a.dnear < b.dnear;
      return a.v > b.v;
    }
  };
  static constexpr float kInfF = 3.0e38f;

  double radius_of(int level) const;
  double rlo(std::uint32_t v) const;
  Grown grow(std::uint32_t x, int level);
  /// Dijkstra from x to radius R tracking the topology of the growing ball: valid_[j − first]
  /// tells whether the ball of radius r_max/2^j (first ≤ j ≤ last) is a topological disk; caps_
  /// collects the grading limits of covered vertices. Returns the distance of the first other
  /// centre met (infinity if none).
  double explore(std::uint32_t x, double R, int first, int last);
  void accept(std::uint32_t x, const Grown& g);
  void push(std::uint32_t v) { heap_.push({label_[v], dnear_[v], v}); }
  void add_cover(std::uint32_t v, std::uint32_t d);
  void remove_cover(std::uint32_t v, std::uint32_t d);
  void queue_halving(std::uint32_t d);

  const SurfelComplex& sc_;
  const ConnectivityGraph& g_;
  std::vector<std::uint8_t> active_;
  double r_max_, r_min_;
  int max_level_;
  SimplifyStats& stats_;

  std::vector<std::int8_t> label_;
  std::vector<float> dnear_;
  std::vector<std::int32_t> centre_disk_;
  std::vector<std::uint32_t> head_;
  struct Link {
    std::uint32_t disk, next;
  };
  std::vector<Link> links_;
  std::uint32_t free_ = kNil;
  std::size_t covered_count_ = 0, active_count_ = 0;

  std::vector<std::uint32_t> centre_;
  std::vector<double> radius_;
  std::vector<std::int8_t> level_;
  std::vector<std::uint8_t> halving_queued_;
  std::vector<std::uint32_t> halving_;
  std::vector<std::uint32_t> new_disks_;

  std::priority_queue<Candidate, std::vector<Candidate>, After> heap_;
  PathWorkspace ws_;
  std::vector<std::pair<double, double>> caps_;
  std::vector<std::uint8_t> valid_;
  std::vector<double> prefixes_;  ///< radii (settled distances) whose ball is a topological disk
};

}  // namespace adamesh::detail
