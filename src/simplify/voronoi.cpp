// Geodesic Voronoi covering VC_G and its closed-ball tests (ALGORITHM.md 2.5).
//
// Cells are grown by multi-source Dijkstra from the disk centres (ties: smaller centre id), and
// updated incrementally when repair adds centres. A cell passes when, on the surfel complex, it
// is one manifold disk (edge-connected, χ = 1, one boundary loop, no pinch), each neighbour cell
// occurs along its boundary loop in one arc, it has at least 3 neighbours (2 with a border arc)
// and it meets the volume border in at most one arc. Junctions — nodes whose complete fan holds
// three or four distinct cells — are the dual's triangles and quads.
#include "voronoi.h"

#include <algorithm>
#include <bit>
#include <cassert>
#include <queue>

#include "graph/shortest_paths.h"

namespace adamesh::detail {

bool ccw_fan(const SurfelComplex& sc, std::uint32_t n, std::array<std::int32_t, 4>& out) {
  const auto& fan = sc.node_fan[n];
  for (auto f : fan)
    if (f < 0) return false;
  const auto u = static_cast<std::uint32_t>(fan[0]);
  const auto nodes = sc.nodes_of(u);
  const std::size_t k = nodes.size();
  std::size_t i = 0;
  while (i < k && nodes[i] != n) ++i;
  assert(i < k);
  const std::int32_t incoming = sc.opposite(u, (i + k - 1) % k);
  // Seen from outside, the surfels around a node follow u, the neighbour across u's incoming
  // edge, the diagonal one, the neighbour across u's outgoing edge (counter-clockwise).
  if (fan[1] == incoming) out = fan;
  else out = {fan[0], fan[3], fan[2], fan[1]};
  return true;
}

Voronoi::Voronoi(const SurfelComplex& sc, const ConnectivityGraph& g)
    : sc_(sc), g_(g), cell_(g.num_vertices(), kNone), dist_(g.num_vertices(), kInf),
      dirty_((sc.num_nodes() + 63) / 64, 0), stamp_(g.num_vertices(), 0) {}

bool Voronoi::better(double d, std::uint32_t cv, std::uint32_t v) const {
  if (cell_[v] == kNone) return true;
  if (d != dist_[v]) return d < dist_[v];
  return cv < centre_[cell_[v]];
}

void Voronoi::add_cells(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& cells) {
  for (const auto& [c, x] : cells) {
    if (c >= centre_.size()) {
      centre_.resize(c + 1, kNone);
      size_.resize(c + 1, 0);
      touched_flag_.resize(c + 1, 0);
    }
    centre_[c] = x;
  }
  // Indexed heap: at most one entry per vertex, its best offer so far, ordered by (distance,
  // centre c-vertex, vertex) — the centre is looked up through the cell. Vertices are assigned
  // in that order and each at most once (weights are ≥ 0), exactly as a lazy heap would.
  // stamp_ serves as the vertex → heap slot map meanwhile (kNone: not in the heap).
  struct Entry {
    double d;
    std::uint32_t v, c;
  };
  const std::uint32_t* centre = centre_.data();
  auto before = [centre](const Entry& a, const Entry& b) {
    if (a.d != b.d) return a.d < b.d;
    if (a.c != b.c) return centre[a.c] < centre[b.c];
    return a.v < b.v;
  };
  std::vector<Entry> heap;
  std::vector<std::uint32_t>& slot = stamp_;
  std::fill(slot.begin(), slot.end(), kNone);
  auto place = [&](std::size_t i, const Entry& e) {
    heap[i] = e;
    slot[e.v] = static_cast<std::uint32_t>(i);
  };
  auto sift_up = [&](std::size_t i) {
    const Entry e = heap[i];
    while (i > 0 && before(e, heap[(i - 1) / 2])) {
      place(i, heap[(i - 1) / 2]);
      i = (i - 1) / 2;
    }
    place(i, e);
  };
  auto sift_down = [&](std::size_t i) {
    const Entry e = heap[i];
    for (;;) {
      std::size_t child = 2 * i + 1;
      if (child >= heap.size()) break;
      if (child + 1 < heap.size() && before(heap[child + 1], heap[child])) ++child;
      if (!before(heap[child], e)) break;
      place(i, heap[child]);
      i = child;
    }
    place(i, e);
  };
  auto offer = [&](double d, std::uint32_t v, std::uint32_t c) {
    if (!better(d, centre[c], v)) return;
    const std::uint32_t i = slot[v];
    if (i == kNone) {
      heap.push_back({d, v, c});
      sift_up(heap.size() - 1);
    } else if (before({d, v, c}, heap[i])) {
      heap[i].d = d;
      heap[i].c = c;
      sift_up(i);
    }
  };
  for (const auto& [c, x] : cells) offer(0.0, x, c);
  while (!heap.empty()) {
    if (ticker) ticker->tick();
    const Entry e = heap.front();
    slot[e.v] = kNone;
    if (heap.size() > 1) {
      heap.front() = heap.back();
      heap.pop_back();
      sift_down(0);
    } else {
      heap.pop_back();
    }
    const std::uint32_t cv = centre[e.c];
    if (!better(e.d, cv, e.v)) continue;
    reassign(e.v, e.c, e.d);
    for (std::size_t k = g_.row[e.v]; k < g_.row[e.v + 1]; ++k)
      offer(e.d + g_.edge_weight(e.v, k), g_.neighbour(e.v, k), e.c);
  }
  std::fill(stamp_.begin(), stamp_.end(), 0);  // back to generation stamps
  gen_ = 0;
}

void Voronoi::reassign(std::uint32_t v, std::uint32_t c, double d) {
  const std::uint32_t old = cell_[v];
  if (old != kNone) --size_[old];
  touch(old);
  cell_[v] = c;
  dist_[v] = d;
  ++size_[c];
  touch(c);
  for (auto nb : g_.neighbours(v)) touch(cell_[nb]);
  for (auto n : sc_.nodes_of(v)) dirty_[n >> 6] |= std::uint64_t{1} << (n & 63);
  any_dirty_ = true;
}

namespace {

/// True when some label occurs in two separate cyclic runs of the 4-fan.
bool pinched_fan(const std::array<std::uint32_t, 4>& c) {
  std::array<std::uint32_t, 4> runs;
  int r = 0;
  for (int q = 0; q < 4; ++q)
    if (r == 0 || runs[r - 1] != c[q]) runs[r++] = c[q];
  if (r > 1 && runs[0] == runs[r - 1]) --r;
  for (int i = 0; i < r; ++i)
    for (int j = i + 1; j < r; ++j)
      if (runs[i] == runs[j]) return true;
  return false;
}

}  // namespace

std::size_t Voronoi::regularize() {
  std::size_t moves = 0;
  std::vector<std::uint64_t> scan(dirty_.size());
  for (int pass = 0; pass < 8 && any_dirty_; ++pass) {
    // The nodes of the vertices changed since the last pass, in increasing order.
    scan.swap(dirty_);
    std::fill(dirty_.begin(), dirty_.end(), 0);
    any_dirty_ = false;
    std::array<std::int32_t, 4> fan;
    for (std::size_t word = 0; word < scan.size(); ++word) {
      for (std::uint64_t bits = scan[word]; bits != 0; bits &= bits - 1) {
        if (ticker) ticker->tick();
        const auto n = static_cast<std::uint32_t>(64 * word + std::countr_zero(bits));
        if (!ccw_fan(sc_, n, fan)) continue;
        std::array<std::uint32_t, 4> c;
        bool skip = false;
        for (int q = 0; q < 4; ++q) {
          c[q] = cell_[static_cast<std::uint32_t>(fan[q])];
          skip |= c[q] == kNone;
        }
        if (skip || !pinched_fan(c)) continue;
        // Candidate moves: one fan surfel takes the cell of a fan neighbour.
        double best = kInf;
        std::uint32_t best_v = kNone, best_c = kNone;
        double best_d = 0;
        for (int q = 0; q < 4; ++q) {
          const auto s = static_cast<std::uint32_t>(fan[q]);
          if (centre_[c[q]] == s) continue;  // centres stay in their cells
          for (int side : {1, 3}) {
            const std::uint32_t x = c[(q + side) % 4];
            if (x == c[q]) continue;
            auto trial = c;
            trial[q] = x;
            if (pinched_fan(trial)) continue;
            double dx = kInf;  // distance to x's centre through a neighbour in x
            for (std::size_t k = g_.row[s]; k < g_.row[s + 1]; ++k)
              if (const auto u = g_.neighbour(s, k); cell_[u] == x)
                dx = std::min(dx, dist_[u] + g_.edge_weight(s, k));
            const double penalty = dx - dist_[s];
            if (penalty < best || (penalty == best && s < best_v)) {
              best = penalty;
              best_v = s;
              best_c = x;
              best_d = dx;
            }
          }
        }
        if (best_v == kNone) continue;
        reassign(best_v, best_c, best_d);
        ++moves;
      }
    }
  }
  std::fill(dirty_.begin(), dirty_.end(), 0);
  any_dirty_ = false;
  return moves;
}

void Voronoi::set_assignment(const std::vector<std::uint32_t>& cell,
                             const std::vector<std::uint32_t>& centres) {
  cell_ = cell;
  centre_ = centres;
  size_.assign(centres.size(), 0);
  touched_flag_.assign(centres.size(), 0);
  for (auto c : cell_)
    if (c != kNone) ++size_[c];
}

void Voronoi::remove_vertices(const std::vector<std::uint32_t>& vertices) {
  for (auto v : vertices) {
    if (cell_[v] == kNone) continue;
    --size_[cell_[v]];
    cell_[v] = kNone;
    dist_[v] = kInf;
  }
}

std::vector<std::uint32_t> Voronoi::take_touched() {
  std::vector<std::uint32_t> out;
  out.swap(touched_);
  for (auto c : out) touched_flag_[c] = 0;
  std::sort(out.begin(), out.end());
  return out;
}

void Voronoi::members_of(std::uint32_t c, std::vector<std::uint32_t>& members) {
  // The cell is connected in G: shortest-path trees stay inside their cell.
  const std::uint32_t gen = next_stamp();
  const std::uint32_t x = centre_[c];
  members.assign(1, x);
  stamp_[x] = gen;
  for (std::size_t i = 0; i < members.size(); ++i)
    for (auto nb : g_.neighbours(members[i]))
      if (cell_[nb] == c && stamp_[nb] != gen) {
        stamp_[nb] = gen;
        members.push_back(nb);
      }
}

void Voronoi::neighbour_cells(std::uint32_t c, std::vector<std::uint32_t>& out) {
  out.clear();
  if (c >= size_.size() || size_[c] == 0) return;
  std::vector<std::uint32_t> members;
  members_of(c, members);
  for (auto v : members)
    for (auto nb : g_.neighbours(v))
      if (cell_[nb] != c && cell_[nb] != kNone) out.push_back(cell_[nb]);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

int Voronoi::check_cell(std::uint32_t c, std::vector<std::uint32_t>& neighbours) {
  neighbours.clear();
  if (size_[c] == 0) return kOk;  // empty (absorbed) cell: nothing to dualise
  const std::uint32_t x = centre_[c];
  if (cell_[x] != c) return kNotDisk;
  std::vector<std::uint32_t> members;
  members_of(c, members);
  if (members.size() != size_[c]) return kNotDisk;

  // Edge-connectivity across polygon edges (corner contacts do not connect a disk).
  next_stamp();
  std::vector<std::uint32_t> queue{x};
  stamp_[x] = gen_;
  for (std::size_t i = 0; i < queue.size(); ++i)
    for (auto o : sc_.opposites_of(queue[i]))
      if (o >= 0 && cell_[o] == c && stamp_[o] != gen_) {
        stamp_[o] = gen_;
        queue.push_back(static_cast<std::uint32_t>(o));
      }
  if (queue.size() != members.size()) return kNotDisk;

  struct HalfEdge {
    std::uint32_t a, b, label;
  };
  constexpr std::uint32_t kBorder = kNone - 1;
  std::vector<HalfEdge> boundary;
  std::vector<std::uint32_t> nodes;
  std::size_t interior_half = 0;
  for (auto u : members) {
    const auto nd = sc_.nodes_of(u);
    const auto op = sc_.opposites_of(u);
    const std::size_t k = nd.size();
    for (std::size_t e = 0; e < k; ++e) {
      nodes.push_back(nd[e]);
      const std::int32_t o = op[e];
      if (o >= 0 && cell_[o] == c) ++interior_half;
      else boundary.push_back({nd[e], nd[(e + 1) % k], o < 0 ? kBorder : cell_[o]});
    }
  }
  std::sort(nodes.begin(), nodes.end());
  const auto v_count = static_cast<long>(std::unique(nodes.begin(), nodes.end()) - nodes.begin());
  const long e_count = static_cast<long>(interior_half / 2 + boundary.size());
  const long chi = v_count - e_count + static_cast<long>(members.size());
  if (chi != 1 || boundary.empty()) return kNotDisk;

  // One boundary loop without pinches: each boundary node starts exactly one half-edge.
  std::sort(boundary.begin(), boundary.end(),
            [](const HalfEdge& p, const HalfEdge& q) { return p.a < q.a; });
  for (std::size_t i = 1; i < boundary.size(); ++i)
    if (boundary[i].a == boundary[i - 1].a) return kNotDisk;
  std::vector<std::uint32_t> labels;
  labels.reserve(boundary.size());
  std::size_t at = 0;
  for (std::size_t step = 0; step < boundary.size(); ++step) {
    labels.push_back(boundary[at].label);
    const std::uint32_t b = boundary[at].b;
    auto it = std::lower_bound(boundary.begin(), boundary.end(), b,
                               [](const HalfEdge& h, std::uint32_t key) { return h.a < key; });
    if (it == boundary.end() || it->a != b) return kNotDisk;
    at = static_cast<std::size_t>(it - boundary.begin());
    if (at == 0 && step + 1 != boundary.size()) return kNotDisk;  // closed early: two loops
  }
  if (at != 0) return kNotDisk;

  // Runs of neighbour labels around the loop.
  std::vector<std::uint32_t> runs;
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (runs.empty() || runs.back() != labels[i]) runs.push_back(labels[i]);
  if (runs.size() > 1 && runs.front() == runs.back()) runs.pop_back();
  std::vector<std::uint32_t> sorted = runs;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 1; i < sorted.size(); ++i)
    if (sorted[i] == sorted[i - 1]) return sorted[i] == kBorder ? kBorderArcs : kPairBoundary;
  const bool has_border = std::binary_search(sorted.begin(), sorted.end(), kBorder);
  for (auto l : runs)
    if (l != kBorder) neighbours.push_back(l);
  if (neighbours.size() < (has_border ? 2u : 3u)) return kFewNeighbours;
  return kOk;
}

namespace {

enum class JunctionKind { none, junction, pinched };

/// The junction at node n: `runs` holds the r distinct cells of its complete fan, in cyclic fan
/// order (either orientation: nothing below depends on it — runs, pinches, the diagonal pairs and
/// the sorted triangles are the same for the reversed cycle), for a junction (r = 3 or 4), or
/// the cells of a fan pinch (a cell twice apart).
JunctionKind junction_at(const SurfelComplex& sc, const std::vector<std::uint32_t>& cell,
                         std::uint32_t n, std::array<std::uint32_t, 4>& runs, int& r) {
  const std::array<std::int32_t, 4>& fan = sc.node_fan[n];
  for (const auto f : fan)
    if (f < 0) return JunctionKind::none;
  std::array<std::uint32_t, 4> c;
  for (int q = 0; q < 4; ++q) {
    c[q] = cell[static_cast<std::uint32_t>(fan[q])];
    if (c[q] == Voronoi::kNone) return JunctionKind::none;
  }
  // Cyclic runs of equal cells.
  r = 0;
  for (int q = 0; q < 4; ++q)
    if (r == 0 || runs[r - 1] != c[q]) runs[r++] = c[q];
  if (r > 1 && runs[0] == runs[r - 1]) --r;
  if (r <= 2) return JunctionKind::none;  // inside a cell or on a pair boundary
  for (int i = 0; i < r; ++i)
    for (int j = i + 1; j < r; ++j)
      if (runs[i] == runs[j]) return JunctionKind::pinched;
  return JunctionKind::junction;
}

}  // namespace

}  // namespace adamesh::detail

