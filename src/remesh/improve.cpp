// Shape improvement on the iso-surface (include/adamesh/improve.h, docs/QUALITY.md).
//
// Each round:
//   1. flips: every interior edge whose two triangles have a smallest angle below the target is
//      flipped when the flip raises that smallest angle by ≥ 1°, the new edge does not exist
//      yet, neither new triangle turns over, and the new edge lies within the deviation bound of
//      the surface (one pass over the edges sorted by key, each triangle flipped once a pass);
//   2. moves: every free vertex with a bad triangle around it moves toward the mean of its
//      triangles' ideal apexes (the point that makes the opposite edge's triangle equilateral, in
//      that triangle's plane), tangentially, then is projected onto the iso-surface; the move is
//      kept only when the smallest angle around the vertex rises and no triangle turns over
//      (step λ = 1, ½, ¼; a vertex with a ring triangle under 20° may travel ¾ of its mean edge
//      length, others — and every vertex of M0 — ¾ of their shortest edge);
//   3. collapses: a needle (smallest angle below `collapse_below_deg`, shortest edge under half
//      the next) loses its shortest edge when the link condition holds (the two ends share only
//      the two opposite vertices, both of valence > 3) and the smallest angle around the merged
//      vertex rises with it at the projected midpoint or at either end (the best of the three).
// With `rescue_below_deg` (the written meshes, docs/QUALITY.md "Rescue"), after the rounds:
// specks become a tetrahedron or an octahedron, border needles lose their boundary edge, and
// after the splits and the untangling the vertices of the triangles still below it move off the
// surface within the deviation bound (then four times it for what is under 10°).
// Flips and link-condition collapses keep the surface's topology; moves keep the connectivity.
// Everything is serial and visits elements in a fixed order, so the result is deterministic.
#include "adamesh/improve.h"
#include "adamesh/metrics.h"
#include "adamesh/volume.h"
#include "remesh/geometry.h"

#include "adamesh/context.h"

#include <algorithm>
#include <optional>
#include <iterator>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <unordered_map>
#include <unordered_set>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

namespace adamesh {

namespace {

using Tri = std::array<std::uint32_t, 3>;
using detail::symmetric_eigen;
constexpr double kDeg = std::numbers::pi / 180;
/// The refinement's bound on a triangle is 1.25 × its sampled error (its samples can miss the
/// worst point); the same margin here.
constexpr double kErrorSafety = 1.25;
/// Vertices with a ring triangle under this (degrees) may move as far as their mean edge length.
constexpr double kWideMoveBelowDeg = 20;
/// Untangling moves make no triangle below this (degrees) unless its ring had one.
constexpr double kUntangleMinAngle = 20;
/// Specks (Improver::replace_specks): at most this long (voxels) and this many triangles, and
/// their replacements have no angle below kSpeckAngleDeg.
constexpr double kSpeckVoxels = 5;
constexpr std::size_t kSpeckMaxTriangles = 128;
constexpr double kSpeckAngleDeg = 25;
/// The rescue's last stage: triangles still under kRescueLastDeg, kRescueLastReach × the
/// deviation bound.
constexpr double kRescueLastDeg = 10;
constexpr double kRescueLastReach = 4;
/// Graded needle splits (Improver::split_needles): rounds, and with a budget the splits kept for
/// the needles the rescue leaves.
constexpr int kNeedleRounds = 6;
constexpr std::size_t kNeedleReserve = 4;
/// Untangling moves make no edge shorter than this many voxels.
constexpr double kUntangleMinEdge = 0.01;
/// The decimation's order (Improver::collapse_cost): quadric error plus this × voxel² × the
/// squared edge length, i.e. an edge costs like a deviation of √0.1 ≈ 0.3 voxel over its
/// length² of surface. Chosen among 0.001–1 on eight decimated scan budgets (docs/QUALITY.md
/// "Decimation by quadric error"): every weight lowered the RMS distance about as much.
constexpr double kDecimateLengthWeight = 0.1;
/// A decimation sweep collapses at most this share of the triangles before the flips.
constexpr double kDecimateSweep = 0.08;
/// The same next to the volume's border (Improver::mark_near_border): mostly the edge length.
constexpr double kDecimateBorderWeight = 10;

double angle_at(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 u = b - a, v = c - a;
  return std::atan2(norm(cross(u, v)), dot(u, v));
}

/// Smallest interior angle (radians) of triangle abc; 0 for a degenerate one. It is the angle
/// opposite the shortest edge: one atan2 (the angle tests are a tenth of the improvement's time).
double min_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double ab = norm2(b - a), bc = norm2(c - b), ca = norm2(a - c);
  if (bc <= ab && bc <= ca) return angle_at(a, b, c);
  if (ca <= ab) return angle_at(b, c, a);
  return angle_at(c, a, b);
}

Vec3 tri_normal(const Vec3& a, const Vec3& b, const Vec3& c) { return cross(b - a, c - a); }

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return a < b ? (std::uint64_t{a} << 32) | b : (std::uint64_t{b} << 32) | a;
}

