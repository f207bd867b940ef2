// Geodesic disk covering C_G of the connectivity graph (Peixoto & Velho 2002; ALGORITHM.md 2.4).
//
// Disks D(x, r) are Dijkstra balls on G. While a disk grows, every settled surfel passes the
// exact local event test (keeps_disk): the first failure at distance ρ is a topological event
// (boundary self-intersection or vanishing) and bounds the radius below ρ. A candidate x with
// label A_i gets the largest radius r_max/2^j (j ≥ i) that is below every event, below the
// distance to every existing centre (independence) and at most twice the smallest radius already
// covering any surfel it would cover (grading). Covering a surfel whose bigger disks exceed 2r
// halves those disks, which may uncover surfels (they become A_{j+1} candidates) and cascade.
// Accepting a disk relabels the uncovered surfels within 2r to A_j (the paper's A_i region).
//
// Candidates are taken by label (largest radius first), then farthest from the known centres
// among those near a centre (front propagation, spreading centres evenly), then by id.
#include "disk_cover.h"

#include <algorithm>
#include <cmath>

namespace adamesh::detail {

DiskCover::DiskCover(const SurfelComplex& sc, const ConnectivityGraph& g,
                     std::vector<std::uint8_t> active, double r_max, double r_min,
                     SimplifyStats& stats)
    : sc_(sc),
      g_(g),
      flags_(std::move(active)),
      r_max_(r_max),
      r_min_(r_min),
      stats_(stats),
      ws_(g.num_vertices(), /*predecessors=*/false) {
  max_level_ = r_max > r_min ? static_cast<int>(std::ceil(std::log2(r_max / r_min) - 1e-9)) : 0;
  max_level_ = std::clamp(max_level_, 0, 60);
  const std::size_t n = g.num_vertices();
  label_.assign(n, 0);
  dnear_.assign(n, kInfF);
  head_.assign(n, kNil);
  slot_ = ZeroedArray<std::uint32_t>(n);
  for (auto& f : flags_) f = f ? kActive : 0;
}

double DiskCover::radius_of(int level) const { return r_max_ / std::ldexp(1.0, level); }

double DiskCover::rlo(std::uint32_t v) const {
  double r = kInf;
  for_each_cover(v, [&](std::uint32_t d) { r = std::min(r, radius_[d]); });
  return r;
}

void DiskCover::seed() {
  active_count_ = 0;
  heap_.reserve(g_.num_vertices());
  for (std::uint32_t v = 0; v < g_.num_vertices(); ++v) {
    active_count_ += active(v);
    if (active(v) && !covered(v)) push(v);
  }
}

std::uint32_t DiskCover::sift_up(std::uint32_t i) {
  const std::uint32_t v = heap_[i];
  while (i > 0) {
    const std::uint32_t parent = (i - 1) / 2;
    if (!before(v, heap_[parent])) break;
    heap_[i] = heap_[parent];
    slot_[heap_[i]] = i + 1;
    i = parent;
  }
  heap_[i] = v;
  slot_[v] = i + 1;
  return i;
}

void DiskCover::sift_down(std::uint32_t i) {
  const std::uint32_t v = heap_[i];
  const auto size = static_cast<std::uint32_t>(heap_.size());
  for (;;) {
    std::uint32_t child = 2 * i + 1;
    if (child >= size) break;
    if (child + 1 < size && before(heap_[child + 1], heap_[child])) ++child;
    if (!before(heap_[child], v)) break;
    heap_[i] = heap_[child];
    slot_[heap_[i]] = i + 1;
    i = child;
  }
  heap_[i] = v;
  slot_[v] = i + 1;
}

void DiskCover::push(std::uint32_t v) {
  if (slot_[v] == 0) {
    heap_.push_back(v);
    sift_up(static_cast<std::uint32_t>(heap_.size() - 1));
  } else {
    sift_down(sift_up(slot_[v] - 1));
  }
}

std::uint32_t DiskCover::pop() {
  const std::uint32_t v = heap_.front();
  slot_[v] = 0;
  const std::uint32_t last = heap_.back();
  heap_.pop_back();
  if (!heap_.empty() && last != v) {
    heap_.front() = last;
    sift_down(0);
  }
  return v;
}

void DiskCover::add_cover(std::uint32_t v, std::uint32_t d) {
  std::uint32_t l;
  if (free_ != kNil) {
    l = free_;
    free_ = link(l).next;
  } else {
    l = num_links_++;
    if ((l >> kChunkBits) == link_chunks_.size())
      link_chunks_.push_back(std::make_unique<Link[]>(std::size_t{1} << kChunkBits));
  }
  if (head_[v] == kNil) ++covered_count_;
  link(l) = {d, head_[v]};
  head_[v] = l;
}

void DiskCover::remove_cover(std::uint32_t v, std::uint32_t d) {
  for (std::uint32_t* p = &head_[v]; *p != kNil; p = &link(*p).next) {
    if (link(*p).disk == d) {
      const std::uint32_t l = *p;
      *p = link(l).next;
      link(l).next = free_;
      free_ = l;
      if (head_[v] == kNil) --covered_count_;
      return;
    }
  }
}

void DiskCover::queue_halving(std::uint32_t d) {
  if (halving_queued_[d]) return;
  halving_queued_[d] = 1;
  halving_.push_back(d);
}

namespace {

/// Runs of disk members in the fan of node n (cyclic for a complete fan, a path on the border).
template <class InDisk>
int fan_runs(const SurfelComplex& sc, std::uint32_t n, InDisk&& in) {
  const auto& fan = sc.node_fan[n];
  bool m[4];
  bool complete = true;
  for (int q = 0; q < 4; ++q) {
    m[q] = fan[q] >= 0 && in(static_cast<std::uint32_t>(fan[q]));
    complete &= fan[q] >= 0;
  }
  int runs = 0;
  for (int q = 0; q < 4; ++q) {
    const int p = (q + 3) % 4;
    const bool prev = m[p] && (complete || q != 0);  // a border fan is a path starting at slot 0
    if (m[q] && !prev) ++runs;
  }
  if (!complete) {
    // Slots of absent voxels break the path: count runs of present members between gaps.
    runs = 0;
    bool in_run = false;
    for (int q = 0; q < 4; ++q) {
      const int slot = q;
      if (fan[slot] < 0 || !m[slot]) {
        in_run = false;
        continue;
      }
      if (!in_run) ++runs;
      in_run = true;
    }
    // A run wrapping from slot 3 to slot 0 through present members is one run.
    if (m[0] && m[3] && fan[0] >= 0 && fan[3] >= 0 && runs > 1) --runs;
  }
  return runs;
}

}  // namespace

double DiskCover::explore(std::uint32_t x, double R, int first, int last) {
  double centre_d = kInf;  // distance of the first other centre met (independence)
  caps_.clear();
  valid_.assign(static_cast<std::size_t>(std::max(0, last - first + 1)), 0);
  // Topology of the growing set, tracked incrementally: χ = nodes − segments + surfels, and the
  // number of pinch nodes (fans holding disk surfels in two or more runs). The set is a
  // topological disk exactly when χ = 1 and there is no pinch.
  long chi = 0, pinches = 0;
  double last_d = -1;
  auto in_disk = [&](std::uint32_t w) { return ws_.settled(w); };
  prefixes_.clear();
  auto record = [&](double from, double to) {  // the current prefix stands for radii [from, to)
    const bool ok = chi == 1 && pinches == 0;
    if (ok) prefixes_.push_back(from);
    for (int j = first; j <= last; ++j) {
      const double r = radius_of(j);
      if (r >= from && r < to) valid_[j - first] = ok;
    }
  };
  // A ball that stays non-disk over a span of 1.5 r_min will not become a disk again at a radius
  // worth having (transient corner contacts close within a voxel or two): stop there. Radii
  // beyond the stop count as invalid, which only makes disks smaller, never wrong.
  double invalid_since = -1;
  dijkstra(
      g_, ws_, x, R,
      [&](std::uint32_t u, double d) {
        if (d > last_d && last_d >= 0) {
          record(last_d, d);
          const bool ok = chi == 1 && pinches == 0;
          if (ok) invalid_since = -1;
          else if (invalid_since < 0) invalid_since = last_d;
          else if (d - invalid_since > 1.5 * r_min_) {
            centre_d = std::min(centre_d, d);  // nothing beyond d is known: treat as blocked
            return Visit::stop;
          }
        }
        if (u != x && (flags_[u] & kCentre)) {  // independence: the disk must not reach a centre
          centre_d = d;
          return Visit::stop;
        }
        last_d = d;
        // u is settled already: count its contacts with the other members.
        auto other = [&](std::uint32_t w) { return w != u && in_disk(w); };
        const auto nodes = sc_.nodes_of(u);
        const auto opp = sc_.opposites_of(u);
        long marked_edges = 0, marked_nodes = 0;
        for (std::size_t e = 0; e < nodes.size(); ++e) {
          if (opp[e] >= 0 && other(static_cast<std::uint32_t>(opp[e]))) ++marked_edges;
          bool node_in = false;
          for (auto f : sc_.node_fan[nodes[e]])
            if (f >= 0 && other(static_cast<std::uint32_t>(f))) node_in = true;
          marked_nodes += node_in;
          const int before = fan_runs(sc_, nodes[e], other);
          const int after = fan_runs(sc_, nodes[e], in_disk);
          pinches += (after >= 2) - (before >= 2);
        }
        chi += 1 + marked_edges - marked_nodes;
        if (covered(u)) caps_.push_back({d, 2.0 * rlo(u)});
        return Visit::expand;
      },
      [&](std::uint32_t w) { return active(w); });
  // Nothing beyond R was explored: the last prefix stands for radii up to R only.
  if (last_d >= 0) record(last_d, std::min(centre_d, std::nextafter(R, kInf)));
  return centre_d;
}

DiskCover::Grown DiskCover::grow(std::uint32_t x, int level) {
  ++stats_.disks_grown;
  const int last = std::max(level, max_level_);  // repair may ask for radii below r_min
  const double centre_d = explore(x, radius_of(level), level, last);
  bool topology_blocked = false;
  for (int j = level; j <= last; ++j) {
    const double r = radius_of(j);
    if (!(r < centre_d)) continue;
    if (!valid_[j - level]) {
      topology_blocked = true;
      continue;
    }
    bool ok = true;
    for (const auto& [d, cap] : caps_)
      if (d <= r && r > cap * (1 + 1e-9)) {
        ok = false;
        break;
      }
    if (ok) {
      if (topology_blocked) ++stats_.events;
      return {r, j};
    }
  }
  if (topology_blocked) ++stats_.events;
  // No r_max/2^j is feasible down to the floor (a feature thinner than the smallest disk, or a
  // tiny component): take the largest ball below the floor radius that is a topological disk and
  // meets independence and grading — at least the centre alone — and let the Voronoi repair
  // resolve what remains.
  ++stats_.floor_conflicts;
  const double floor_r = radius_of(last);
  for (auto it = prefixes_.rbegin(); it != prefixes_.rend(); ++it) {
    const double r = *it;
    if (r > floor_r || !(r < centre_d)) continue;
    bool ok = true;
    for (const auto& [d, cap] : caps_)
      if (d <= r && r > cap * (1 + 1e-9)) {
        ok = false;
        break;
      }
    if (ok) return {r, last};
  }
  return {0.0, last};
}

void DiskCover::accept(std::uint32_t x, const Grown& grown) {
  const auto id = static_cast<std::uint32_t>(centre_.size());
  centre_.push_back(x);
  radius_.push_back(grown.radius);
  level_.push_back(static_cast<std::int8_t>(grown.level));
  halving_queued_.push_back(0);
  flags_[x] |= kCentre;
  new_disks_.push_back(id);
  const double r = radius_[id];  // the stored (float) radius defines the disk from now on
  const double big = 2.0 * r * (1 + 1e-9);
  dijkstra(
      g_, ws_, x, std::max(2.0 * r, 0.0),
      [&](std::uint32_t v, double d) {
        if (d <= r) {
          for_each_cover(v, [&](std::uint32_t z) {
            if (radius_[z] > big) queue_halving(z);
          });
          add_cover(v, id);
        } else if (!covered(v)) {
          bool changed = false;
          if (label_[v] < grown.level) {
            label_[v] = static_cast<std::int8_t>(grown.level);
            changed = true;
          }
          if (d < dnear_[v]) {
            dnear_[v] = static_cast<float>(d);
            changed = true;
          }
          if (changed) push(v);
        }
        return Visit::expand;
      },
      [&](std::uint32_t w) { return active(w); });
}

bool DiskCover::halve(std::uint32_t z, bool grading) {
  // Repairs stop kRepairLevels below the growth floor; grading cascades may go further (down to
  // the centre alone), so that radii sharing a surfel always stay within a factor two.
  const int top = grading ? kDeepestLevel : max_level_ + kRepairLevels;
  if (level_[z] >= top || radius_[z] <= 0) {
    ++stats_.floor_conflicts;
    return false;
  }
  ++stats_.halvings;
  const double old_r = radius_[z];
  // The new radius: the largest r_max/2^j below the old one whose ball is still a topological
  // disk (a prefix of a disk need not be one); the centre alone when none is.
  explore(centre_[z], old_r, level_[z] + 1, top);
  int level = top;
  double r = 0;
  for (int j = level_[z] + 1; j <= top; ++j)
    if (valid_[j - level_[z] - 1] && radius_of(j) < old_r) {
      level = j;
      r = radius_of(j);
      break;
    }
  level_[z] = static_cast<std::int8_t>(level);
  radius_[z] = r;
  const double big = 2.0 * r * (1 + 1e-9);
  dijkstra(
      g_, ws_, centre_[z], old_r,
      [&](std::uint32_t v, double d) {
        if (d > r) {
          remove_cover(v, z);
          if (!covered(v)) {
            if (label_[v] < level_[z]) label_[v] = level_[z];
            if (d < dnear_[v]) dnear_[v] = static_cast<float>(d);
            push(v);
          }
        } else {
          for_each_cover(v, [&](std::uint32_t w) {
            if (w == z) return;
            if (radius_[w] > big) queue_halving(w);
            if (radius_[w] > 0 && r > 2.0 * radius_[w] * (1 + 1e-9)) queue_halving(z);
          });
        }
        return Visit::expand;
      },
      [&](std::uint32_t w) { return active(w); });
  return true;
}

void DiskCover::process_halvings() {
  while (!halving_.empty()) {
    const std::uint32_t z = halving_.back();
    halving_.pop_back();
    halving_queued_[z] = 0;
    halve(z, true);
  }
}

void DiskCover::run() {
  while (!heap_.empty()) {
    const std::uint32_t v = pop();
    if (!active(v) || covered(v)) continue;
    const Grown grown = grow(v, label_[v]);
    accept(v, grown);
    process_halvings();
    if (on_progress && active_count_ > 0)
      on_progress(double(covered_count_) / double(active_count_));
  }
  // Memory: the seed filled the heap with every vertex and the growths touched the whole
  // workspace; repairs push few candidates and search locally, but all over the surface on
  // noisy data: their searches use a hash table sized to one search, and a fresh (untouched)
  // slot array keeps only the pages they touch resident.
  std::vector<std::uint32_t>().swap(heap_);
  slot_ = ZeroedArray<std::uint32_t>(g_.num_vertices());
  ws_ = PathWorkspace::sparse(/*predecessors=*/false);
}

std::vector<std::uint32_t> DiskCover::take_new_disks() {
  std::vector<std::uint32_t> out;
  out.swap(new_disks_);
  return out;
}

}  // namespace adamesh::detail