namespace adamesh::detail {

void dual_violations(const SurfelComplex& sc, const std::vector<std::uint32_t>& cell,
                     const std::vector<std::uint32_t>& centre_of_cell,
                     std::vector<std::uint32_t>& violated, std::vector<std::size_t>* kinds,
                     StageTicker* ticker) {
  auto tick = [ticker] {
    if (ticker) ticker->tick();
  };
  // Memory (docs/SIMPLIFICATION.md): junctions are visited again instead of being stored — once
  // for pinches, the triangle count and the quad diagonals, once over the fans for which
  // diagonals are dual edges, once hashing the triangles and, when hashes collide, once more to
  // count the colliding triangles exactly.
  auto key = [](std::uint32_t a, std::uint32_t b) {
    if (a > b) std::swap(a, b);
    return (std::uint64_t(a) << 32) | b;
  };
  std::vector<std::uint32_t> pinched;
  std::vector<std::uint64_t> diagonals;  // both diagonals of every 4-cell junction
  std::size_t max_triangles = 0;
  std::array<std::uint32_t, 4> runs;
  int r = 0;
  for (std::uint32_t n = 0; n < sc.num_nodes(); ++n) {
    tick();
    const JunctionKind kind = junction_at(sc, cell, n, runs, r);
    if (kind == JunctionKind::pinched) {
      for (int i = 0; i < r; ++i) pinched.push_back(runs[i]);
    } else if (kind == JunctionKind::junction) {
      max_triangles += static_cast<std::size_t>(r - 2);
      if (r == 4) {
        diagonals.push_back(key(runs[0], runs[2]));
        diagonals.push_back(key(runs[1], runs[3]));
      }
    }
  }
  std::sort(pinched.begin(), pinched.end());
  pinched.erase(std::unique(pinched.begin(), pinched.end()), pinched.end());
  violated.insert(violated.end(), pinched.begin(), pinched.end());
  if (kinds) (*kinds)[kFanPinch] += pinched.size();

  // Which quad diagonals are edges of the dual already (cells adjacent across a polygon edge),
  // and which ones the quads below have chosen: flags in an open-addressing table of the
  // diagonals (memory: only the diagonals are listed, not every dual edge).
  constexpr std::uint8_t kIsEdge = 1, kAdded = 2;
  std::size_t cap = 16;
  while (cap < 2 * diagonals.size()) cap *= 2;
  std::vector<std::uint64_t> table(cap, 0);  // 0 = empty (a key's larger cell is never 0)
  std::vector<std::uint8_t> flags(cap, 0);
  auto slot_of = [&](std::uint64_t k) {
    std::size_t i = static_cast<std::size_t>((k * 0x9E3779B97F4A7C15ull) >> 20) & (cap - 1);
    while (table[i] != 0 && table[i] != k) i = (i + 1) & (cap - 1);
    return i;
  };
  for (const auto k : diagonals) table[slot_of(k)] = k;
  // Cells on some diagonal (centre_of_cell is indexed by cell id).
  std::vector<std::uint64_t> on_diagonal((centre_of_cell.size() + 63) / 64, 0);
  for (const auto k : diagonals)
    for (const std::uint32_t c : {static_cast<std::uint32_t>(k >> 32), static_cast<std::uint32_t>(k)})
      on_diagonal[c / 64] |= std::uint64_t{1} << (c % 64);
  const bool any_diagonal = !diagonals.empty();
  std::vector<std::uint64_t>().swap(diagonals);
  auto flagged = [](const std::vector<std::uint64_t>& bits, std::uint32_t c) {
    return (bits[c / 64] >> (c % 64) & 1) != 0;
  };
  // Two cells are adjacent across a segment exactly when they hold consecutive surfels of a
  // node's fan (voxels of neighbouring quadrants share the face the segment from the node lies
  // on), so one pass over the fans finds them.
  if (any_diagonal)
    for (std::uint32_t n = 0; n < sc.num_nodes(); ++n) {
      tick();
      const auto& fan = sc.node_fan[n];
      for (int q = 0; q < 4; ++q) {
        const std::int32_t s0 = fan[q], s1 = fan[(q + 1) & 3];
        if (s0 < 0 || s1 < 0) continue;
        const std::uint32_t a = cell[static_cast<std::uint32_t>(s0)], b = cell[static_cast<std::uint32_t>(s1)];
        if (a == b || a == Voronoi::kNone || b == Voronoi::kNone || !flagged(on_diagonal, a) ||
            !flagged(on_diagonal, b))
          continue;
        const std::size_t i = slot_of(key(a, b));
        if (table[i] != 0) flags[i] |= kIsEdge;
      }
    }
  auto has_edge = [&](std::uint32_t a, std::uint32_t b) {  // (a, b): a quad's diagonal
    return flags[slot_of(key(a, b))] != 0;
  };
  auto add = [&](std::uint32_t a, std::uint32_t b) { flags[slot_of(key(a, b))] |= kAdded; };
  auto clear_added = [&] {
    for (auto& f : flags) f &= static_cast<std::uint8_t>(~kAdded);
  };

  // The dual's triangles, each as its sorted cell triple; only duplicates matter here (two
  // junctions with the same three cells). Memory: instead of listing every triangle (12 bytes
  // each), a first pass sets one bit per triangle in a hashed bitmap (16 bits per triangle) and
  // keeps the triangles whose bit was set already; a second pass counts those candidates exactly.
  using Tri = std::array<std::uint32_t, 3>;
  auto for_each_triangle = [&](bool first_pass, auto&& emit_sorted) {
    clear_added();
    auto emit = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
      Tri t{a, b, c};
      std::sort(t.begin(), t.end());
      emit_sorted(t);
    };
    for (std::uint32_t n = 0; n < sc.num_nodes(); ++n) {
      tick();
      if (junction_at(sc, cell, n, runs, r) != JunctionKind::junction) continue;
      const auto& c = runs;
      if (r == 3) {
        emit(c[0], c[1], c[2]);
        continue;
      }
      auto len = [&](std::uint32_t a, std::uint32_t b) {
        return distance(sc.cvertex_position(centre_of_cell[a]), sc.cvertex_position(centre_of_cell[b]));
      };
      const bool ac_exists = has_edge(c[0], c[2]), bd_exists = has_edge(c[1], c[3]);
      bool use_ac;
      if (ac_exists && bd_exists) {
        if (first_pass) {
          for (int q = 0; q < 4; ++q) violated.push_back(c[q]);
          if (kinds) ++(*kinds)[kFanPinch];
        }
        continue;
      } else if (ac_exists) {
        use_ac = false;
      } else if (bd_exists) {
        use_ac = true;
      } else {
        const double lac = len(c[0], c[2]), lbd = len(c[1], c[3]);
        use_ac = lac < lbd || (lac == lbd && std::min(c[0], c[2]) < std::min(c[1], c[3]));
      }
      if (use_ac) {
        emit(c[0], c[1], c[2]);
        emit(c[0], c[2], c[3]);
        add(c[0], c[2]);
      } else {
        emit(c[0], c[1], c[3]);
        emit(c[1], c[2], c[3]);
        add(c[1], c[3]);
      }
    }
  };
  const std::uint64_t bits = 64 * (max_triangles / 4 + 1);  // ≥ 16 per triangle
  std::vector<std::uint64_t> seen(bits / 64, 0);
  auto hash = [&](const Tri& t) {  // a bit index in [0, bits): 32 mixed bits scaled to the range
    std::uint64_t h = (std::uint64_t{t[0]} * 0x9E3779B97F4A7C15ull) ^ t[1];
    h = (h * 0xC2B2AE3D27D4EB4Full) ^ t[2];
    h *= 0x165667B19E3779F9ull;
    return ((h >> 32) * bits) >> 32;
  };
  std::vector<Tri> candidates;
  for_each_triangle(true, [&](const Tri& t) {
    const std::uint64_t b = hash(t);
    std::uint64_t& word = seen[b / 64];
    if (word >> (b % 64) & 1) candidates.push_back(t);
    word |= std::uint64_t{1} << (b % 64);
  });
  std::vector<std::uint64_t>().swap(seen);
  if (!candidates.empty()) {
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    std::vector<std::uint32_t> count(candidates.size(), 0);
    std::vector<std::uint64_t> in_candidate(on_diagonal.size(), 0);
    for (const Tri& t : candidates)
      for (const auto c : t) in_candidate[c / 64] |= std::uint64_t{1} << (c % 64);
    for_each_triangle(false, [&](const Tri& t) {
      if (!flagged(in_candidate, t[0]) || !flagged(in_candidate, t[1]) || !flagged(in_candidate, t[2]))
        return;
      const auto it = std::lower_bound(candidates.begin(), candidates.end(), t);
      if (it != candidates.end() && *it == t) ++count[static_cast<std::size_t>(it - candidates.begin())];
    });
    for (std::size_t i = 0; i < candidates.size(); ++i)
      for (std::uint32_t k = 1; k < count[i]; ++k) {
        for (auto c : candidates[i]) violated.push_back(c);
        if (kinds) ++(*kinds)[kDuplicate];
      }
  }
  std::sort(violated.begin(), violated.end());
  violated.erase(std::unique(violated.begin(), violated.end()), violated.end());
}

}  // namespace adamesh::detail