/// Distance between segments pq and rs (closest points, clamped).
double segment_distance(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const Vec3 d1 = q - p, d2 = s - r, w = p - r;
  const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, w);
  double t1 = 0, t2 = 0;
  if (a <= 0 && e <= 0) return norm(w);
  if (a <= 0) {
    t2 = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = dot(d1, w);
    if (e <= 0) {
      t1 = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = dot(d1, d2), den = a * e - b * b;
      t1 = den > 0 ? std::clamp((b * f - c * e) / den, 0.0, 1.0) : 0.0;
      t2 = (b * t1 + f) / e;
      if (t2 < 0) {
        t2 = 0;
        t1 = std::clamp(-c / a, 0.0, 1.0);
      } else if (t2 > 1) {
        t2 = 1;
        t1 = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return norm((p + t1 * d1) - (r + t2 * d2));
}


class Improver {
 public:
  Improver(Mesh& mesh, const std::vector<std::uint8_t>& fixed, const ScalarField* field,
           double iso, const ImproveOptions& o, const ExecutionContext& ctx, const char* stage)
      : field_(field), iso_(iso), o_(o), ctx_(ctx), tick_(ctx, stage, 2048) {
    const std::size_t nv = mesh.num_vertices(), nt = mesh.num_triangles();
    p_.resize(nv);
    for (std::size_t v = 0; v < nv; ++v) p_[v] = mesh.vertex(v);
    t_.resize(nt);
    for (std::size_t t = 0; t < nt; ++t)
      t_[t] = {mesh.triangles[3 * t], mesh.triangles[3 * t + 1], mesh.triangles[3 * t + 2]};
    fixed_.assign(nv, 0);
    for (std::size_t v = 0; v < std::min(nv, fixed.size()); ++v) fixed_[v] = fixed[v];
    speck_.assign(nv, 0);
    tri_alive_.assign(nt, 1);
    dirty_.assign(nv, 1);
    dev_ = o_.max_deviation > 0 ? o_.max_deviation : 0.25 * o_.voxel;
    has_box_ = o_.box.hi.x > o_.box.lo.x;
    // The vertices are the mesh's floats: a vertex on a face that is not a float (spacing 1.6:
    // z max 110.4) lies up to half a float step off the exact face, so it was neither pinned to
    // its face nor allowed any move, and the slivers there stayed (docs/QUALITY.md).
    if (has_box_) o_.box = widened_to_floats(o_.box);
    if (!o_.faces.empty()) set_oblique_faces();
    bounds_ = detail::VolumeBounds(o_.box, o_.faces);
    mark_boundary_vertices();
  }

  /// M0: every move stays under ¾ of the shortest incident edge (anchors stay valid).
  void keep_moves_small() { small_moves_ = true; }

  /// After decimate(): the lowest angle floor its collapses needed (degrees), and the triangle
  /// count at which the first floor (kDecimateShapeFloorDeg) found no collapse (0: it never stuck).
  double decimate_floor_deg() const { return decimate_floor_deg_; }
  std::size_t decimate_stuck_at() const { return decimate_stuck_at_; }

  ImproveStats run() {
    ImproveStats st;
    measure(st.min_angle_before_deg, st.pct_below_20_before);
    // Unfold first: flips and moves on a folded patch make it worse (a vertex dragged across
    // its neighbour: 15 crossing pairs left when the rounds go first, none when they follow).
    std::size_t first = 0;
    if (o_.untangle) {
      untangle(st);
      first = st.intersections_before;
    }
    for (int r = 0; r < o_.rounds; ++r) {
      tick_.poll(static_cast<double>(r) / (o_.rounds + 1));
      const std::size_t f = flip_pass();
      const std::size_t m = move_pass();
      const std::size_t c = o_.collapse_below_deg > 0 ? collapse_pass() : 0;
      st.flips += f;
      st.moves += m;
      st.collapses += c;
      st.rounds = r + 1;
      if (f + m + c == 0) break;
    }
    // Splits give back the triangles collapses took (the budget holds), then a last flip pass:
    // the final moves and splits can leave flippable pairs.
    tick_.poll(static_cast<double>(o_.rounds) / (o_.rounds + 1));
    // Specks and border needles before the splits: the budget holds.
    if (o_.rescue_below_deg > 0) {
      replace_specks(st);
      st.collapses += collapse_border_needles(o_.rescue_below_deg * kDeg);
    }
    if (o_.target_triangles > 0) {
      // Room for the graded needle splits at the end (kNeedleReserve splits; what they leave
      // is split there).
      const std::size_t reserve = o_.rescue_below_deg > 0 ? 2 * kNeedleReserve : 0;
      st.splits = split_pass(o_.target_triangles > reserve ? o_.target_triangles - reserve : 0);
    }
    st.flips += flip_pass();
    if (o_.untangle) {
      // Unfolding leaves umbrella-shaped slivers: shape again, then unfold what that undid.
      untangle(st);
      for (int r = 0; r < 2; ++r) st.flips += flip_pass(), st.moves += move_pass();
      untangle(st);
      st.intersections_before = first;
    }
    if (o_.rescue_below_deg > 0) {
      rescue(st);
      // Collapses next to each other wait for the next pass.
      for (int pass = 0; pass < 4; ++pass) {
        const std::size_t c = collapse_below(kRescueLastDeg * kDeg);
        st.collapses += c;
        if (c == 0) break;
      }
      // Border needles the splits, the untangling and the rescue left or made.
      st.collapses += collapse_border_needles(kRescueLastDeg * kDeg);
      // Needles held by the topology that the rescue left: graded splits, at most 0.1 % more
      // triangles; a budget (or the default mesh's cap): the room reserved above, and what they
      // leave of it goes to the budget's last splits.
      std::size_t cap = std::max<std::size_t>(4, alive_triangles() / 2000);
      if (o_.target_triangles > 0) {
        const std::size_t have = alive_triangles();
        cap = have < o_.target_triangles ? (o_.target_triangles - have) / 2 : 0;
      }
      st.needle_splits = split_needles(kRescueLastDeg * kDeg, kNeedleRounds, cap);
      st.splits += st.needle_splits;
      if (o_.target_triangles > 0) st.splits += split_pass(o_.target_triangles);
    }
    measure(st.min_angle_after_deg, st.pct_below_20_after);
    return st;
  }

  void write(Mesh& mesh, bool renumbered, std::vector<std::uint32_t>* vertex_map) const {
    // Splits (kept or undone) add vertices and triangles: only the renumbering writes them.
    renumbered |= p_.size() != mesh.num_vertices() || t_.size() != mesh.num_triangles();
    if (vertex_map) {
      vertex_map->resize(p_.size());
      for (std::uint32_t v = 0; v < p_.size(); ++v) (*vertex_map)[v] = v;
    }
    if (!renumbered) {
      for (std::size_t v = 0; v < p_.size(); ++v) {
        mesh.positions[3 * v] = static_cast<float>(p_[v].x);
        mesh.positions[3 * v + 1] = static_cast<float>(p_[v].y);
        mesh.positions[3 * v + 2] = static_cast<float>(p_[v].z);
      }
      for (std::size_t t = 0; t < t_.size(); ++t)
        for (int k = 0; k < 3; ++k) mesh.triangles[3 * t + k] = t_[t][k];
      return;
    }
    std::vector<std::uint32_t> id(p_.size(), UINT32_MAX);
    Mesh out;
    for (std::size_t t = 0; t < t_.size(); ++t) {
      if (!tri_alive_[t]) continue;
      std::array<std::uint32_t, 3> n{};
      for (int k = 0; k < 3; ++k) {
        auto& i = id[t_[t][k]];
        if (i == UINT32_MAX) i = out.add_vertex(p_[t_[t][k]]);
        n[k] = i;
      }
      out.add_triangle(n[0], n[1], n[2]);
    }
    if (vertex_map) *vertex_map = std::move(id);
    mesh = std::move(out);
  }

 private:
  const ScalarField* field_;
  double iso_;
  ImproveOptions o_;
  const ExecutionContext& ctx_;  ///< threads of the intersection counts, cancellation inside parallel_ranges
  /// Cancellation and progress inside the passes (mutable: the const edge walk ticks too).
  mutable StageTicker tick_;
  double dev_ = 0;
  double flip_below_ = 0;  ///< > 0: only pairs with a triangle below this flip (radians)
  bool has_box_ = false;
  bool oblique_ = false;  ///< o_.faces set: inside and on-face tests in the grid's index space
  std::array<Vec3, 3> face_normal_{};
  std::array<double, 3> face_tol_{};
  detail::VolumeBounds bounds_;  ///< inside_box()
  bool small_moves_ = false;  ///< M0: every move under ¾ of the shortest incident edge
  double decimate_floor_deg_ = 0;
  std::size_t decimate_stuck_at_ = 0;
  std::vector<Vec3> p_;
  std::vector<Tri> t_;
  std::vector<std::uint8_t> fixed_, boundary_, tri_alive_;
  std::vector<std::uint8_t> speck_;  // per vertex: a speck's replacement (replace_specks) — stays
  std::vector<std::uint8_t> dirty_;  // per vertex: its ring changed since the last move pass
  // vertex v -> its alive triangles inc_[inc_off_[v] .. inc_end_[v]) (CSR after build_incidence;
  // decimate_in_order() moves a merged vertex's list to the end of inc_)
  std::vector<std::uint32_t> inc_off_, inc_end_, inc_;
  std::vector<std::array<double, 10>> quad_;  // decimate(): per-vertex error quadrics
  std::vector<std::uint8_t> near_border_;     // decimate(): see mark_near_border()

  /// Largest |distance| estimate at seven points of triangle abc (centroid, edge midpoints, and
  /// the points halfway from the centroid to the corners); 0 without a field or error bound.
  double tri_error(const Vec3& a, const Vec3& b, const Vec3& c) const {
    if (!field_ || o_.max_error <= 0) return 0;
    const Vec3 g = (a + b + c) / 3.0;
    double e = 0;
    for (const Vec3& q : {g, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a), 0.5 * (g + a),
                          0.5 * (g + b), 0.5 * (g + c)})
      e = std::max(e, std::abs(signed_distance(*field_, iso_, q, 1e30)));
    return e;
  }

  /// The triangles around v with v at q stay within the error bound (or no worse than now).
  bool ring_error_ok(std::uint32_t v, const Vec3& q) const {
    if (!field_ || o_.max_error <= 0) return true;
    const double bound = o_.max_error / kErrorSafety;
    for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i) {
      const Tri& t = t_[inc_[i]];
      Vec3 a = p_[t[0]], b = p_[t[1]], c = p_[t[2]];
      const double before = tri_error(a, b, c);
      (t[0] == v ? a : t[1] == v ? b : c) = q;
      if (tri_error(a, b, c) > std::max(bound, before)) return false;
    }
    return true;
  }

  double tri_min_angle(const Tri& t) const { return min_angle(p_[t[0]], p_[t[1]], p_[t[2]]); }

  void measure(double& min_deg, double& pct20) const {
    double mn = 180;
    std::size_t below = 0, n = 0;
    for (std::size_t t = 0; t < t_.size(); ++t) {
      if (!tri_alive_[t]) continue;
      const double a = tri_min_angle(t_[t]) / kDeg;
      mn = std::min(mn, a);
      below += a < 20;
      ++n;
    }
    min_deg = n ? mn : 0;
    pct20 = n ? 100.0 * static_cast<double>(below) / static_cast<double>(n) : 0;
  }

  /// Vertices on an edge used by one triangle (mesh boundary) or by more than two: never moved.
  void mark_boundary_vertices() {
    std::vector<std::uint64_t> keys;
    keys.reserve(3 * t_.size());
    for (const Tri& t : t_)
      for (int k = 0; k < 3; ++k) keys.push_back(edge_key(t[k], t[(k + 1) % 3]));
    std::sort(keys.begin(), keys.end());
    boundary_.assign(p_.size(), 0);
    for (std::size_t i = 0; i < keys.size();) {
      std::size_t j = i;
      while (j < keys.size() && keys[j] == keys[i]) ++j;
      if (j - i != 2) {
        boundary_[keys[i] >> 32] = 1;
        boundary_[keys[i] & 0xffffffffu] = 1;
      }
      i = j;
    }
  }

  void mark_ring_dirty(std::uint32_t v) {
    dirty_[v] = 1;
    for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i)
      for (auto u : t_[inc_[i]]) dirty_[u] = 1;
  }

  void build_incidence() {
    inc_off_.assign(p_.size() + 1, 0);
    for (std::size_t t = 0; t < t_.size(); ++t)
      if (tri_alive_[t])
        for (auto v : t_[t]) ++inc_off_[v + 1];
    for (std::size_t v = 0; v < p_.size(); ++v) inc_off_[v + 1] += inc_off_[v];
    inc_.resize(inc_off_.back());
    std::vector<std::uint32_t> fill(inc_off_.begin(), inc_off_.end() - 1);
    for (std::size_t t = 0; t < t_.size(); ++t)
      if (tri_alive_[t])
        for (auto v : t_[t]) inc_[fill[v]++] = static_cast<std::uint32_t>(t);
    inc_end_.assign(inc_off_.begin() + 1, inc_off_.end());
  }

  /// Oblique grids: index-space faces, a vertex on one within the float rounding of its
  /// coordinates.
  void set_oblique_faces() {
    oblique_ = has_box_ = true;
    for (int a = 0; a < 3; ++a) {
      face_normal_[a] = normalized(o_.faces.to_index.row(a));
      face_tol_[a] = o_.faces.rounding[a] + 1e-9 * o_.faces.extent[a];
    }
  }
  Vec3 grid_index(const Vec3& q) const { return o_.faces.to_index * (q - o_.faces.origin); }

  bool inside_box(const Vec3& q) const { return bounds_.contains(q); }

  /// Distance from q to the iso-surface (Newton projection), or infinity when it does not
  /// converge to within a tenth of the deviation bound.
  double surface_distance(const Vec3& q, double max_step) const {
    ProjectOptions po;
    po.max_steps = 8;
    po.tolerance = 1e-3 * o_.voxel;
    po.max_step = max_step;
    const ProjectResult r = project_to_iso(*field_, iso_, q, po);
    if (r.residual > 0.1 * dev_) return std::numeric_limits<double>::infinity();
    return distance(q, r.point);
  }

  /// Projects q onto the surface; false when the projection does not converge or leaves the box.
  bool project(Vec3& q, double max_step) const {
    if (!field_) return inside_box(q);
    ProjectOptions po;
    po.max_steps = 8;
    po.tolerance = 1e-4 * o_.voxel;
    po.max_step = max_step;
    const ProjectResult r = project_to_iso(*field_, iso_, q, po);
    if (r.residual > 1e-2 * o_.voxel) return false;
    q = r.point;
    return inside_box(q);
  }

  /// The current mesh in float (alive triangles only; id[k] is the t_ index of its triangle k).
  Mesh snapshot(std::vector<std::uint32_t>& id) const {
    Mesh m;
    m.positions.resize(3 * p_.size());
    for (std::size_t v = 0; v < p_.size(); ++v)
      for (int k = 0; k < 3; ++k) m.positions[3 * v + k] = static_cast<float>(p_[v][k]);
    id.clear();
    for (std::size_t t = 0; t < t_.size(); ++t) {
      if (!tri_alive_[t]) continue;
      id.push_back(static_cast<std::uint32_t>(t));
      for (auto v : t_[t]) m.triangles.push_back(v);
    }
    return m;
  }

  /// tbb::parallel_for over [begin, end) in ranges of `grain`: body(range) on each, the ranges
  /// left once the cancel flag is set skipped, and the cancellation thrown after the loop, on
  /// this thread (an uncancellable plan over a million vertices held a cancel for 1.6 s).
  template <class Index, class Body>
  void parallel_ranges(Index begin, Index end, Index grain, Body&& body) const {
    tbb::parallel_for(tbb::blocked_range<Index>(begin, end, grain),
                      [&](const tbb::blocked_range<Index>& r) {
                        if (!ctx_.cancelled()) body(r);
                      });
    tick_.check();
  }

  /// Removes self-intersections where it can (issue 13): the vertices of intersecting triangles
  /// move half way to the mean of their neighbours (a fold or a crossing made by placements on a
  /// noisy surface unfolds; projecting back onto the surface folds it again: where two sheets of
  /// the surface are closer than the triangles are wide, no mesh on the surface avoids crossing),
  /// all at once, and a round is kept only when the count goes down (the rounds stop after one
  /// that removes under 1 %); when it does not, the next round also moves their neighbours (up
  /// to two rings). Fixed and boundary
  /// vertices stay, the box and an explicit error bound hold. The count is exact but
  /// incremental (issue 14): after the first full count only pairs with a triangle around a
  /// moved vertex are tested again (the connectivity does not change here).
  void untangle(ImproveStats& st) {
    using PairList = std::vector<std::pair<std::uint32_t, std::uint32_t>>;
    tick_.check();
    std::vector<std::uint32_t> id;  // mesh triangle -> t_ index
    Mesh m = snapshot(id);
    PairList pairs;  // in mesh triangle indices
    {
      IntersectionReport r = self_intersections(m, m.num_triangles() * m.num_triangles(), ctx_);
      if (r.pairs < 0) {  // not measured (piles of triangles): nothing to do
        st.intersections_before = st.intersections_after = 0;
        return;
      }
      pairs = std::move(r.first_pairs);
    }
    std::size_t cur = pairs.size();
    st.intersections_before = cur;
    if (cur == 0) {
      st.intersections_after = 0;
      return;
    }
    std::vector<std::uint8_t> moved(p_.size(), 0), involved(m.num_triangles(), 0);
    auto set_position = [&](std::uint32_t v, const Vec3& q) {
      p_[v] = q;
      for (int k = 0; k < 3; ++k) m.positions[3 * v + k] = static_cast<float>(q[k]);
    };
    int ring = 0;
    for (int round = 0; round < 16 && cur > 0; ++round) {
      tick_.check();  // a round over a large mesh takes a tenth of a second or more
      build_incidence();
      std::vector<std::uint8_t> sel(p_.size(), 0);
      for (const auto& [a, b] : pairs)
        for (auto t : {a, b})
          for (auto v : t_[id[t]]) sel[v] = 1;
      for (int k = 0; k < ring; ++k) {
        std::vector<std::uint8_t> grown = sel;
        for (std::uint32_t v = 0; v < p_.size(); ++v)
          if (sel[v]) {
            neighbours(v, na_);
            for (auto w : na_) grown[w] = 1;
          }
        sel = std::move(grown);
      }
      // All moves from the current positions (applied together below), so they are planned in
      // parallel and collected in vertex order.
      std::vector<std::uint8_t> go(p_.size(), 0);
      std::vector<Vec3> dest(p_.size());
      tbb::enumerable_thread_specific<std::vector<std::uint32_t>> nbrs;
      parallel_ranges<std::uint32_t>(0, static_cast<std::uint32_t>(p_.size()), 512,
                                     [&](const tbb::blocked_range<std::uint32_t>& r) {
        std::vector<std::uint32_t>& na = nbrs.local();
        for (std::uint32_t v = r.begin(); v != r.end(); ++v) {
          if (!sel[v] || fixed_[v] || boundary_[v] || speck_[v] || inc_off_[v] == inc_end_[v]) continue;
          neighbours(v, na);
          if (na.empty()) continue;
          Vec3 q{};
          for (auto w : na) q = q + p_[w];
          q = (1.0 / static_cast<double>(na.size())) * q;
          // Half way, else all the way, and not into slivers (CT head at 20k, 943 pairs: full
          // umbrella alone 55 pairs but 1.6 % of triangles under 20° instead of 0.96 %; half
          // way with a 20° guard 141 pairs at 0.80 %).
          // Nor into specks: moving every vertex of a tiny closed component to the mean of its
          // neighbours shrinks it (a 4-vertex speck on ct_lidc2_chest went to one point in float).
          const double floor_len = kUntangleMinEdge * o_.voxel;
          auto ring_ok = [&](const Vec3& c) {
            double before = std::numbers::pi, after = std::numbers::pi;
            for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i) {
              const Tri& u = t_[inc_[i]];
              before = std::min(before, tri_min_angle(u));
              Vec3 x[3] = {p_[u[0]], p_[u[1]], p_[u[2]]};
              for (int j = 0; j < 3; ++j)
                if (u[j] == v) {
                  if (distance(c, x[(j + 1) % 3]) < floor_len || distance(c, x[(j + 2) % 3]) < floor_len)
                    return false;
                  x[j] = c;
                }
              after = std::min(after, min_angle(x[0], x[1], x[2]));
            }
            return after >= std::min(before, kUntangleMinAngle * kDeg);
          };
          const Vec3 half = p_[v] + 0.5 * (q - p_[v]);
          if (ring_ok(half)) q = half;
          else if (!ring_ok(q)) continue;
          if (!inside_box(q) || (o_.max_error > 0 && !ring_error_ok(v, q))) continue;
          go[v] = 1;
          dest[v] = q;
        }
      });
      std::vector<std::pair<std::uint32_t, Vec3>> moves;
      for (std::uint32_t v = 0; v < p_.size(); ++v)
        if (go[v]) moves.push_back({v, dest[v]});
      std::vector<Vec3> old(moves.size());
      for (std::size_t i = 0; i < moves.size(); ++i) {
        old[i] = p_[moves[i].first];
        moved[moves[i].first] = 1;
        set_position(moves[i].first, moves[i].second);
      }
      // Each move was checked with its neighbours where they were; together the moves of a tiny
      // closed component (every vertex toward the others) shrink it, round after round, into a
      // point (a 4-vertex grain on a noisy scan at spacing 0.7: two vertices in one place, a 0°
      // triangle). The edge floor on the moves' result: a vertex with an edge under it goes
      // back, until none has one. (The angle guard on the result as well undid too many moves:
      // CT head at 100k, 416 → 545 crossing pairs left.)
      {
        std::vector<std::uint8_t> back(moves.size(), 0);
        const double floor_len = kUntangleMinEdge * o_.voxel;
        for (bool changed = true; changed;) {
          changed = false;
          for (std::size_t i = 0; i < moves.size(); ++i) {
            if (back[i]) continue;
            const std::uint32_t v = moves[i].first;
            bool short_edge = false;
            for (std::uint32_t j = inc_off_[v]; j < inc_end_[v] && !short_edge; ++j)
              for (auto w : t_[inc_[j]])
                if (w != v && distance(p_[w], p_[v]) < floor_len) short_edge = true;
            if (!short_edge) continue;
            set_position(v, old[i]);
            back[i] = 1;
            changed = true;
          }
        }
      }
      // Recount: the pairs away from the moved vertices stay as they were.
      for (std::size_t k = 0; k < involved.size(); ++k) {
        const std::uint32_t* c = &m.triangles[3 * k];
        involved[k] = moved[c[0]] | moved[c[1]] | moved[c[2]];
      }
      for (const auto& mv : moves) moved[mv.first] = 0;
      std::optional<PairList> near = intersecting_pairs_involving(m, involved, ctx_);
      PairList next;
      if (near) next = pairs_after_change(pairs, involved, *near);
      if (near && next.size() < cur) {
        // Rounds that remove under 1 % of the pairs move the same stuck vertices again and
        // again (the frog: 48 rounds over 300k pairs, the last 30 removing 0.1–1 % each, a
        // second apiece): the last one is kept and the untangling stops.
        const bool slow = cur - next.size() < cur / 100;
        cur = next.size();
        pairs.swap(next);
        st.untangle_moves += moves.size();
        ring = 0;
        if (slow) break;
      } else {
        for (std::size_t i = 0; i < moves.size(); ++i) set_position(moves[i].first, old[i]);
        if (++ring > 2) break;
      }
    }
    st.intersections_after = cur;
  }

  /// Graded splits for the triangles still under `floor` at the end (docs/QUALITY.md "Rescue",
  /// item 6): a needle whose short edge may not collapse (the link condition fails at a handle a
  /// few hundredths of a voxel wide) keeps its shape under flips, moves and collapses. Splitting
  /// its longest edge halves its long sides (the angle opposite the short edge about doubles),
  /// and Lawson flips around the new vertex (an edge opposite it flips when that raises the
  /// pair's smallest angle) repair the flat triangle the split leaves beside it; rounds repeat
  /// on what is still under the floor, so the neighbourhood grades down to the short edge's
  /// size. Each needle works on its patch (the triangles within two rings of its vertices;
  /// patches of one round do not overlap) and is kept only when the patch got better
  /// (insert_on_edge) and none of its changed triangles crosses another. The new vertex is the
  /// midpoint projected onto the surface on the edge's own side (else the midpoint). Returns
  /// the splits kept; stops after `rounds` rounds or `max_splits` splits.
  std::size_t split_needles(double floor, int rounds, std::size_t max_splits) {
    std::size_t total = 0;
    for (int round = 0; round < rounds && total < max_splits; ++round) {
      tick_.check();
      build_incidence();
      std::vector<std::uint32_t> needles;
      for (std::uint32_t t = 0; t < t_.size(); ++t)
        if (tri_alive_[t] && tri_min_angle(t_[t]) < floor) needles.push_back(t);
      if (needles.empty()) break;
      std::vector<std::uint8_t> taken(t_.size(), 0);  // in a patch of this round
      struct Done {
        std::vector<std::pair<std::uint32_t, Tri>> saved;  // the patch as it was
        std::vector<std::uint32_t> tris;                   // the patch now (with new triangles)
      };
      std::vector<Done> done;
      for (const std::uint32_t t : needles) {
        if (total + done.size() >= max_splits) break;
        if (!tri_alive_[t] || taken[t] || tri_min_angle(t_[t]) >= floor) continue;
        Done d;
        if (!needle_patch(t, taken, d.tris)) continue;
        for (auto u : d.tris) d.saved.push_back({u, t_[u]});
        // The longest edge, else the second longest (the needle's other long side).
        bool ok = false;
        for (int rank = 0; rank < 2 && !ok; ++rank) {
          std::vector<std::uint32_t> tris = d.tris;
          const std::size_t n_before = t_.size();
          if (insert_on_edge(t, rank, floor, tris)) {
            d.tris = std::move(tris);
            ok = true;
            break;
          }
          for (std::size_t u = n_before; u < t_.size(); ++u) tri_alive_[u] = 0;
          for (const auto& [u, old] : d.saved) t_[u] = old;
        }
        if (!ok) continue;
        for (auto u : d.tris) {
          if (u >= taken.size()) taken.resize(u + 1, 0);
          taken[u] = 1;
        }
        done.push_back(std::move(d));
      }
      if (done.empty()) break;
      std::vector<std::int32_t> owner(t_.size(), -1);
      // Only the triangles a needle changed or made count (a patch may hold crossings already).
      for (std::size_t c = 0; c < done.size(); ++c) {
        for (auto u : done[c].tris) owner[u] = static_cast<std::int32_t>(c);
        for (const auto& [u, old] : done[c].saved)
          if (tri_alive_[u] && t_[u] == old) owner[u] = -1;
      }
      const std::vector<std::uint8_t> undo = changes_that_cross(owner, done.size());
      std::size_t kept = 0;
      for (std::size_t c = 0; c < done.size(); ++c) {
        if (!undo[c]) {
          ++kept;
          continue;
        }
        for (auto u : done[c].tris) tri_alive_[u] = 0;  // new ones die; the vertex stays unused
        for (const auto& [u, old] : done[c].saved) t_[u] = old, tri_alive_[u] = 1;
      }
      total += kept;
      if (kept == 0) break;
    }
    build_incidence();
    return total;
  }

  /// The alive triangles within two rings of triangle t's vertices, sorted; false when one of
  /// them is in another patch of the round (`taken`).
  bool needle_patch(std::uint32_t t, const std::vector<std::uint8_t>& taken,
                    std::vector<std::uint32_t>& tris) const {
    tris.clear();
    std::vector<std::uint32_t> vs(t_[t].begin(), t_[t].end());
    const std::size_t indexed = inc_off_.size() - 1;  // the incidence is the round's start
    for (int ring = 0; ring < 2; ++ring) {
      const std::size_t n = vs.size();
      for (std::size_t i = 0; i < n; ++i) {
        // A vertex an earlier split of the round made is in that split's (taken) patch.
        if (vs[i] >= indexed) return false;
        for (std::uint32_t j = inc_off_[vs[i]]; j < inc_end_[vs[i]]; ++j) {
          if (taken[inc_[j]]) return false;
          tris.push_back(inc_[j]);
          for (auto w : t_[inc_[j]]) vs.push_back(w);
        }
      }
      std::sort(vs.begin(), vs.end());
      vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
    }
    std::sort(tris.begin(), tris.end());
    tris.erase(std::unique(tris.begin(), tris.end()), tris.end());
    for (auto u : tris)
      if (taken[u]) return false;
    return true;
  }

  /// Splits needle t's longest edge (rank 0; rank 1: the next longest) inside its patch `tris`
  /// (both triangles of the edge in it) and flips around the new vertex (Lawson: an edge
  /// opposite it whose other triangle is in the patch flips when the pair's smallest angle rises
  /// by 1° and the flip's usual tests pass); true when the patch got better (see the end).
  /// `tris` gains the new triangles. On false the caller restores the patch (the new triangles
  /// are dead).
  bool insert_on_edge(std::uint32_t t, int rank, double floor, std::vector<std::uint32_t>& tris) {
    const double target = o_.target_angle_deg * kDeg;
    double before = std::numbers::pi;
    std::size_t under_before = 0, poor_before = 0;
    for (auto u : tris) {
      const double a = tri_min_angle(t_[u]);
      before = std::min(before, a);
      under_before += a < floor;
      poor_before += a < target;
    }
    // The edge map of the patch: key -> (triangle, side), two entries for an inner edge.
    auto side_of = [&](std::uint32_t u, std::uint32_t a, std::uint32_t b) -> int {
      for (int k = 0; k < 3; ++k)
        if (t_[u][k] == a && t_[u][(k + 1) % 3] == b) return k;
      return -1;
    };
    auto across = [&](std::uint32_t u, std::uint32_t a, std::uint32_t b) -> std::int64_t {
      // The patch triangle with side b -> a (u has a -> b), when exactly one has it.
      std::int64_t found = -1;
      for (auto w : tris) {
        if (w == u || !tri_alive_[w] || side_of(w, b, a) < 0) continue;
        if (found >= 0) return -1;
        found = w;
      }
      return found;
    };
    std::array<int, 3> order{0, 1, 2};
    std::array<double, 3> len{};
    for (int j = 0; j < 3; ++j) len[j] = distance(p_[t_[t][j]], p_[t_[t][(j + 1) % 3]]);
    std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return len[x] > len[y]; });
    const int k = order[rank];
    const std::uint32_t a = t_[t][k], b = t_[t][(k + 1) % 3];
    if (boundary_[a] && boundary_[b]) return false;
    const std::int64_t t2 = across(t, a, b);
    if (t2 < 0) return false;
    const int k2 = side_of(static_cast<std::uint32_t>(t2), b, a);
    const std::size_t first_new = t_.size();
    if (!split_edge(t, static_cast<std::uint8_t>(k), static_cast<std::uint32_t>(t2),
                    static_cast<std::uint8_t>(k2), true))
      return false;
    const std::uint32_t m = static_cast<std::uint32_t>(p_.size() - 1);
    for (std::size_t u = first_new; u < t_.size(); ++u)
      tris.push_back(static_cast<std::uint32_t>(u));
    // Lawson flips around m.
    for (int it = 0, flips = 1; flips > 0 && it < 8; ++it) {
      flips = 0;
      for (std::size_t i = 0; i < tris.size(); ++i) {
        const std::uint32_t u = tris[i];
        if (!tri_alive_[u]) continue;
        const int j = t_[u][0] == m ? 0 : t_[u][1] == m ? 1 : t_[u][2] == m ? 2 : -1;
        if (j < 0) continue;
        const std::uint32_t x = t_[u][(j + 1) % 3], y = t_[u][(j + 2) % 3];  // u: m, x, y
        const std::int64_t w = across(u, x, y);
        if (w < 0) continue;
        const int kw = side_of(static_cast<std::uint32_t>(w), y, x);
        const std::uint32_t z = t_[w][(kw + 2) % 3];
        if (z == m) continue;
        bool exists = false;  // edge m-z (m is new: only patch triangles have it)
        for (auto v : tris)
          if (tri_alive_[v] && (t_[v][0] == m || t_[v][1] == m || t_[v][2] == m) &&
              (t_[v][0] == z || t_[v][1] == z || t_[v][2] == z))
            exists = true;
        if (exists) continue;
        const Vec3 &pm = p_[m], &px = p_[x], &py = p_[y], &pz = p_[z];
        const double old_min = std::min(min_angle(pm, px, py), min_angle(py, px, pz));
        const double new_min = std::min(min_angle(pm, px, pz), min_angle(pm, pz, py));
        if (new_min < old_min + kDeg) continue;
        const Vec3 old_n =
            normalized(tri_normal(pm, px, py)) + normalized(tri_normal(py, px, pz));
        const Vec3 n1 = normalized(tri_normal(pm, px, pz));
        const Vec3 n2 = normalized(tri_normal(pm, pz, py));
        if (dot(n1, old_n) <= 0 || dot(n2, old_n) <= 0 || dot(n1, n2) <= 0) continue;
        if (!flip_within_deviation(px, py, pm, pz)) continue;
        t_[u] = {m, x, z};
        t_[w] = {m, z, y};
        ++flips;
      }
    }
    double after = std::numbers::pi;
    std::size_t under_after = 0, poor_after = 0;
    for (auto u : tris)
      if (tri_alive_[u]) {
        const double a = tri_min_angle(t_[u]);
        after = std::min(after, a);
        under_after += a < floor;
        poor_after += a < target;
      }
    // At most the two new triangles under the target angle (the splits are capped: the share
    // under it rises by at most 0.1 points).
    if (poor_after > poor_before + 2) return false;
    // Kept when the patch's smallest angle rises, or stays while fewer triangles are under the
    // floor (the twin of a back-to-back needle pair, in the same patch, waits for the next one).
    return after > before + 0.1 * kDeg || (after >= before && under_after < under_before);
  }

  std::size_t alive_triangles() const {
    return static_cast<std::size_t>(std::count(tri_alive_.begin(), tri_alive_.end(), 1));
  }

  /// Splits interior edges at their midpoint projected onto the surface until the mesh has
  /// `target` − 1 or `target` triangles: the edges that stand farthest from the surface
  /// (midpoint distance × length) first, at most one split per triangle a pass.
  std::size_t split_pass(std::size_t target) {
    std::size_t splits = 0;
    for (int pass = 0; pass < 8; ++pass) {
      const std::size_t have = alive_triangles();
      if (have + 1 >= target) break;
      std::size_t need = (target - have) / 2;
      struct Cand {
        double key;
        std::uint32_t t1, t2;
        std::uint8_t k1, k2;
      };
      std::vector<Cand> cands;
      for_each_interior_edge([&](std::uint32_t t1, std::uint8_t k1, std::uint32_t t2, std::uint8_t k2) {
        cands.push_back({0.0, t1, t2, k1, k2});
      });
      // Keys in parallel (a distance estimate per edge), then a total order: key, then the edge
      // walk's order (issue 14: the same order as the serial stable sort).
      std::vector<std::uint32_t> order(cands.size());
      parallel_ranges<std::size_t>(0, cands.size(), 1024,
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                            Cand& c = cands[i];
                            const Vec3& a = p_[t_[c.t1][c.k1]];
                            const Vec3& b = p_[t_[c.t1][(c.k1 + 1) % 3]];
                            const double len = distance(a, b);
                            double d = 0;
                            if (field_) d = std::abs(signed_distance(*field_, iso_, 0.5 * (a + b), len));
                            c.key = (d + 1e-3 * o_.voxel) * len * len;
                            order[i] = static_cast<std::uint32_t>(i);
                          }
                        });
      tbb::parallel_sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) {
        return cands[x].key != cands[y].key ? cands[x].key > cands[y].key : x < y;
      });
      {
        std::vector<Cand> sorted(cands.size());
        for (std::size_t i = 0; i < order.size(); ++i) sorted[i] = cands[order[i]];
        cands.swap(sorted);
      }
      std::vector<std::uint8_t> touched(t_.size(), 0);
      std::size_t done = 0;
      for (const Cand& c : cands) {
        if (done == need) break;
        tick_.tick();
        if (touched[c.t1] || touched[c.t2]) continue;
        if (split_edge(c.t1, c.k1, c.t2, c.k2)) {
          touched[c.t1] = touched[c.t2] = 1;
          ++done;
        }
      }
      splits += done;
      if (done == 0) break;
    }
    return splits;
  }

  /// `same_side`: the projected midpoint is used only where ∇f there faces the two triangles
  /// as it does at a and b (at a handle or in a thin wall the nearest surface may be another
  /// sheet); else the midpoint stays on the chord.
  bool split_edge(std::uint32_t t1, std::uint8_t k1, std::uint32_t t2, std::uint8_t k2,
                  bool same_side = false) {
    const std::uint32_t a = t_[t1][k1], b = t_[t1][(k1 + 1) % 3], x = t_[t1][(k1 + 2) % 3];
    const std::uint32_t y = t_[t2][(k2 + 2) % 3];
    if (speck_[a] || speck_[b]) return false;
    Vec3 m = 0.5 * (p_[a] + p_[b]);
    const double len = distance(p_[a], p_[b]);
    Vec3 q = m;
    if (project(q, 0.25 * len) && distance(q, m) < 0.25 * len) {
      bool side_ok = true;
      if (same_side && field_) {
        const Vec3 n = normalized(tri_normal(p_[a], p_[b], p_[x])) +
                       normalized(tri_normal(p_[b], p_[a], p_[y]));
        const double s = dot(n, field_->gradient(q));
        const double sa = dot(n, field_->gradient(p_[a])), sb = dot(n, field_->gradient(p_[b]));
        side_ok = (s > 0 && sa > 0 && sb > 0) || (s < 0 && sa < 0 && sb < 0);
      }
      if (side_ok) m = q;
    }
    if (has_box_ && !inside_box(m)) return false;
    const Vec3 n1 = tri_normal(p_[a], p_[b], p_[x]), n2 = tri_normal(p_[b], p_[a], p_[y]);
    const std::array<std::array<Vec3, 3>, 4> kids{{{p_[a], m, p_[x]}, {m, p_[b], p_[x]},
                                                   {p_[b], m, p_[y]}, {m, p_[a], p_[y]}}};
    for (int i = 0; i < 4; ++i)
      if (dot(tri_normal(kids[i][0], kids[i][1], kids[i][2]), i < 2 ? n1 : n2) <= 0) return false;
    const auto mv = static_cast<std::uint32_t>(p_.size());
    p_.push_back(m);
    fixed_.push_back(0);
    dirty_.push_back(1);
    boundary_.push_back(0);
    speck_.push_back(0);
    t_[t1] = {a, mv, x};
    t_[t2] = {b, mv, y};
    t_.push_back({mv, b, x});
    t_.push_back({mv, a, y});
    tri_alive_.push_back(1);
    tri_alive_.push_back(1);
    return true;
  }

  struct Side {
    std::uint64_t key;
    std::uint32_t t;
    std::uint8_t k;
  };

  /// The sides of the live triangles in (edge key, triangle, side) order.
  std::vector<Side> sorted_sides() const {
    // Sides bucketed by their lower vertex (the key's high word), each bucket sorted by
    // (key, triangle, side): the same total order as one sort of all sides, for any thread
    // count, in linear time plus small sorts (one sort of 3M sides was 5 % of an extract).
    const std::size_t nv = p_.size();
    std::vector<std::uint32_t> start(nv + 1, 0);
    for (std::size_t t = 0; t < t_.size(); ++t)
      if (tri_alive_[t])
        for (int k = 0; k < 3; ++k) ++start[std::min(t_[t][k], t_[t][(k + 1) % 3]) + 1];
    for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
    std::vector<Side> sides(start[nv]);
    {
      std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
      for (std::size_t t = 0; t < t_.size(); ++t)
        if (tri_alive_[t])
          for (std::uint8_t k = 0; k < 3; ++k) {
            const std::uint32_t a = t_[t][k], b = t_[t][(k + 1) % 3];
            sides[fill[std::min(a, b)]++] = {edge_key(a, b), static_cast<std::uint32_t>(t), k};
          }
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t v = r.begin(); v != r.end(); ++v)
                          std::sort(sides.begin() + start[v], sides.begin() + start[v + 1],
                                    [](const Side& a, const Side& b) {
                                      return a.key != b.key ? a.key < b.key
                                             : a.t != b.t   ? a.t < b.t
                                                            : a.k < b.k;
                                    });
                      });
    return sides;
  }

  /// f(t1, k1, t2, k2) for every manifold, consistently oriented interior edge: side k1 of t1
  /// runs a -> b, side k2 of t2 runs b -> a. Edges in key order.
  template <class F>
  void for_each_interior_edge(F&& f) const {
    for_each_interior_edge(sorted_sides(), f);
  }

  template <class F>
  void for_each_interior_edge(const std::vector<Side>& sides, F&& f) const {
    for (std::size_t i = 0; i + 1 < sides.size(); ++i) {
      if (sides[i].key != sides[i + 1].key) continue;
      if (i > 0 && sides[i - 1].key == sides[i].key) continue;
      if (i + 2 < sides.size() && sides[i + 2].key == sides[i].key) continue;
      const Side &s1 = sides[i], &s2 = sides[i + 1];
      if (t_[s2.t][s2.k] != t_[s1.t][(s1.k + 1) % 3] || t_[s2.t][(s2.k + 1) % 3] != t_[s1.t][s1.k])
        continue;
      tick_.tick();
      f(s1.t, s1.k, s2.t, s2.k);
    }
  }

  /// Would flipping the edge of t1 (side k1) and t2 (side k2) to xy pass every test but the
  /// pass's bookkeeping (touched triangles, edges added earlier in the pass)? Reads the mesh only.
  bool flip_ok(std::uint32_t t1, std::uint8_t k1, std::uint32_t t2, std::uint8_t k2,
               const std::vector<std::uint64_t>& existing) const {
    const std::uint32_t a = t_[t1][k1], b = t_[t1][(k1 + 1) % 3], x = t_[t1][(k1 + 2) % 3];
    const std::uint32_t y = t_[t2][(k2 + 2) % 3];
    if (x == y || speck_[a] || speck_[b]) return false;
    const Vec3 &pa = p_[a], &pb = p_[b], &px = p_[x], &py = p_[y];
    const double old_min = std::min(min_angle(pa, pb, px), min_angle(pb, pa, py));
    if (old_min >= (flip_below_ > 0 ? flip_below_ : o_.target_angle_deg * kDeg)) return false;
    const double new_min = std::min(min_angle(pa, py, px), min_angle(pb, px, py));
    if (new_min < old_min + kDeg) return false;
    if (std::binary_search(existing.begin(), existing.end(), edge_key(x, y))) return false;
    const Vec3 old_n = normalized(tri_normal(pa, pb, px)) + normalized(tri_normal(pb, pa, py));
    const Vec3 n1 = normalized(tri_normal(pa, py, px)), n2 = normalized(tri_normal(pb, px, py));
    if (dot(n1, old_n) <= 0 || dot(n2, old_n) <= 0 || dot(n1, n2) <= 0) return false;
    if (!flip_within_deviation(pa, pb, px, py)) return false;
    if (o_.max_error > 0 && field_) {
      const double before = std::max(tri_error(pa, pb, px), tri_error(pb, pa, py));
      const double after = std::max(tri_error(pa, py, px), tri_error(pb, px, py));
      if (after > std::max(o_.max_error / kErrorSafety, before)) return false;
    }
    return true;
  }

  /// One pass of max-min-angle flips over the interior edges in key order; a triangle flips at
  /// most once a pass. The tests (angles, normals, the surface distance of the new edge, the
  /// error bound) run in parallel on the pass's starting mesh: an edge whose two triangles no
  /// earlier flip touched reads exactly that mesh, so applying the results in order gives the
  /// serial pass's flips for any thread count (issue 14).
  std::size_t flip_pass() {
    // Every edge, sorted (the flips must not create one that exists), from the sorted sides.
    const std::vector<Side> sides = sorted_sides();
    std::vector<std::uint64_t> existing;
    existing.reserve(sides.size() / 2 + 1);
    for (const Side& sd : sides)
      if (existing.empty() || existing.back() != sd.key) existing.push_back(sd.key);
    std::vector<FlipEdge> edges;
    edges.reserve(3 * t_.size() / 2);
    for_each_interior_edge(sides, [&](std::uint32_t t1, std::uint8_t k1, std::uint32_t t2, std::uint8_t k2) {
      edges.push_back({t1, t2, k1, k2});
    });
    return flip_edges(edges, existing, 512);
  }

  /// An interior edge: side k1 of triangle t1 and side k2 of t2 (t1 the lower index).
  struct FlipEdge {
    std::uint32_t t1, t2;
    std::uint8_t k1, k2;
  };

  /// The flips of `edges` (in edge-key order) that pass flip_ok — tested in parallel on the
  /// starting mesh, `existing` the sorted keys of the edges a flip could duplicate — applied in
  /// order; an edge whose triangles an earlier flip touched, or whose new edge an earlier flip
  /// made, stays.
  std::size_t flip_edges(const std::vector<FlipEdge>& edges, const std::vector<std::uint64_t>& existing,
                         std::size_t grain) {
    std::vector<std::uint8_t> ok(edges.size(), 0);
    parallel_ranges<std::size_t>(0, edges.size(), grain, [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i)
        ok[i] = flip_ok(edges[i].t1, edges[i].k1, edges[i].t2, edges[i].k2, existing);
    });
    std::unordered_set<std::uint64_t> added;
    std::vector<std::uint8_t> touched(t_.size(), 0);
    std::size_t flips = 0;
    for (std::size_t i = 0; i < edges.size(); ++i) {
      if (!ok[i]) continue;
      const auto [t1, t2, k1, k2] = edges[i];
      if (touched[t1] || touched[t2]) continue;
      const std::uint32_t a = t_[t1][k1], b = t_[t1][(k1 + 1) % 3], x = t_[t1][(k1 + 2) % 3];
      const std::uint32_t y = t_[t2][(k2 + 2) % 3];
      const std::uint64_t kxy = edge_key(x, y);
      if (added.count(kxy)) continue;
      dirty_[a] = dirty_[b] = dirty_[x] = dirty_[y] = 1;
      t_[t1] = {a, y, x};
      t_[t2] = {b, x, y};
      touched[t1] = touched[t2] = 1;
      added.insert(kxy);
      ++flips;
    }
    return flips;
  }

  /// flip_pass() when only pairs with a triangle below `flip_below_` may flip (the rescue's
  /// flips): the same flips in the same order, from the edges of those triangles instead of
  /// every edge (ct_lidc2_chest@100.5 default: 1.4 s of the rescue's 1.5 s of flips were the
  /// walk over every edge). Needs the incidence lists current.
  std::size_t flip_pass_below() {
    const double floor = flip_below_;
    std::vector<std::uint8_t> bad(t_.size(), 0);
    parallel_ranges<std::size_t>(0, t_.size(), 4096, [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t t = r.begin(); t != r.end(); ++t)
        bad[t] = tri_alive_[t] && tri_min_angle(t_[t]) < floor;
    });
    std::vector<std::pair<std::uint64_t, FlipEdge>> keyed;
    for (std::uint32_t t = 0; t < t_.size(); ++t) {
      if (!bad[t]) continue;
      for (std::uint8_t k = 0; k < 3; ++k) {
        const std::uint32_t a = t_[t][k], b = t_[t][(k + 1) % 3];
        // The edge as for_each_interior_edge has it: exactly two sides, opposite, the first one
        // the lower triangle's.
        std::uint32_t u = UINT32_MAX, sides = 0;
        std::uint8_t ku = 0;
        for (std::uint32_t i = inc_off_[a]; i < inc_end_[a]; ++i) {
          const std::uint32_t w = inc_[i];
          for (std::uint8_t j = 0; j < 3; ++j) {
            const std::uint32_t p = t_[w][j], q = t_[w][(j + 1) % 3];
            if ((p == a && q == b) || (p == b && q == a)) {
              ++sides;
              if (w != t) u = w, ku = j;
            }
          }
        }
        if (sides != 2 || u == UINT32_MAX || t_[u][ku] != b) continue;
        keyed.push_back({edge_key(a, b), t < u ? FlipEdge{t, u, k, ku} : FlipEdge{u, t, ku, k}});
      }
    }
    std::sort(keyed.begin(), keyed.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    std::vector<FlipEdge> edges;
    for (std::size_t i = 0; i < keyed.size(); ++i)
      if (i == 0 || keyed[i].first != keyed[i - 1].first) edges.push_back(keyed[i].second);
    // The edges a flip could duplicate: those at the apexes.
    std::vector<std::uint64_t> existing;
    for (const FlipEdge& e : edges)
      for (const std::uint32_t x : {t_[e.t1][(e.k1 + 2) % 3], t_[e.t2][(e.k2 + 2) % 3]})
        for (std::uint32_t i = inc_off_[x]; i < inc_end_[x]; ++i)
          for (auto w : t_[inc_[i]])
            if (w != x) existing.push_back(edge_key(x, w));
    std::sort(existing.begin(), existing.end());
    existing.erase(std::unique(existing.begin(), existing.end()), existing.end());
    return flip_edges(edges, existing, 64);
  }

  bool flip_within_deviation(const Vec3& pa, const Vec3& pb, const Vec3& px, const Vec3& py) const {
    if (!field_) return segment_distance(pa, pb, px, py) <= dev_;
    const double len = distance(px, py);
    const double d_new = surface_distance(0.5 * (px + py), std::max(0.5 * len, o_.voxel));
    if (d_new <= dev_) return true;
    const double d_old = surface_distance(0.5 * (pa + pb), std::max(0.5 * distance(pa, pb), o_.voxel));
    return d_new <= d_old;
  }

  /// Smallest angle over the alive triangles around v, with v at q (radians); sets `flipped`
  /// when a triangle turns by more than ~70° against its normal at the current position.
  double ring_min_angle(std::uint32_t v, const Vec3& q, bool& flipped) const {
    double mn = std::numbers::pi;
    flipped = false;
    for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i) {
      const Tri& t = t_[inc_[i]];
      Vec3 a = p_[t[0]], b = p_[t[1]], c = p_[t[2]];
      const Vec3 n_old = normalized(tri_normal(a, b, c));
      (t[0] == v ? a : t[1] == v ? b : c) = q;
      const Vec3 n_new = normalized(tri_normal(a, b, c));
      if (dot(n_old, n_new) < 0.35) flipped = true;
      mn = std::min(mn, min_angle(a, b, c));
    }
    return mn;
  }

  /// Where a tangential move takes v (toward the mean of the equilateral apexes over its ring's
  /// outer edges, re-projected, with step 1, 1/2, 1/4): false when v stays (fixed, on the
  /// boundary, well shaped already, or no step improves its ring's smallest angle within the
  /// bounds). Reads the mesh only.
  bool plan_move(std::uint32_t v, Vec3& to) const {
    if (fixed_[v] || boundary_[v] || speck_[v] || inc_end_[v] == inc_off_[v]) return false;
    const double target = o_.target_angle_deg * kDeg;
    bool flipped = false;
    const Vec3 pv = p_[v];
    const double old_min = ring_min_angle(v, pv, flipped);
    if (old_min >= target) return false;
    Vec3 n{}, goal{};
    double lmin = std::numeric_limits<double>::max();
    const double w = 1.0 / (inc_end_[v] - inc_off_[v]);
    for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i) {
      const Tri& t = t_[inc_[i]];
      const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      const Vec3 &p = p_[t[(k + 1) % 3]], &q = p_[t[(k + 2) % 3]];
      const Vec3 nt = tri_normal(pv, p, q);
      n += nt;
      const Vec3 e = q - p;
      const double le = norm(e);
      lmin = std::min({lmin, le, distance(pv, p)});
      // The apex of the equilateral triangle on pq, on v's side, in the triangle's plane
      // (counter-clockwise p, q, apex: the in-plane normal of pq pointing left).
      const Vec3 side = normalized(cross(normalized(nt), e));
      goal += w * (0.5 * (p + q) + (std::sqrt(3.0) / 2) * le * (norm2(side) > 0 ? side : Vec3{}));
    }
    n = normalized(n);
    if (norm2(n) == 0) return false;
    // A vertex with a triangle under 20° may travel up to ¾ of the mean length of its edges
    // instead of ¾ of the shortest (not on M0, whose anchors must stay valid starting points):
    // at a cluster of vertices a few hundredths of a voxel apart (a tiny handle or neck of the
    // trilinear surface, whose edges the link condition keeps from collapsing) the short cap let
    // a move grow the cluster's edges by only ¾ per pass (CT head at 20k: 0.75 → 0.67 % under
    // 20°, smallest angle 0.16° → 1.5°; docs/QUALITY.md).
    if (!small_moves_ && old_min < kWideMoveBelowDeg * kDeg) {
      double lsum = 0;
      for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i) {
        const Tri& t = t_[inc_[i]];
        lsum += distance(pv, p_[t[t[0] == v ? 1 : t[1] == v ? 2 : 0]]);
      }
      lmin = std::max(lmin, lsum / (inc_end_[v] - inc_off_[v]));
    }
    for (double lambda : {1.0, 0.5, 0.25}) {
      Vec3 q = pv + lambda * (goal - pv);
      q -= dot(q - pv, n) * n;
      if (!project(q, 0.5 * lmin)) continue;
      if (distance(q, pv) > 0.75 * lmin + 1e-12) continue;
      const double new_min = ring_min_angle(v, q, flipped);
      if (flipped || new_min < old_min + 0.1 * kDeg) continue;
      if (!ring_error_ok(v, q)) continue;
      to = q;
      return true;
    }
    return false;
  }

  /// One pass of tangential moves over the vertices whose ring changed, in index order (a move
  /// makes its ring dirty again: later vertices are looked at in this pass, earlier ones in the
  /// next). The plans of the vertices dirty at the start are made in parallel on the starting
  /// mesh; a vertex whose ring an earlier move of this pass changed is planned again, in order,
  /// so the pass moves exactly what the serial pass would, for any thread count (issue 14).
  /// Vertices `members` (ascending) in waves for a pass that visits them in vertex order and
  /// whose step at a vertex reads and writes only its triangles: each member one past the latest
  /// wave of the earlier members sharing a triangle with it, so members of one wave share none
  /// and the waves in turn, each in parallel, give the serial order's result. Wave k is
  /// order[start[k] .. start[k + 1]), ascending. Needs the incidence lists current.
  void waves_of(const std::vector<std::uint32_t>& members, std::vector<std::uint32_t>& order,
                std::vector<std::uint32_t>& start) const {
    std::vector<std::uint32_t> wave(p_.size(), 0);  // 1 + wave of a member, 0 otherwise
    std::uint32_t waves = 0;
    for (const std::uint32_t v : members) {
      std::uint32_t w = 0;
      for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i)
        for (auto u : t_[inc_[i]])
          if (u < v) w = std::max(w, wave[u]);
      wave[v] = w + 1;
      waves = std::max(waves, w + 1);
    }
    start.assign(waves + 1, 0);
    for (const std::uint32_t v : members) ++start[wave[v]];
    for (std::uint32_t k = 0; k < waves; ++k) start[k + 1] += start[k];
    order.resize(members.size());
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (const std::uint32_t v : members) order[fill[wave[v] - 1]++] = v;
  }

  std::size_t move_pass() {
    build_incidence();
    const std::size_t nv = p_.size();
    // In vertex order, a dirty vertex plans a move from its ring's positions, moves, and marks
    // its ring dirty (ring vertices after it are looked at in this pass). A plan reads only the
    // vertex's triangles, so a vertex waits only for the vertices before it that share one: in
    // waves (each vertex one past the latest wave of its earlier neighbours; those of one wave
    // share no triangle), each wave in parallel, the marks applied after it — the serial result
    // for any thread count. (A parallel plan of every dirty vertex with a serial pass that made
    // again the plans whose ring had moved re-planned more than half on one core.)
    std::vector<std::uint32_t> all(nv), order, start;
    std::iota(all.begin(), all.end(), 0u);
    waves_of(all, order, start);
    std::vector<std::uint8_t> went(nv, 0);
    std::vector<Vec3> before(nv);
    for (std::size_t k = 0; k + 1 < start.size(); ++k) {
      const std::uint32_t b = start[k], e = start[k + 1];
      std::size_t dirty = 0;
      for (std::uint32_t i = b; i < e; ++i) dirty += dirty_[order[i]];
      if (dirty == 0) continue;
      parallel_ranges<std::uint32_t>(b, e, 64, [&](const tbb::blocked_range<std::uint32_t>& r) {
        for (std::uint32_t i = r.begin(); i != r.end(); ++i) {
          const std::uint32_t v = order[i];
          if (!dirty_[v]) continue;
          dirty_[v] = 0;
          Vec3 q;
          if (!plan_move(v, q)) continue;
          before[v] = p_[v];
          went[v] = !small_moves_ && distance(q, p_[v]) > 0.75 * shortest_edge(v) + 1e-12 ? 2 : 1;
          p_[v] = q;
        }
      });
      for (std::uint32_t i = b; i < e; ++i)
        if (went[order[i]]) mark_ring_dirty(order[i]);
    }
    std::vector<std::pair<std::uint32_t, Vec3>> wide;  // long moves and their old positions
    std::size_t moves = 0;
    for (std::uint32_t v = 0; v < nv; ++v) {
      if (!went[v]) continue;
      if (went[v] == 2) wide.push_back({v, before[v]});
      ++moves;
    }
    return moves - undo_crossing_moves(wide);
  }

  double shortest_edge(std::uint32_t v) const {
    double l = std::numeric_limits<double>::max();
    for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i) {
      const Tri& t = t_[inc_[i]];
      for (auto u : t)
        if (u != v) l = std::min(l, distance(p_[v], p_[u]));
    }
    return l;
  }

  /// Undoes the long moves (beyond ¾ of the shortest edge) of a pass that made triangles
  /// intersect: pairs with a triangle around such a vertex that did not intersect before the
  /// pass send the vertex back, until no new pair is left. Returns the moves undone. (The long
  /// moves spread the vertex clusters at tiny handles, and there the surface's sheets are close:
  /// unguarded, they added 60 % to the MRI head's crossing pairs at 20k.)
  std::size_t undo_crossing_moves(const std::vector<std::pair<std::uint32_t, Vec3>>& from) {
    if (from.empty()) return 0;
    using PairList = std::vector<std::pair<std::uint32_t, std::uint32_t>>;
    std::vector<std::uint32_t> id;
    Mesh m = snapshot(id);
    std::vector<std::uint32_t> tri_of(t_.size(), UINT32_MAX);  // t_ index -> mesh triangle
    for (std::uint32_t i = 0; i < id.size(); ++i) tri_of[id[i]] = i;
    std::vector<std::uint8_t> involved(m.num_triangles(), 0);
    for (const auto& [v, old] : from)
      for (std::uint32_t k = inc_off_[v]; k < inc_end_[v]; ++k) involved[tri_of[inc_[k]]] = 1;
    auto set = [&](std::uint32_t v, const Vec3& q) {
      p_[v] = q;
      for (int k = 0; k < 3; ++k) m.positions[3 * v + k] = static_cast<float>(q[k]);
    };
    std::vector<Vec3> now(from.size());
    for (std::size_t i = 0; i < from.size(); ++i) now[i] = p_[from[i].first];
    for (const auto& [v, old] : from) set(v, old);
    const std::optional<PairList> before = intersecting_pairs_involving(m, involved, ctx_);
    for (std::size_t i = 0; i < from.size(); ++i) set(from[i].first, now[i]);
    if (!before) return 0;
    std::vector<std::int32_t> slot(p_.size(), -1);
    for (std::size_t i = 0; i < from.size(); ++i) slot[from[i].first] = static_cast<std::int32_t>(i);
    std::vector<std::uint8_t> undone(from.size(), 0);
    std::size_t count = 0;
    // After the first count only the triangles around the vertices sent back change: the other
    // pairs stay, and the next count asks about those triangles alone (all of them involved).
    std::optional<PairList> after = intersecting_pairs_involving(m, involved, ctx_);
    std::vector<std::uint8_t> changed(m.num_triangles(), 0);
    for (int iter = 0; iter < 32; ++iter) {
      if (!after) break;
      std::fill(changed.begin(), changed.end(), 0);
      bool any = false;
      for (const auto& pr : *after) {
        if (std::binary_search(before->begin(), before->end(), pr)) continue;
        for (auto t : {pr.first, pr.second})
          for (auto v : t_[id[t]])
            if (slot[v] >= 0 && !undone[slot[v]]) {
              undone[slot[v]] = 1;
              set(v, from[slot[v]].second);
              mark_ring_dirty(v);
              for (std::uint32_t k = inc_off_[v]; k < inc_end_[v]; ++k) changed[tri_of[inc_[k]]] = 1;
              ++count;
              any = true;
            }
      }
      if (!any) break;
      const std::optional<PairList> near = intersecting_pairs_involving(m, changed, ctx_);
      if (!near) break;
      after = pairs_after_change(*after, changed, *near);
    }
    return count;
  }

  /// A free vertex of `tri` with three triangles around it is removed and the three become one
  /// (the triangle of its neighbours) when that one is better shaped, not turned over, and within
  /// the deviation bound of the removed vertex.
  bool remove_valence3(const Tri& tri, std::vector<std::uint8_t>& busy) {
    for (std::uint32_t v : tri) {
      if (fixed_[v] || boundary_[v] || speck_[v] || inc_end_[v] - inc_off_[v] != 3) continue;
      // Ring a -> b -> c around v from its three triangles (v, a, b), (v, b, c), (v, c, a).
      std::array<std::uint32_t, 3> next{}, from{};
      for (int i = 0; i < 3; ++i) {
        const Tri& u = t_[inc_[inc_off_[v] + i]];
        const int k = u[0] == v ? 0 : u[1] == v ? 1 : 2;
        from[i] = u[(k + 1) % 3];
        next[i] = u[(k + 2) % 3];
      }
      const std::uint32_t a = from[0], b = next[0];
      std::uint32_t c = UINT32_MAX;
      for (int i = 0; i < 3; ++i)
        if (from[i] == b) c = next[i];
      if (c == UINT32_MAX || c == a || c == b) continue;
      bool low = false;
      for (auto u : {a, b, c}) low |= inc_end_[u] - inc_off_[u] <= 3 || busy[u];
      if (low) continue;
      const Vec3 n = tri_normal(p_[a], p_[b], p_[c]);
      double old_min = std::numbers::pi;
      Vec3 old_n{};
      for (int i = 0; i < 3; ++i) {
        const Tri& u = t_[inc_[inc_off_[v] + i]];
        old_min = std::min(old_min, tri_min_angle(u));
        old_n += normalized(tri_normal(p_[u[0]], p_[u[1]], p_[u[2]]));
      }
      if (dot(normalized(n), normalized(old_n)) < 0.5) continue;
      if (min_angle(p_[a], p_[b], p_[c]) <= old_min) continue;
      if (o_.max_error > 0 && tri_error(p_[a], p_[b], p_[c]) > o_.max_error / kErrorSafety) continue;
      const double height = std::abs(dot(p_[v] - p_[a], normalized(n)));
      if (height > std::max(dev_, 0.25 * std::sqrt(norm(n)))) continue;
      std::uint32_t keep = inc_[inc_off_[v]];
      t_[keep] = {a, b, c};
      dirty_[a] = dirty_[b] = dirty_[c] = 1;
      tri_alive_[inc_[inc_off_[v] + 1]] = tri_alive_[inc_[inc_off_[v] + 2]] = 0;
      busy[v] = busy[a] = busy[b] = busy[c] = 1;
      return true;
    }
    return false;
  }

  void neighbours(std::uint32_t v, std::vector<std::uint32_t>& out) const {
    out.clear();
    for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i)
      for (auto u : t_[inc_[i]])
        if (u != v) out.push_back(u);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

  /// Neighbour lists for the collapse tests (one per thread when they run in parallel).
  struct Rings {
    std::vector<std::uint32_t> na, nb, common;
  };

  /// The tests of collapsing edge ab (b into a; a is not fixed unless b is, see try_collapse)
  /// except the busy marks: the link condition, the merged point q (projected midpoint, a or b,
  /// the best-shaped that passes; a when a is fixed), no triangle turned over, the smallest angle, the error bound. Reads the
  /// mesh only; leaves a's and b's neighbours and their common ones in `r`.
  bool collapse_ok(std::uint32_t a, std::uint32_t b, bool must_improve, double min_after, Vec3& q,
                   Rings& r) const {
    neighbours(a, r.na);
    neighbours(b, r.nb);
    r.common.clear();
    std::set_intersection(r.na.begin(), r.na.end(), r.nb.begin(), r.nb.end(),
                          std::back_inserter(r.common));
    if (r.common.size() != 2) return false;  // link condition
    for (auto c : r.common)
      if (inc_end_[c] - inc_off_[c] <= 3) return false;
    // Where the merged vertex goes: the projected midpoint, else a's or b's own place (both on
    // the surface already), whichever leaves the best smallest angle; a fixed a stays.
    const double len = distance(p_[a], p_[b]);
    std::array<Vec3, 3> at{};
    int n_at = 0;
    if (fixed_[a]) {
      at[n_at++] = p_[a];
    } else {
      Vec3 m = 0.5 * (p_[a] + p_[b]);
      if (project(m, std::max(0.5 * len, o_.voxel))) at[n_at++] = m;
      at[n_at++] = p_[a];
      at[n_at++] = p_[b];
    }
    double old_min = std::numbers::pi;
    for (auto v : {a, b})
      for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i)
        old_min = std::min(old_min, tri_min_angle(t_[inc_[i]]));
    double best = -1;
    for (int c = 0; c < n_at; ++c) {
      const double new_min = merged_min_angle(a, b, at[c]);
      if (new_min <= best) continue;
      if (must_improve ? new_min <= old_min : new_min < std::min(old_min, min_after)) continue;
      if (!ring_error_ok(a, at[c]) || !ring_error_ok(b, at[c])) continue;
      best = new_min;
      q = at[c];
    }
    return best >= 0;
  }

  /// Smallest angle of the triangles around a and b, except the two on ab, with both ends at q;
  /// -1 when one of them turns over.
  double merged_min_angle(std::uint32_t a, std::uint32_t b, const Vec3& q) const {
    double new_min = std::numbers::pi;
    for (auto v : {a, b}) {
      for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i) {
        const Tri& u = t_[inc_[i]];
        const bool has_a = u[0] == a || u[1] == a || u[2] == a;
        const bool has_b = u[0] == b || u[1] == b || u[2] == b;
        if (has_a && has_b) continue;
        Vec3 c0 = p_[u[0]], c1 = p_[u[1]], c2 = p_[u[2]];
        const Vec3 n_old = normalized(tri_normal(c0, c1, c2));
        for (int j = 0; j < 3; ++j)
          if (u[j] == a || u[j] == b) (j == 0 ? c0 : j == 1 ? c1 : c2) = q;
        if (dot(n_old, normalized(tri_normal(c0, c1, c2))) < 0.35) return -1;
        new_min = std::min(new_min, min_angle(c0, c1, c2));
      }
    }
    return new_min;
  }

  /// Which end of ab is kept: a, unless only b is fixed. False when the edge may not collapse
  /// whatever the tests say (a boundary end, both ends fixed).
  bool collapse_ends(std::uint32_t& a, std::uint32_t& b) const {
    if (boundary_[a] || boundary_[b] || speck_[a] || speck_[b] || (fixed_[a] && fixed_[b])) return false;
    if (fixed_[b]) std::swap(a, b);  // keep the fixed end where it is
    return true;
  }

  /// Collapses b into a at q (collapse_ok passed) and marks the touched vertices busy.
  void commit_collapse(std::uint32_t a, std::uint32_t b, const Vec3& q, const Rings& r,
                       std::vector<std::uint8_t>& busy) {
    p_[a] = q;
    for (auto v : r.na) dirty_[v] = 1;
    for (auto v : r.nb) dirty_[v] = 1;
    dirty_[a] = 1;
    for (std::uint32_t i = inc_off_[b]; i < inc_end_[b]; ++i) {
      Tri& u = t_[inc_[i]];
      if (u[0] == a || u[1] == a || u[2] == a) {
        tri_alive_[inc_[i]] = 0;
        continue;
      }
      for (auto& w : u)
        if (w == b) w = a;
    }
    for (auto v : r.na) busy[v] = 1;
    for (auto v : r.nb) busy[v] = 1;
    busy[a] = busy[b] = 1;
  }

  /// Collapses edge ab (b into a, at their projected midpoint, a or b, or at a when a is fixed) when the
  /// link condition holds, no triangle turns over, and the smallest angle around the merged
  /// vertex is above `min_after` (radians) — or, with `must_improve`, above the smallest angle
  /// before. Nothing within the rings of busy vertices; marks the touched vertices busy.
  bool try_collapse(std::uint32_t a, std::uint32_t b, std::vector<std::uint8_t>& busy,
                    bool must_improve, double min_after) {
    if (busy[a] || busy[b] || !collapse_ends(a, b)) return false;
    Vec3 q;
    if (!collapse_ok(a, b, must_improve, min_after, q, rings_)) return false;
    for (auto c : rings_.common)
      if (busy[c]) return false;
    commit_collapse(a, b, q, rings_, busy);
    return true;
  }

  /// The side (k: edge tri[k] -> tri[k + 1]) of a needle's shortest edge, when it is under half
  /// the next; -1 otherwise.
  int needle_side(const Tri& tri) const {
    std::array<double, 3> len{};
    for (int k = 0; k < 3; ++k) len[k] = distance(p_[tri[k]], p_[tri[(k + 1) % 3]]);
    int k = 0;
    for (int j = 1; j < 3; ++j)
      if (len[j] < len[k]) k = j;
    return len[k] < 0.5 * std::min(len[(k + 1) % 3], len[(k + 2) % 3]) ? k : -1;
  }

  std::size_t collapse_pass() {
    build_incidence();
    const double bad = o_.collapse_below_deg * kDeg;
    std::vector<std::uint8_t> busy(p_.size(), 0);
    std::size_t collapses = 0;
    for (std::size_t t = 0; t < t_.size(); ++t) {
      if (!tri_alive_[t]) continue;
      tick_.tick();
      const Tri tri = t_[t];
      if (busy[tri[0]] || busy[tri[1]] || busy[tri[2]]) continue;
      if (tri_min_angle(tri) >= bad) continue;
      if (remove_valence3(tri, busy)) {
        ++collapses;
        continue;
      }
      // Shortest edge (a, b) opposite c; a needle has it well under the other two.
      const int k = needle_side(tri);
      if (k < 0) continue;
      collapses += try_collapse(tri[k], tri[(k + 1) % 3], busy, true, 0);
    }
    return collapses;
  }

 public:
  /// Error quadric (Garland & Heckbert 1997): the symmetric 4×4 matrix Σ area·[n; d][n; d]ᵀ of
  /// the planes n·x + d = 0 of the triangles a vertex stands for, upper triangle row by row.
  using Quadric = std::array<double, 10>;
  static double quadric_cost(const Quadric& q, const Vec3& p) {
    const double x = p.x, y = p.y, z = p.z;
    return q[0] * x * x + 2 * q[1] * x * y + 2 * q[2] * x * z + 2 * q[3] * x + q[4] * y * y +
           2 * q[5] * y * z + 2 * q[6] * y + q[7] * z * z + 2 * q[8] * z + q[9];
  }
  /// The order of decimate()'s collapses: the quadric error of merging a and b (the smaller of
  /// the costs at their midpoint and at either end, with both quadrics summed), plus
  /// kDecimateLengthWeight·voxel²·|ab|², so that flat regions, where every cost is about zero,
  /// still go shortest edge first.
  double collapse_cost(std::uint32_t a, std::uint32_t b) const {
    Quadric q = quad_[a];
    for (int i = 0; i < 10; ++i) q[i] += quad_[b][i];
    const double c = std::min({quadric_cost(q, 0.5 * (p_[a] + p_[b])), quadric_cost(q, p_[a]),
                               quadric_cost(q, p_[b])});
    const double len2 = norm2(p_[a] - p_[b]);
    const double w =
        near_border_[a] || near_border_[b] ? kDecimateBorderWeight : kDecimateLengthWeight;
    return std::max(c, 0.0) + w * o_.voxel * o_.voxel * len2;
  }

  /// Vertices of the triangles that touch a border vertex (which never collapses): their edges
  /// go by length, so the triangles along the volume's faces stay as fine as the border.
  void mark_near_border() {
    near_border_.assign(p_.size(), 0);
    for (std::size_t t = 0; t < t_.size(); ++t) {
      if (!tri_alive_[t]) continue;
      bool touch = false;
      for (auto v : t_[t]) touch |= boundary_[v] || fixed_[v];
      if (touch)
        for (auto v : t_[t]) near_border_[v] = 1;
    }
  }

  /// Each vertex's quadric: the planes of its triangles, weighted by their areas.
  void init_quadrics() {
    quad_.assign(p_.size(), Quadric{});
    for (std::size_t t = 0; t < t_.size(); ++t) {
      if (!tri_alive_[t]) continue;
      const Vec3 &a = p_[t_[t][0]], &b = p_[t_[t][1]], &c = p_[t_[t][2]];
      const Vec3 cr = tri_normal(a, b, c);
      const double area2 = norm(cr);
      if (!(area2 > 0)) continue;
      const Vec3 n = (1.0 / area2) * cr;
      const double d = -dot(n, a), w = 0.5 * area2;
      const double v[4] = {n.x, n.y, n.z, d};
      Quadric q{};
      int i = 0;
      for (int r = 0; r < 4; ++r)
        for (int cidx = r; cidx < 4; ++cidx) q[i++] = w * v[r] * v[cidx];
      for (auto vi : t_[t])
        for (int k = 0; k < 10; ++k) quad_[vi][k] += q[k];
    }
  }

  /// Collapses interior edges (well-shaped collapses only: no triangle below 15° unless it was
  /// there) in the order of collapse_cost() until the mesh has at most `target` triangles. When
  /// nothing collapses above the target, the floor goes down (10°, 5°, 2°): thin tubes (vessels)
  /// leave no well-shaped collapse, and a budget that is not met is worse than the slivers the
  /// run after the decimation removes again (ct_lidc2_chest at 100.5, one component, 5,000
  /// triangles: stuck at 8,494 with the 15° floor alone).
  /// In the order of quadric error while the shape floor holds; a budget that needs collapses
  /// below it starts again from the same mesh in the order of edge length (the shortest edges
  /// hold the slivers those collapses make; by error, ct_lidc2_chest 200.5 at 5k, out of reach
  /// at 8,143 triangles, had RMS 3.49 instead of 2.83).
  std::size_t decimate(std::size_t target) {
    const std::vector<Vec3> p0 = p_;
    const std::vector<Tri> t0 = t_;
    const std::vector<std::uint8_t> alive0 = tri_alive_, dirty0 = dirty_;
    const std::size_t n = decimate_in_order(target, true);
    if (decimate_stuck_at_ == 0) return n;
    const std::size_t stuck = decimate_stuck_at_;
    p_ = p0;
    t_ = t0;
    tri_alive_ = alive0;
    dirty_ = dirty0;
    decimate_stuck_at_ = 0;
    const std::size_t m = decimate_in_order(target, false);
    decimate_stuck_at_ = stuck;  // where the floor stopped (the same mesh, either order)
    return m;
  }

  /// Greedy collapses in the order of the cost (quadric error, or edge length) from one heap:
  /// an edge's entry holds its ends' versions; a collapse bumps the merged vertex's version and
  /// pushes its edges with their new costs. An edge whose tests fail is dropped and waits for a
  /// change next to it (a collapse at a neighbour of either end pushes it again). A sweep ends
  /// when the heap is empty or kDecimateSweep of the triangles went, then flips reshape the
  /// mesh and the next sweep starts from every edge. A sweep without a collapse lowers the
  /// shape floor.
  /// Serial and in a total order (cost, then the edge's key): deterministic.
  std::size_t decimate_in_order(std::size_t target, bool by_error) {
    static constexpr double kFloors[] = {kDecimateShapeFloorDeg, 10, 5, 2};
    std::size_t collapses = 0, floor = 0;
    if (by_error) init_quadrics();
    std::size_t have = alive_triangles();
    struct Entry {
      double cost;
      std::uint64_t key;  // (smaller end << 32) | larger end
      std::uint32_t va, vb;
    };
    auto later = [](const Entry& x, const Entry& y) {
      return x.cost != y.cost ? x.cost > y.cost : x.key > y.key;
    };
    std::vector<std::uint32_t> ver(p_.size(), 0);
    std::vector<std::uint8_t> marks(p_.size(), 0);  // commit_collapse's busy marks, not read here
    std::vector<std::uint8_t> in_ring(p_.size(), 0);
    std::vector<std::uint8_t> parked(p_.size(), 0);  // an edge of the vertex failed its tests
    std::vector<Entry> heap;
    std::vector<std::uint32_t> nbrs, ring;
    std::size_t live = 0;  // heap entries after the last clean-up
    Rings r;
    auto entry = [&](std::uint32_t a, std::uint32_t b) {
      if (a > b) std::swap(a, b);
      return Entry{by_error ? collapse_cost(a, b) : distance(p_[a], p_[b]),
                   (std::uint64_t{a} << 32) | b, ver[a], ver[b]};
    };
    // The interior edges of a (two triangles on it, opposite orientations) into the heap.
    auto push_edges_of = [&](std::uint32_t a) {
      neighbours(a, nbrs);
      for (const std::uint32_t u : nbrs) {
        if (in_ring[u] && u < a) continue;  // pushed from u
        int fwd = 0, bwd = 0;
        for (std::uint32_t i = inc_off_[a]; i < inc_end_[a]; ++i) {
          const Tri& t = t_[inc_[i]];
          for (int k = 0; k < 3; ++k) {
            fwd += t[k] == a && t[(k + 1) % 3] == u;
            bwd += t[k] == u && t[(k + 1) % 3] == a;
          }
        }
        if (fwd != 1 || bwd != 1) continue;
        heap.push_back(entry(a, u));
        std::push_heap(heap.begin(), heap.end(), later);
      }
    };
    // After b went into a: a's list is both lists' alive triangles (at the end of inc_), b's is
    // empty, the two common neighbours lose the triangles that died.
    auto relink = [&](std::uint32_t a, std::uint32_t b) {
      const auto start = static_cast<std::uint32_t>(inc_.size());
      for (const std::uint32_t v : {a, b})
        for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i)
          if (tri_alive_[inc_[i]]) inc_.push_back(inc_[i]);
      inc_off_[a] = start;
      inc_end_[a] = static_cast<std::uint32_t>(inc_.size());
      inc_end_[b] = inc_off_[b];
      for (const std::uint32_t c : r.common) {
        std::uint32_t w = inc_off_[c];
        for (std::uint32_t i = inc_off_[c]; i < inc_end_[c]; ++i)
          if (tri_alive_[inc_[i]]) inc_[w++] = inc_[i];
        inc_end_[c] = w;
      }
    };
    while (have > target && floor < std::size(kFloors)) {
      build_incidence();
      if (by_error) mark_near_border();
      heap.clear();
      for_each_interior_edge([&](std::uint32_t t1, std::uint8_t k1, std::uint32_t, std::uint8_t) {
        heap.push_back(entry(t_[t1][k1], t_[t1][(k1 + 1) % 3]));
      });
      std::make_heap(heap.begin(), heap.end(), later);
      live = heap.size();
      std::fill(parked.begin(), parked.end(), 0);
      std::size_t done = 0;
      // A sweep takes at most kDecimateSweep of the triangles: flips in between keep the
      // neighbourhoods well shaped for the shape floor's tests.
      const auto sweep = static_cast<std::size_t>(kDecimateSweep * static_cast<double>(have));
      const std::size_t stop = std::max(target, have - sweep);
      while (have > stop && !heap.empty()) {
        std::pop_heap(heap.begin(), heap.end(), later);
        const Entry e = heap.back();
        heap.pop_back();
        tick_.tick();
        std::uint32_t a = static_cast<std::uint32_t>(e.key >> 32);
        std::uint32_t b = static_cast<std::uint32_t>(e.key & 0xffffffffu);
        if (ver[a] != e.va || ver[b] != e.vb || !collapse_ends(a, b)) continue;
        Vec3 q;
        if (!collapse_ok(a, b, false, kFloors[floor] * kDeg, q, r)) {
          parked[a] = parked[b] = 1;
          continue;
        }
        commit_collapse(a, b, q, r, marks);
        relink(a, b);
        if (by_error) {
          for (int k = 0; k < 10; ++k) quad_[a][k] += quad_[b][k];
          // As mark_near_border() would now: a's triangles that touch a border vertex.
          for (std::uint32_t i = inc_off_[a]; i < inc_end_[a]; ++i) {
            const Tri& t = t_[inc_[i]];
            bool touch = false;
            for (auto v : t) touch |= boundary_[v] || fixed_[v];
            if (!touch) continue;
            for (auto v : t)
              if (!near_border_[v]) near_border_[v] = 1, parked[v] = 1, ++ver[v];  // new costs
          }
        }
        ++ver[b];
        have -= 2;  // the link condition held: ab had two triangles
        ++done;
        // The moved lists grow inc_: compact it now and then.
        if (inc_.size() > 8 * (inc_off_.size() + 16)) {
          build_incidence();
        }
        // a's edges have new costs; the neighbours' rings changed, so did their edges' tests:
        // those whose test failed (dropped, `parked`) go back into the heap (the others are
        // still in it, at the same cost).
        neighbours(a, nbrs);
        ring.clear();
        for (const std::uint32_t v : nbrs)
          if (parked[v]) ring.push_back(v), parked[v] = 0;
        ring.push_back(a);
        ++ver[a];
        for (const std::uint32_t v : ring) in_ring[v] = 1;
        for (const std::uint32_t v : ring) push_edges_of(v);
        for (const std::uint32_t v : ring) in_ring[v] = 0;
        // Entries of bumped versions pile up: keep the heap within twice the live ones.
        if (heap.size() > 2 * live + 1024) {
          std::erase_if(heap, [&](const Entry& x) {
            return ver[x.key >> 32] != x.va || ver[x.key & 0xffffffffu] != x.vb;
          });
          std::make_heap(heap.begin(), heap.end(), later);
          live = heap.size();
        }
      }
      collapses += done;
      if (have <= target) break;
      if (done == 0) {
        if (floor == 0) decimate_stuck_at_ = have;
        ++floor;
        continue;
      }
      flip_pass();  // better-shaped neighbourhoods let more edges go in the next sweep
    }
    decimate_floor_deg_ = kFloors[std::min(floor, std::size(kFloors) - 1)];
    std::vector<Quadric>().swap(quad_);
    std::vector<std::uint8_t>().swap(near_border_);
    build_incidence();
    return collapses;
  }

  /// Specks (docs/QUALITY.md "Rescue"): a closed component of sphere topology at most
  /// kSpeckVoxels voxels long that still has a triangle below `rescue_below_deg` after the rounds
  /// has no well-shaped mesh on its surface (a grain a few hundredths of a voxel thick): it becomes
  /// a tetrahedron (when it had at most 6 triangles) or an octahedron inscribed in its principal
  /// box, the box's thin sides grown until every angle is at least 25°. The new vertices stay
  /// where they are in the later passes; a speck whose new triangles cross another triangle keeps
  /// its old ones.
  void replace_specks(ImproveStats& st) {
    build_incidence();
    const std::size_t nv = p_.size(), nt0 = t_.size();
    const double floor = o_.rescue_below_deg * kDeg;
    std::vector<std::uint32_t> parent(nv);
    for (std::uint32_t v = 0; v < nv; ++v) parent[v] = v;
    auto find = [&](std::uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (std::size_t t = 0; t < nt0; ++t) {
      if (!tri_alive_[t]) continue;
      for (int k = 1; k < 3; ++k) {
        const std::uint32_t a = find(t_[t][0]), b = find(t_[t][k]);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    }
    std::vector<std::uint32_t> count(nv, 0);
    for (std::size_t t = 0; t < nt0; ++t)
      if (tri_alive_[t]) ++count[find(t_[t][0])];
    std::vector<std::pair<std::uint32_t, std::uint32_t>> members;  // (root, triangle)
    for (std::size_t t = 0; t < nt0; ++t)
      if (tri_alive_[t]) {
        const std::uint32_t r = find(t_[t][0]);
        if (count[r] <= kSpeckMaxTriangles) members.push_back({r, static_cast<std::uint32_t>(t)});
      }
    std::sort(members.begin(), members.end());
    std::vector<SpeckDone> done;
    for (std::size_t i = 0; i < members.size();) {
      std::size_t j = i;
      while (j < members.size() && members[j].first == members[i].first) ++j;
      std::vector<std::uint32_t> tris;
      for (std::size_t k = i; k < j; ++k) tris.push_back(members[k].second);
      i = j;
      tick_.tick();
      if (auto d = speck(tris, floor)) done.push_back(std::move(*d));
    }
    if (done.empty()) return;
    // New triangles that cross others: that speck keeps its old triangles.
    std::vector<std::int32_t> owner(t_.size(), -1);
    for (std::size_t s = 0; s < done.size(); ++s)
      for (std::uint32_t t = done[s].first_tri; t < done[s].first_tri + done[s].n_tris; ++t)
        owner[t] = static_cast<std::int32_t>(s);
    const std::vector<std::uint8_t> undo = changes_that_cross(owner, done.size());
    for (std::size_t s = 0; s < done.size(); ++s) {
      if (!undo[s]) {
        ++st.specks;
        continue;
      }
      ++st.specks_undone;
      for (std::uint32_t t = done[s].first_tri; t < done[s].first_tri + done[s].n_tris; ++t)
        tri_alive_[t] = 0;
      for (auto t : done[s].old_tris) tri_alive_[t] = 1;
    }
    build_incidence();
  }

  struct SpeckDone {
    std::vector<std::uint32_t> old_tris;
    std::uint32_t first_tri, n_tris;
  };

  /// One speck candidate (its alive triangles): replaced when it qualifies (see replace_specks).
  std::optional<SpeckDone> speck(const std::vector<std::uint32_t>& tris, double floor) {
    std::vector<std::uint32_t> vs;
    bool bad = false;
    for (auto t : tris) {
      bad |= tri_min_angle(t_[t]) < floor;
      for (auto v : t_[t]) vs.push_back(v);
    }
    if (!bad) return std::nullopt;
    std::sort(vs.begin(), vs.end());
    vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
    for (auto v : vs)
      if (fixed_[v] || boundary_[v] || speck_[v]) return std::nullopt;
    std::vector<std::uint64_t> edges;
    for (auto t : tris)
      for (int k = 0; k < 3; ++k) edges.push_back(edge_key(t_[t][k], t_[t][(k + 1) % 3]));
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    if (vs.size() + tris.size() != edges.size() + 2) return std::nullopt;  // sphere: V - E + F = 2
    // Principal box of the vertices.
    Vec3 mean{};
    for (auto v : vs) mean += p_[v];
    mean = (1.0 / static_cast<double>(vs.size())) * mean;
    std::array<double, 9> cov{};
    for (auto v : vs) {
      const Vec3 d = p_[v] - mean;
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) cov[3 * r + c] += d[r] * d[c];
    }
    std::array<double, 3> w{};
    std::array<Vec3, 3> ax{};
    symmetric_eigen(cov, w, ax);
    std::array<double, 3> lo{}, hi{};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::numeric_limits<double>::max();
      hi[a] = std::numeric_limits<double>::lowest();
      for (auto v : vs) {
        const double x = dot(p_[v] - mean, ax[a]);
        lo[a] = std::min(lo[a], x);
        hi[a] = std::max(hi[a], x);
      }
    }
    Vec3 centre = mean;
    std::array<double, 3> h{};
    for (int a = 0; a < 3; ++a) {
      centre += (0.5 * (lo[a] + hi[a])) * ax[a];
      h[a] = 0.5 * (hi[a] - lo[a]);
    }
    if (2 * h[0] > kSpeckVoxels * o_.voxel || h[0] <= 0) return std::nullopt;
    const bool tetra = tris.size() <= 6;
    static constexpr std::array<std::array<int, 3>, 4> kTetra = {{{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}}};
    static constexpr std::array<std::array<int, 3>, 8> kOcta = {
        {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}}};
    std::vector<Vec3> q;
    std::vector<std::array<int, 3>> f;
    if (tetra) f.assign(kTetra.begin(), kTetra.end());
    else f.assign(kOcta.begin(), kOcta.end());
    auto build = [&] {
      q.clear();
      if (tetra) {
        for (const auto& sg : {std::array<double, 3>{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}})
          q.push_back(centre + (sg[0] * h[0]) * ax[0] + (sg[1] * h[1]) * ax[1] + (sg[2] * h[2]) * ax[2]);
      } else {
        for (int a = 0; a < 3; ++a) {
          q.push_back(centre + h[a] * ax[a]);
          q.push_back(centre - h[a] * ax[a]);
        }
      }
      // The octahedron's order: +e0, -e0, +e1, -e1, +e2, -e2 (kOcta's numbering).
      double mn = std::numbers::pi;
      for (const auto& tri : f) mn = std::min(mn, min_angle(q[tri[0]], q[tri[1]], q[tri[2]]));
      return mn;
    };
    double mn = build();
    for (int it = 0; it < 60 && mn < kSpeckAngleDeg * kDeg; ++it) {
      int k = 0;
      for (int a = 1; a < 3; ++a)
        if (h[a] < h[k]) k = a;
      h[k] = std::max(1.2 * h[k], 0.02 * h[0]);
      mn = build();
    }
    if (mn < kSpeckAngleDeg * kDeg) return std::nullopt;
    for (const Vec3& x : q)
      if (!inside_box(x)) return std::nullopt;
    if (o_.max_error > 0 && field_) {  // an explicit bound holds (or it is no worse than before)
      double before = 0, after = 0;
      for (auto t : tris) before = std::max(before, tri_error(p_[t_[t][0]], p_[t_[t][1]], p_[t_[t][2]]));
      for (const auto& tri : f) after = std::max(after, tri_error(q[tri[0]], q[tri[1]], q[tri[2]]));
      if (after > std::max(o_.max_error / kErrorSafety, before)) return std::nullopt;
    }
    // Orientation: the speck's triangles enclose a positive or a negative volume; so do the new.
    auto volume = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
      return dot(a - centre, cross(b - centre, c - centre));
    };
    double v_old = 0, v_new = 0;
    for (auto t : tris) v_old += volume(p_[t_[t][0]], p_[t_[t][1]], p_[t_[t][2]]);
    for (const auto& tri : f) v_new += volume(q[tri[0]], q[tri[1]], q[tri[2]]);
    if ((v_old > 0) != (v_new > 0))
      for (auto& tri : f) std::swap(tri[1], tri[2]);
    SpeckDone d;
    d.old_tris = tris;
    d.first_tri = static_cast<std::uint32_t>(t_.size());
    d.n_tris = static_cast<std::uint32_t>(f.size());
    for (auto t : tris) tri_alive_[t] = 0;
    const auto base = static_cast<std::uint32_t>(p_.size());
    for (const Vec3& x : q) {
      p_.push_back(x);
      fixed_.push_back(0);
      dirty_.push_back(0);
      boundary_.push_back(0);
      speck_.push_back(1);
    }
    for (const auto& tri : f) {
      t_.push_back({base + tri[0], base + tri[1], base + tri[2]});
      tri_alive_.push_back(1);
    }
    return d;
  }

  /// Off-surface rescue of the triangles below `rescue_below_deg` (ImproveOptions): their
  /// vertices move in 3-D by compass search (steps along the ring's normal, two tangents and
  /// toward the equilateral apexes; the best that raises the ring's smallest angle within the
  /// bounds is taken, else the step halves), in index order, a few rounds; then the moves that
  /// made triangles intersect go back.
  void rescue(ImproveStats& st) {
    std::vector<std::uint8_t> moved(p_.size(), 0);
    build_incidence();
    rescue_stage(o_.rescue_below_deg * kDeg, 1, moved, st);
    // Last resort for what is still under 10°: four times the deviation bound (a cluster of
    // vertices a few hundredths of a voxel apart at a tiny handle has no well-shaped mesh within
    // a quarter voxel of the surface; CT head at 20k: 5.4° → 10.2°).
    rescue_stage(kRescueLastDeg * kDeg, kRescueLastReach, moved, st);
    st.rescued = static_cast<std::size_t>(std::count(moved.begin(), moved.end(), 1));
  }

  /// The vertices of the triangles below `floor` move (rescue_vertex, the deviation bound times
  /// `widen`) in index order, four rounds; a move that made triangles cross goes back and the
  /// vertex tries again with half the reach (a fold near the vertex often leaves room for a
  /// shorter move), three attempts.

  void rescue_stage(double floor, double widen, std::vector<std::uint8_t>& moved, ImproveStats& st) {
    std::vector<double> reach(p_.size(), std::numeric_limits<double>::infinity());
    for (int attempt = 0; attempt < 3; ++attempt) {
      std::vector<std::pair<std::uint32_t, Vec3>> from;  // vertex, position before this attempt
      std::vector<std::uint8_t> in_from(p_.size(), 0);
      for (int round = 0; round < 4; ++round) {
        tick_.check();
        if (widen > 1) {
          // Flips of the pairs with a triangle below the floor, judged with the wider bound too
          // (a flat cap whose long edge the quarter-voxel test kept: MRI head 1.0°).
          const double dev = dev_;
          dev_ *= widen;
          flip_below_ = floor;
          const std::size_t flips = flip_pass_below();
          dev_ = dev;
          flip_below_ = 0;
          if (flips > 0) build_incidence();
        }
        std::vector<std::uint8_t> below(t_.size(), 0), sel(p_.size(), 0);
        parallel_ranges<std::size_t>(0, t_.size(), 4096, [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t t = r.begin(); t != r.end(); ++t)
            below[t] = tri_alive_[t] && tri_min_angle(t_[t]) < floor;
        });
        for (std::size_t t = 0; t < t_.size(); ++t)
          if (below[t])
            for (auto v : t_[t]) sel[v] = 1;
        // A vertex's search reads only its triangles: in waves (waves_of), the serial result
        // (vertex order) for any thread count.
        std::vector<std::uint32_t> cand, order, start;
        for (std::uint32_t v = 0; v < p_.size(); ++v)
          if (sel[v]) cand.push_back(v);
        waves_of(cand, order, start);
        std::vector<Vec3> before(p_.size());
        std::vector<std::uint8_t> went(p_.size(), 0);
        for (std::size_t k = 0; k + 1 < start.size(); ++k)
          parallel_ranges<std::uint32_t>(start[k], start[k + 1], 8, [&](const tbb::blocked_range<std::uint32_t>& r) {
            for (std::uint32_t i = r.begin(); i != r.end(); ++i) {
              const std::uint32_t v = order[i];
              before[v] = p_[v];
              went[v] = rescue_vertex(v, reach[v], widen);
            }
          });
        std::size_t n = 0;
        for (const std::uint32_t v : cand) {
          if (!went[v]) continue;
          if (!in_from[v]) from.push_back({v, before[v]});
          in_from[v] = 1;
          ++n;
        }
        if (n == 0) break;
      }
      std::vector<Vec3> to(from.size());
      for (std::size_t i = 0; i < from.size(); ++i) to[i] = p_[from[i].first];
      const std::size_t undone = undo_crossing_moves(from);
      for (std::size_t i = 0; i < from.size(); ++i) {
        const std::uint32_t v = from[i].first;
        if (p_[v] == from[i].second) reach[v] = 0.5 * distance(to[i], from[i].second);
        else moved[v] = 1;
      }
      st.rescue_undone += undone;
      if (undone == 0) break;
    }
  }

  /// Which of `n` local changes left a triangle crossing another one: owner[t] is the change
  /// that made alive triangle t (or −1); a change is flagged when one of its triangles is in an
  /// intersecting pair, and every change when the count was not measured (its test budget).
  std::vector<std::uint8_t> changes_that_cross(const std::vector<std::int32_t>& owner,
                                               std::size_t n) const {
    std::vector<std::uint32_t> id;
    const Mesh m = snapshot(id);
    std::vector<std::uint8_t> involved(m.num_triangles(), 0);
    for (std::size_t k = 0; k < id.size(); ++k) involved[k] = owner[id[k]] >= 0;
    const auto pairs = intersecting_pairs_involving(m, involved, ctx_);
    std::vector<std::uint8_t> crossing(n, pairs ? 0 : 1);
    if (pairs)
      for (const auto& [x, y] : *pairs)
        for (auto k : {x, y})
          if (owner[id[k]] >= 0) crossing[owner[id[k]]] = 1;
    return crossing;
  }

  /// Last resort for the triangles still under `floor` after the rescue: the collapse of
  /// whichever of their three edges leaves the best smallest angle around the merged vertex
  /// (collapse_ok's tests: link condition, no valence-3 common neighbour, no triangle turned,
  /// a smallest angle above the one before around both ends, the error bound). The rounds
  /// collapse only a needle's shortest edge; a cap, or a needle whose shortest edge is blocked,
  /// often has another edge that goes (ct_lidc2_chest at 100.5, default mesh: 15 of the 59
  /// triangles under 10°). A collapse after which one of the merged vertex's triangles crosses
  /// another triangle goes back. Returns the collapses kept.
  std::size_t collapse_below(double floor) {
    build_incidence();
    struct Undo {
      std::uint32_t a;
      Vec3 pa;
      std::vector<std::pair<std::uint32_t, Tri>> tris;  // b's triangles as they were
    };
    std::vector<Undo> done;
    std::vector<std::uint8_t> busy(p_.size(), 0);
    for (std::size_t t = 0; t < t_.size(); ++t) {
      if (!tri_alive_[t]) continue;
      const Tri tri = t_[t];
      if (busy[tri[0]] || busy[tri[1]] || busy[tri[2]] || tri_min_angle(tri) >= floor) continue;
      tick_.tick();
      double best = -1;
      std::uint32_t ba = 0, bb = 0;
      for (int k = 0; k < 3; ++k)
        for (int dir = 0; dir < 2; ++dir) {
          std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
          if (dir) std::swap(a, b);
          Vec3 q;
          if (!collapse_ends(a, b) || !collapse_ok(a, b, true, 0, q, rings_)) continue;
          bool free = true;
          for (auto c : rings_.common) free &= !busy[c];
          const double m = merged_min_angle(a, b, q);
          if (free && m > best) {
            best = m;
            ba = a;
            bb = b;
          }
        }
      if (best < 0) continue;
      Vec3 q;
      collapse_ok(ba, bb, true, 0, q, rings_);  // the chosen one's point and rings again
      Undo u{ba, p_[ba], {}};
      for (std::uint32_t i = inc_off_[bb]; i < inc_end_[bb]; ++i)
        u.tris.push_back({inc_[i], t_[inc_[i]]});
      commit_collapse(ba, bb, q, rings_, busy);
      done.push_back(std::move(u));
    }
    if (done.empty()) return 0;
    build_incidence();
    std::vector<std::int32_t> owner(t_.size(), -1);
    for (std::size_t c = 0; c < done.size(); ++c)
      for (std::uint32_t i = inc_off_[done[c].a]; i < inc_end_[done[c].a]; ++i)
        owner[inc_[i]] = static_cast<std::int32_t>(c);
    const std::vector<std::uint8_t> undo = changes_that_cross(owner, done.size());
    std::size_t kept = 0;
    for (std::size_t c = 0; c < done.size(); ++c) {
      if (!undo[c]) {
        ++kept;
        continue;
      }
      p_[done[c].a] = done[c].pa;
      for (const auto& [ti, old] : done[c].tris) {
        t_[ti] = old;
        tri_alive_[ti] = 1;
      }
    }
    build_incidence();
    return kept;
  }

  /// Box faces v lies on (per axis).
  std::array<bool, 3> pinned_axes(std::uint32_t v) const {
    std::array<bool, 3> pinned{};
    if (!has_box_) return pinned;
    if (oblique_) {
      const Vec3 u = grid_index(p_[v]);
      for (int a = 0; a < 3; ++a)
        pinned[a] = std::abs(u[a]) <= face_tol_[a] ||
                    std::abs(u[a] - o_.faces.extent[a]) <= face_tol_[a];
      return pinned;
    }
    for (int a = 0; a < 3; ++a) {
      // On a face: within a float step of it (the stored vertex and the computed face differ
      // by up to half of one).
      const double side = 1e-9 * (o_.box.hi[a] - o_.box.lo[a]);
      const double flo = std::max(side, 0x1p-23 * std::abs(o_.box.lo[a]));
      const double fhi = std::max(side, 0x1p-23 * std::abs(o_.box.hi[a]));
      pinned[a] = std::abs(p_[v][a] - o_.box.lo[a]) <= flo ||
                  std::abs(p_[v][a] - o_.box.hi[a]) <= fhi;
    }
    return pinned;
  }

  /// Border needles: a triangle below the floor whose shortest edge (under half the next) runs
  /// along the mesh boundary between two vertices on the same box face loses that edge — the two
  /// merge at either end or at the midpoint (all on the face), the best-shaped that raises the
  /// smallest angle around them, when the boundary edge's only common neighbour is the opposite
  /// vertex and the boundary loop keeps more than three edges (the topology stays).
  std::size_t collapse_border_needles(double floor) {
    build_incidence();
    std::vector<std::uint8_t> busy(p_.size(), 0);
    std::size_t n = 0;
    for (std::size_t t = 0; t < t_.size(); ++t) {
      if (!tri_alive_[t]) continue;
      const Tri tri = t_[t];
      if (busy[tri[0]] || busy[tri[1]] || busy[tri[2]]) continue;
      const double old_min = tri_min_angle(tri);
      if (old_min >= floor) continue;
      const int k = needle_side(tri);
      if (k < 0) continue;
      std::uint32_t a = tri[k], b = tri[(k + 1) % 3];
      const std::uint32_t c = tri[(k + 2) % 3];
      if (!boundary_[a] || !boundary_[b] || speck_[a] || speck_[b]) continue;
      // ab is a boundary edge: t is its only triangle.
      std::size_t on_ab = 0;
      for (std::uint32_t i = inc_off_[a]; i < inc_end_[a]; ++i) {
        const Tri& u = t_[inc_[i]];
        on_ab += u[0] == b || u[1] == b || u[2] == b;
      }
      if (on_ab != 1 || inc_end_[c] - inc_off_[c] < 2) continue;
      const auto pa = pinned_axes(a), pb = pinned_axes(b);
      const int na = pa[0] + pa[1] + pa[2], nb = pb[0] + pb[1] + pb[2];
      bool same_face = false;
      for (int ax = 0; ax < 3; ++ax) {
        if (!pa[ax] || !pb[ax]) continue;
        same_face |= oblique_ ? std::abs(grid_index(p_[a])[ax] - grid_index(p_[b])[ax]) <=
                                    2 * face_tol_[ax]
                              : p_[a][ax] == p_[b][ax];
      }
      if (!same_face || (na > 1 && nb > 1)) continue;
      if (nb > 1) std::swap(a, b);  // a box-edge vertex stays where it is
      neighbours(a, rings_.na);
      neighbours(b, rings_.nb);
      rings_.common.clear();
      std::set_intersection(rings_.na.begin(), rings_.na.end(), rings_.nb.begin(), rings_.nb.end(),
                            std::back_inserter(rings_.common));
      if (rings_.common.size() != 1) continue;
      // The loop keeps more than three edges: a's and b's other boundary neighbours differ.
      auto other_boundary_neighbour = [&](std::uint32_t x, std::uint32_t y) {
        std::vector<std::uint32_t> nx;
        neighbours(x, nx);
        for (auto w : nx) {
          if (w == y || !boundary_[w]) continue;
          std::size_t shared = 0;
          for (std::uint32_t i = inc_off_[x]; i < inc_end_[x]; ++i) {
            const Tri& u = t_[inc_[i]];
            shared += u[0] == w || u[1] == w || u[2] == w;
          }
          if (shared == 1) return w;
        }
        return UINT32_MAX;
      };
      const std::uint32_t wa = other_boundary_neighbour(a, b), wb = other_boundary_neighbour(b, a);
      if (wa == UINT32_MAX || wa == wb) continue;
      double ring_min = std::numbers::pi;
      for (auto v : {a, b})
        for (std::uint32_t i = inc_off_[v]; i < inc_end_[v]; ++i)
          ring_min = std::min(ring_min, tri_min_angle(t_[inc_[i]]));
      std::array<Vec3, 3> at = {p_[a], p_[b], 0.5 * (p_[a] + p_[b])};
      const int n_at = na > 1 ? 1 : 3;
      double best = ring_min;
      int pick = -1;
      for (int i = 0; i < n_at; ++i) {
        const double m = merged_min_angle(a, b, at[i]);
        if (m <= best || !inside_box(at[i])) continue;
        if (!ring_error_ok(a, at[i]) || !ring_error_ok(b, at[i])) continue;
        best = m;
        pick = i;
      }
      if (pick < 0) continue;
      commit_collapse(a, b, at[pick], rings_, busy);
      ++n;
    }
    if (n) build_incidence();
    return n;
  }

  /// Largest distance to the surface of the points around v with v at q: q, the midpoints of
  /// v's edges and the centroids of its triangles (infinity where a projection fails); once it
  /// exceeds `limit` the rest is not measured (the result is then some value above it). `orient`
  /// (one per triangle around v): the side of the surface each triangle faces, the sign of its
  /// normal against ∇f where its centroid projects (0: unknown); `learn` sets them, else a
  /// triangle that turned to the other side makes the result infinite (a thin speck's triangles
  /// may turn far, which the usual 70° guard forbids, but never inside out).
  double ring_deviation(std::uint32_t v, const Vec3& q, std::vector<std::int8_t>& orient,
                        bool learn, double limit = std::numeric_limits<double>::infinity()) const {
    if (!field_) return 0;
    constexpr double kInf = std::numeric_limits<double>::infinity();
    double e = 0;
    ProjectOptions po;
    po.max_steps = 8;
    po.tolerance = 1e-3 * o_.voxel;
    const std::uint32_t nt = inc_end_[v] - inc_off_[v];
    for (std::uint32_t i = 0; i < nt; ++i) {
      const Tri& t = t_[inc_[inc_off_[v] + i]];
      const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      const Vec3 &a = p_[t[(k + 1) % 3]], &b = p_[t[(k + 2) % 3]];
      const double len = std::max(distance(q, a), distance(q, b));
      po.max_step = std::max(0.5 * len, o_.voxel);
      e = std::max(e, surface_distance(0.5 * (q + a), po.max_step));
      const Vec3 g = (q + a + b) / 3.0;
      const ProjectResult r = project_to_iso(*field_, iso_, g, po);
      if (r.residual > 0.1 * dev_) return kInf;
      e = std::max(e, distance(g, r.point));
      const double side = dot(tri_normal(q, a, b), r.gradient);
      const std::int8_t s = side > 0 ? 1 : side < 0 ? -1 : 0;
      if (learn) orient[i] = s;
      else if (orient[i] != 0 && s != orient[i]) return kInf;
      if (!std::isfinite(e) || e > limit) return e;
    }
    return std::max(e, surface_distance(q, o_.voxel));
  }

  /// One vertex's compass search, at most `reach` from where it is, the deviation bound times
  /// `widen`; true when it moved.
  bool rescue_vertex(std::uint32_t v, double reach, double widen) {
    Vec3 p;
    if (!plan_rescue(v, reach, widen, p)) return false;
    p_[v] = p;
    return true;
  }

  /// rescue_vertex's search without the move: reads only v's triangles (their vertices'
  /// positions), so plans of vertices whose rings did not change are the serial ones.
  bool plan_rescue(std::uint32_t v, double reach, double widen, Vec3& out) const {
    const std::uint32_t nt = inc_end_[v] - inc_off_[v];
    if (nt == 0 || speck_[v]) return false;
    // Box faces a border vertex lies on: it stays on them (slides along its face). A vertex
    // inside the mesh that lies on a face (a placement clamped into the box) may leave it inward:
    // pinned, its flat caps in the face plane stayed (a 0.08° cap on a scan with 0.8 spacing).
    const bool border = fixed_[v] || boundary_[v];
    const std::array<bool, 3> pinned = border ? pinned_axes(v) : std::array<bool, 3>{};
    const bool on_face = pinned[0] || pinned[1] || pinned[2];
    if (border && !on_face) return false;
    const Vec3 start = p_[v];
    // The ring's normals at the start (without a field no triangle may turn by more than ~70°
    // from them; with one, ring_deviation checks the side each faces).
    std::vector<Vec3> n0(nt);
    Vec3 n{};
    double lsum = 0;
    Vec3 goal{};
    for (std::uint32_t i = 0; i < nt; ++i) {
      const Tri& t = t_[inc_[inc_off_[v] + i]];
      const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
      const Vec3 &a = p_[t[(k + 1) % 3]], &b = p_[t[(k + 2) % 3]];
      const Vec3 tn = tri_normal(start, a, b);
      n0[i] = normalized(tn);
      n += tn;
      lsum += distance(start, a);
      const Vec3 e = b - a;
      const Vec3 side = normalized(cross(n0[i], e));
      goal += (1.0 / nt) * (0.5 * (a + b) + (std::sqrt(3.0) / 2) * norm(e) * side);
    }
    n = normalized(n);
    if (norm2(n) == 0) return false;
    auto ring_score = [&](const Vec3& q) {
      double mn = std::numbers::pi;
      for (std::uint32_t i = 0; i < nt; ++i) {
        const Tri& t = t_[inc_[inc_off_[v] + i]];
        Vec3 x[3] = {p_[t[0]], p_[t[1]], p_[t[2]]};
        for (int j = 0; j < 3; ++j)
          if (t[j] == v) x[j] = q;
        const Vec3 tn = normalized(tri_normal(x[0], x[1], x[2]));
        if (!field_ && (dot(tn, n0[i]) < 0.35 || dot(tn, n) <= 0)) return -1.0;
        if (norm2(tn) == 0) return -1.0;
        mn = std::min(mn, min_angle(x[0], x[1], x[2]));
      }
      return mn;
    };
    const double target = o_.target_angle_deg * kDeg;
    double cur = ring_score(start);
    if (cur < 0 || cur >= target) return false;  // before the projections below: they cost
    std::vector<std::int8_t> orient(nt, 0);
    const double dev0 = ring_deviation(v, start, orient, true);
    const double tol = widen * (std::isfinite(dev0) ? std::max(dev_, dev0) : dev_);
    auto admissible = [&](const Vec3& q) {
      if (!inside_box(q) || distance(q, start) > reach) return false;
      if (o_.max_error > 0 && !ring_error_ok(v, q)) return false;
      return ring_deviation(v, q, orient, false, tol) <= tol;
    };
    Vec3 t1 = cross(n, std::abs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0});
    t1 = normalized(t1);
    const Vec3 t2 = cross(n, t1);
    std::array<Vec3, 7> dirs = {t1, -1.0 * t1, t2, -1.0 * t2, n, -1.0 * n, goal - start};
    for (Vec3& d : dirs) {
      for (int a = 0; a < 3; ++a)
        if (pinned[a]) {
          if (oblique_) d = d - dot(d, face_normal_[a]) * face_normal_[a];  // along the face
          else d[a] = 0;
        }
      d = normalized(d);
    }
    double h = 0.25 * lsum / nt;
    const double h_min = 0.02 * h;
    Vec3 p = start;
    for (int it = 0; it < 40 && h >= h_min && cur < target; ++it) {
      std::array<std::pair<double, int>, 7> cand{};
      for (int i = 0; i < 7; ++i) {
        if (norm2(dirs[i]) == 0) {
          cand[i] = {-1, i};
          continue;
        }
        cand[i] = {ring_score(p + h * dirs[i]), i};
      }
      std::sort(cand.begin(), cand.end(), [](const auto& x, const auto& y) {
        return x.first != y.first ? x.first > y.first : x.second < y.second;
      });
      bool step = false;
      for (const auto& [score, i] : cand) {
        if (score < cur + 0.01 * kDeg) break;
        const Vec3 q = p + h * dirs[i];
        if (!admissible(q)) continue;
        p = q;
        cur = score;
        step = true;
        break;
      }
      if (!step) h *= 0.5;
    }
    if (p == start) return false;
    out = p;
    return true;
  }

 private:
  std::vector<std::uint32_t> na_;
  Rings rings_;

};

}  // namespace

namespace {

/// f() with at most context.threads worker threads (the passes' parallel tests).
template <class F>
auto in_arena(const ExecutionContext& context, F&& f) {
  if (context.threads <= 0) return f();
  tbb::task_arena arena(context.threads);
  return arena.execute(std::forward<F>(f));
}

}  // namespace

ImproveStats improve_mesh(Mesh& mesh, const std::vector<std::uint8_t>& fixed,
                          const ScalarField* field, double iso, const ImproveOptions& options,
                          std::vector<std::uint32_t>* vertex_map, const ExecutionContext& context) {
  if (mesh.num_triangles() == 0) return {};
  return in_arena(context, [&] {
    Improver imp(mesh, fixed, field, iso, options, context, "improve");
    const ImproveStats st = imp.run();
    imp.write(mesh, st.collapses + st.specks + st.specks_undone + st.splits > 0, vertex_map);
    mesh.normals.clear();
    return st;
  });
}

std::vector<std::uint8_t> remap_vertex_flags(const std::vector<std::uint8_t>& flags,
                                             const std::vector<std::uint32_t>& vertex_map,
                                             std::size_t num_vertices) {
  std::vector<std::uint8_t> out(num_vertices, 0);
  for (std::size_t v = 0; v < std::min(flags.size(), vertex_map.size()); ++v)
    if (vertex_map[v] < num_vertices) out[vertex_map[v]] = flags[v];
  return out;
}

ImproveStats improve_base_mesh(BaseMesh& base, const ScalarField* field, double iso,
                               const ImproveOptions& options, std::size_t decimate_to,
                               const ExecutionContext& context) {
  std::vector<std::uint32_t> map;
  ImproveStats st;
  if (base.mesh.num_triangles() == 0) return st;
  in_arena(context, [&] {
    Improver imp(base.mesh, base.border, field, iso, options, context, "improve M0");
    imp.keep_moves_small();
    const std::size_t removed = decimate_to > 0 ? imp.decimate(decimate_to) : 0;
    st = imp.run();
    st.decimated = removed;
    st.decimate_floor_deg = imp.decimate_floor_deg();
    st.decimate_stuck_at = imp.decimate_stuck_at();
    imp.write(base.mesh, st.collapses + removed > 0, &map);
    base.mesh.normals.clear();
    return 0;
  });
  auto remap = [&](auto& per_vertex) {
    std::remove_reference_t<decltype(per_vertex)> out(base.mesh.num_vertices());
    for (std::size_t v = 0; v < map.size() && v < per_vertex.size(); ++v)
      if (map[v] != UINT32_MAX) out[map[v]] = per_vertex[v];
    per_vertex = std::move(out);
  };
  remap(base.anchor);
  remap(base.border);
  remap(base.component);
  return st;
}

GridFaces oblique_faces(const Grid& grid) {
  GridFaces f;
  if (grid.axis_aligned()) return f;
  f.to_index = grid.index_to_world_matrix().inverse();
  f.origin = grid.origin;
  f.rounding = grid.float_rounding_in_index();
  for (int a = 0; a < 3; ++a)
    f.extent[a] = static_cast<double>(std::max<std::int64_t>(grid.dims[a] - 1, 0));
  // A flat grid (a single slice): its box.
  if (!(f.extent.x > 0 && f.extent.y > 0 && f.extent.z > 0)) return GridFaces{};
  return f;
}

}  // namespace adamesh
