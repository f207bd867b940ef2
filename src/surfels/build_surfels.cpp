// Surfel complex extraction (ALGORITHM.md 2.2): sign classification, nodes on sign-changing
// edges, face segments (asymptotic decider), cycles = surfels, fans, c-vertices
// (the surfel across a segment is read off the fans when needed: SurfelComplex::opposite).
//
// References: Lorensen & Cline, "Marching Cubes" (SIGGRAPH 1987); Nielson & Hamann, "The
// asymptotic decider" (Visualization 1991); Peixoto & Velho 2002 (surfels, c-vertices).
//
// Passes, parallel over z-slabs with oneTBB, no locks (count -> prefix sum -> fill, as in
// OpenVDB's VolumeToMesh and VTK's Flying Edges):
//   1. count:  per node plane k (edges whose lower endpoint has z = k) the nodes, per voxel layer
//              k the surfels and polygon entries. Signs are classified per plane with two (three)
//              planes resident; a voxel's case is two 4-bit "quad codes" of adjacent planes.
//   2. prefix: plane/layer offsets, so every id is fixed before anything is written.
//   3. fill:   each slab writes its planes' nodes (key order = id order) and its layers' surfels
//              (voxel (z,y,x) order, cycles in configuration order), node_fan slots and
//              node_turn (the fan slot offset of the surfel across an outgoing edge).
//   4. link:   per surfel, c-vertex = mean of its nodes.
// Pass 1 also records each sample row's sign state (one sign or mixed); pass 3 sets the one-sign
// rows without reading the samples and skips rows without nodes or surfels (Flying Edges' trim).
// marching_cubes(volume) runs passes 1–3 with the mesh as the only output: node positions are the
// vertices and each polygon is triangulated in pass 3, so no complex is built.
// Node ids of a plane are found through per-plane arrays (first id, edge mask) (no hashing).
// The result depends only on the data: identical bytes for any thread count or slab split.
#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/surfels.h"
#include "surfels/cell_table.h"
#include "surfels/polygon_triangulator.h"
#include "surfels/sized.h"

namespace adamesh {

namespace {

using detail::CellConfig;

// Sign state of one row of samples (fixed j and k), found by pass 1 and used by pass 3 to skip
// the rows far from the surface (Flying Edges' trimming, per row): all negative, all positive, or
// both signs present.
constexpr std::uint8_t kRowMixed = 2;

struct Counts {
  std::vector<std::int64_t> plane_nodes;    // per node plane
  std::vector<std::int64_t> layer_surfels;  // per voxel layer
  std::vector<std::int64_t> layer_entries;  // per voxel layer
  std::vector<std::uint8_t> rows;           // per row (k, j): 0/1 = all one sign, or kRowMixed
};

template <class T>
class Extractor {
 public:
  Extractor(const Volume& v, double iso, double inside_sign)
      : data_(v.samples<T>()),
        nx_(v.grid.dims[0]),
        ny_(v.grid.dims[1]),
        nz_(v.grid.dims[2]),
        plane_(nx_ * ny_),
        iso_(iso),
        sgn_(inside_sign > 0 ? 1.0 : -1.0),
        origin_(v.grid.origin),
        to_world_(v.grid.index_to_world_matrix()),
        mirrored_(to_world_.determinant() < 0),
        table_(detail::cell_table()),
        thr_(make_threshold(iso, inside_sign > 0)) {
    zeros_.reset(new std::uint8_t[nx_]());
    const auto& edges = detail::cube_edges();
    for (int e = 0; e < 12; ++e) {
      const auto& ce = edges[e];
      edge_offset_[e] = ce.lower[1] * nx_ + ce.lower[0];
      edge_axis_[e] = ce.axis;
      edge_plane_[e] = ce.lower[2];
      edge_slot_[e] = ce.quadrant;
    }
  }

  std::int64_t nz() const { return nz_; }
  std::int64_t ny() const { return ny_; }

  /// Nodes of the node planes [z0, z1) only: counted into counts[k] (write = false), or written
  /// with ids from node_base (write = true), exactly as the fill pass writes them.
  void nodes_only(std::int64_t z0, std::int64_t z1, bool write, std::vector<std::int64_t>& counts,
                  const std::vector<std::int64_t>& node_base, SurfelComplex& out) const {
    std::unique_ptr<std::uint8_t[]> s0(new std::uint8_t[plane_]), s1(new std::uint8_t[plane_]);
    std::unique_ptr<PlaneIds> ids(write ? new PlaneIds(plane_) : nullptr);
    classify(z0, s0.get());
    for (std::int64_t k = z0; k < z1; ++k) {
      const bool top = k + 1 < nz_;
      if (top) classify(k + 1, s1.get());
      if (write)
        plane_nodes(k, s0.get(), top ? s1.get() : nullptr, nullptr, nullptr, node_base[k], *ids,
                    out.node_pos.data() + 3 * node_base[k], out.node_key.data() + node_base[k]);
      else counts[k] = count_plane_nodes(s0.get(), top ? s1.get() : nullptr, nullptr, nullptr);
      std::swap(s0, s1);
    }
  }

  /// Pass 1 over node planes [z0, z1); also the row states of these planes.
  void count(std::int64_t z0, std::int64_t z1, Counts& out) const {
    std::unique_ptr<std::uint8_t[]> s0(new std::uint8_t[plane_]), s1(new std::uint8_t[plane_]);
    std::unique_ptr<std::uint8_t[]> q0(new std::uint8_t[plane_]), q1(new std::uint8_t[plane_]);
    // Row states of planes k and k + 1; written to out.rows only for the planes of the slab.
    std::unique_ptr<std::uint8_t[]> r0(new std::uint8_t[ny_]), r1(new std::uint8_t[ny_]);
    classify_rows(z0, s0.get(), r0.get());
    quads(s0.get(), r0.get(), q0.get());
    for (std::int64_t k = z0; k < z1; ++k) {
      const bool top = k + 1 < nz_;
      if (top) {
        classify_rows(k + 1, s1.get(), r1.get());
        quads(s1.get(), r1.get(), q1.get());
      }
      std::copy(r0.get(), r0.get() + ny_, out.rows.begin() + k * ny_);
      out.plane_nodes[k] = count_plane_nodes(s0.get(), top ? s1.get() : nullptr, r0.get(),
                                             top ? r1.get() : nullptr);
      if (top) {
        std::int64_t surfels = 0, entries = 0;
        auto add = [&](std::int64_t i, std::int64_t j, int c) {
          entries += table_.entries(c);
          surfels += table_.config(c, decisions(c, i, j, k), mirrored_).num_cycles;
        };
        for_active_voxels(q0.get(), q1.get(), r0.get(), r1.get(), add);
        out.layer_surfels[k] = surfels;
        out.layer_entries[k] = entries;
      }
      std::swap(s0, s1);
      std::swap(q0, q1);
      std::swap(r0, r1);
    }
  }

  /// Pass 3 over node planes [z0, z1): nodes of these planes, surfels of these layers, into the
  /// complex `out`; or (`mesh` given) straight into the marching cubes mesh: vertex = node
  /// position, each surfel's triangles where marching_cubes(complex) puts them.
  void fill(std::int64_t z0, std::int64_t z1, const std::vector<std::int64_t>& node_base,
            const std::vector<std::int64_t>& surfel_base,
            const std::vector<std::int64_t>& entry_base,
            const std::vector<std::uint8_t>& row_states, SurfelComplex* out, Mesh* mesh) const {
    auto rows = [&](std::int64_t k) { return row_states.data() + k * ny_; };
    std::unique_ptr<std::uint8_t[]> s0(new std::uint8_t[plane_]), s1(new std::uint8_t[plane_]),
        s2(new std::uint8_t[plane_]);
    std::unique_ptr<std::uint8_t[]> q0(new std::uint8_t[plane_]), q1(new std::uint8_t[plane_]);
    PlaneIds m0(plane_), m1(plane_);
    // Mesh: the nodes of plane z1 belong to the next slab, but the triangles of layer z1 − 1
    // need their positions: computed here too, into a local copy.
    std::vector<float> top_plane;
    if (mesh && z1 < nz_) top_plane.resize(3 * (node_base[z1 + 1] - node_base[z1]));
    // Where plane k's node positions (and keys) go, or nullptr for a plane of the next slab.
    auto targets = [&](std::int64_t k, PlaneIds& ids) {
      ids.base = static_cast<std::uint32_t>(node_base[k]);
      float* pos = nullptr;
      std::uint64_t* keys = nullptr;
      if (mesh) pos = k < z1 ? mesh->positions.data() + 3 * node_base[k] : top_plane.data();
      else if (k < z1) {
        pos = out->node_pos.data() + 3 * node_base[k];
        keys = out->node_key.data() + node_base[k];
      }
      ids.pos = pos;
      return std::pair{pos, keys};
    };
    // Rows of one sign are set without reading the samples, rows whose points have no node (and
    // voxels no surfel) are skipped.
    classify_known(z0, s0.get(), rows(z0));
    quads(s0.get(), rows(z0), q0.get());
    const bool has1 = z0 + 1 < nz_;
    if (has1) classify_known(z0 + 1, s1.get(), rows(z0 + 1));
    {
      const auto [pos, keys] = targets(z0, m0);
      plane_nodes(z0, s0.get(), has1 ? s1.get() : nullptr, rows(z0), has1 ? rows(z0 + 1) : nullptr,
                  node_base[z0], m0, pos, keys);
    }
    for (std::int64_t k = z0; k < z1 && k + 1 < nz_; ++k) {
      // Invariant: s0/s1 = signs of planes k, k+1; q0 = quads of k; m0 = ids of plane k.
      const bool has2 = k + 2 < nz_;
      if (has2) classify_known(k + 2, s2.get(), rows(k + 2));
      quads(s1.get(), rows(k + 1), q1.get());
      const auto [pos, keys] = targets(k + 1, m1);
      plane_nodes(k + 1, s1.get(), has2 ? s2.get() : nullptr, rows(k + 1),
                  has2 ? rows(k + 2) : nullptr, node_base[k + 1], m1, pos, keys);
      if (mesh)
        layer_triangles(k, q0.get(), q1.get(), rows(k), rows(k + 1), m0, m1, surfel_base[k],
                        entry_base[k], mesh->triangles.data());
      else
        layer_surfels(k, q0.get(), q1.get(), rows(k), rows(k + 1), m0, m1, surfel_base[k],
                      entry_base[k], *out);
      std::swap(s0, s1);
      std::swap(s1, s2);
      std::swap(q0, q1);
      std::swap(m0, m1);
    }
  }

 private:
  /// Node ids of one plane, compactly (5 bytes per point instead of 12): the id of the point's
  /// first node in key order and the mask of its sign-changing edges (bit = axis). The node on
  /// edge (p, axis) is first[p] + number of mask bits below `axis`. Entries are written only at
  /// points with nodes, the only ones ever looked up. `pos`: the plane's node positions (3 floats
  /// per node from id `base` on), where the direct marching cubes reads them back.
  struct PlaneIds {
    explicit PlaneIds(std::int64_t n) : first(new std::uint32_t[n]), mask(new std::uint8_t[n]) {}
    std::unique_ptr<std::uint32_t[]> first;
    std::unique_ptr<std::uint8_t[]> mask;
    std::uint32_t id(std::int64_t p, int axis) const {
      static constexpr std::uint8_t kRank[8][3] = {{0, 0, 0}, {0, 1, 1}, {0, 0, 0}, {0, 1, 2},
                                                   {0, 0, 0}, {0, 1, 1}, {0, 0, 1}, {0, 1, 2}};
      return first[p] + kRank[mask[p]][axis];
    }
    Vec3 position(std::uint32_t id) const {
      const float* q = pos + 3 * std::size_t{id - base};
      return {q[0], q[1], q[2]};
    }
    const float* pos = nullptr;
    std::uint32_t base = 0;
  };

  double value(std::int64_t lin) const { return sgn_ * (static_cast<double>(data_[lin]) - iso_); }

  /// Signs of plane k: s[p] = 1 when positive. Compares in the sample type against the exact
  /// threshold (see Threshold), so the loop vectorises.
  void classify(std::int64_t k, std::uint8_t* s) const { classify_range(k * plane_, plane_, s); }

  void classify_range(std::int64_t first, std::int64_t n, std::uint8_t* s) const {
    // Locals and restrict: uint8_t stores may alias anything, members included.
    const T* __restrict src = data_ + first;
    std::uint8_t* __restrict out = s;
    if (thr_.constant >= 0) {
      std::memset(out, thr_.constant, static_cast<std::size_t>(n));
      return;
    }
    const T t = thr_.value;
    if (sgn_ > 0) {
      for (std::int64_t p = 0; p < n; ++p) out[p] = src[p] >= t;
    } else {
      for (std::int64_t p = 0; p < n; ++p) out[p] = src[p] <= t;
    }
  }

  /// classify(), and the state of each row into rows[j] (0/1: all of that sign, or kRowMixed).
  void classify_rows(std::int64_t k, std::uint8_t* s, std::uint8_t* rows) const {
    classify(k, s);
    for (std::int64_t j = 0; j < ny_; ++j) {
      const std::uint8_t* a = s + j * nx_;
      const std::int64_t positive = count_differences(a, zeros_.get(), nx_);
      rows[j] = positive == 0 ? 0 : (positive == nx_ ? 1 : kRowMixed);
    }
  }

  /// classify() with the row states known: rows of one sign are set, not computed.
  void classify_known(std::int64_t k, std::uint8_t* s, const std::uint8_t* rows) const {
    for (std::int64_t j = 0; j < ny_; ++j) {
      if (rows[j] != kRowMixed) std::memset(s + j * nx_, rows[j], static_cast<std::size_t>(nx_));
      else classify_range(k * plane_ + j * nx_, nx_, s + j * nx_);
    }
  }

  /// Does no point of row j of a plane (row states r, r_up of the plane above, null on the last
  /// plane) have a node, i.e. rows j, j + 1 and j of the plane above all of one sign?
  bool nodeless_row(const std::uint8_t* r, const std::uint8_t* r_up, std::int64_t j) const {
    if (!r || r[j] == kRowMixed) return false;
    if (j + 1 < ny_ && r[j + 1] != r[j]) return false;
    return !r_up || r_up[j] == r[j];
  }

  /// Is every voxel of row j of a layer (row states r0, r1 of its planes) on one side?
  static bool empty_voxel_row(const std::uint8_t* r0, const std::uint8_t* r1, std::int64_t j) {
    return r0[j] != kRowMixed && r0[j + 1] == r0[j] && r1[j] == r0[j] && r1[j + 1] == r0[j];
  }

  /// For samples of type T: f ≥ iso ⇔ f ≥ value (inside_sign +1), f ≤ iso ⇔ f ≤ value (−1),
  /// exactly as the comparison of double(f) with iso. `constant` is 0/1 when no sample value
  /// can be on the other side (threshold outside T's range), else −1.
  struct Threshold {
    T value{};
    int constant = -1;
  };

  static Threshold make_threshold(double iso, bool ge) {
    Threshold t;
    if constexpr (std::is_integral_v<T>) {
      const double r = ge ? std::ceil(iso) : std::floor(iso);
      const double lo = static_cast<double>(std::numeric_limits<T>::min());
      const double hi = static_cast<double>(std::numeric_limits<T>::max());
      if (r > hi) t.constant = ge ? 0 : 1;
      else if (r < lo) t.constant = ge ? 1 : 0;
      else t.value = static_cast<T>(r);
    } else if constexpr (std::is_same_v<T, float>) {
      float f = static_cast<float>(iso);  // nearest; step to the closest float on iso's side
      if (ge && static_cast<double>(f) < iso) f = std::nextafter(f, std::numeric_limits<float>::infinity());
      if (!ge && static_cast<double>(f) > iso) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
      t.value = f;
    } else {
      t.value = static_cast<T>(iso);
    }
    return t;
  }

  void quads(const std::uint8_t* s, const std::uint8_t* rows, std::uint8_t* q) const {
    const std::int64_t nx = nx_, ny = ny_;
    for (std::int64_t j = 0; j + 1 < ny; ++j) {
      if (rows[j] != kRowMixed && rows[j + 1] == rows[j]) {
        std::memset(q + j * nx, rows[j] ? 15 : 0, static_cast<std::size_t>(nx - 1));
        continue;
      }
      const std::uint8_t* __restrict a = s + j * nx;
      const std::uint8_t* __restrict b = a + nx;
      std::uint8_t* __restrict out = q + j * nx;
      for (std::int64_t i = 0; i + 1 < nx; ++i)
        out[i] = static_cast<std::uint8_t>(a[i] | (a[i + 1] << 1) | (b[i] << 2) | (b[i + 1] << 3));
    }
  }

  /// Number of positions where two 0/1 byte arrays differ, 8 bytes at a time.
  static std::int64_t count_differences(const std::uint8_t* a, const std::uint8_t* b,
                                        std::int64_t n) {
    std::int64_t c = 0, i = 0;
    for (; i + 8 <= n; i += 8) {
      std::uint64_t wa, wb;
      std::memcpy(&wa, a + i, 8);
      std::memcpy(&wb, b + i, 8);
      // Bytes are 0/1: their sum is the top byte of the product (no popcnt on baseline x86-64).
      c += static_cast<std::int64_t>(((wa ^ wb) * 0x0101010101010101ull) >> 56);
    }
    for (; i < n; ++i) c += a[i] ^ b[i];
    return c;
  }

  /// Nodes of a plane (signs s, of the plane above up, null on the last plane), skipping the
  /// nodeless rows when the row states are given.
  std::int64_t count_plane_nodes(const std::uint8_t* s, const std::uint8_t* up,
                                 const std::uint8_t* r, const std::uint8_t* r_up) const {
    std::int64_t n = 0;
    for (std::int64_t j = 0; j < ny_; ++j) {
      if (nodeless_row(r, r_up, j)) continue;
      const std::uint8_t* a = s + j * nx_;
      n += count_differences(a, a + 1, nx_ - 1);                 // x edges
      if (j + 1 < ny_) n += count_differences(a, a + nx_, nx_);  // y edges
      if (up) n += count_differences(a, up + j * nx_, nx_);      // z edges
    }
    return n;
  }

  /// Calls f(i, j, case) for the voxels of a layer with a sign change, in (j, i) order; q0/q1
  /// are the quad codes of its bottom and top planes. Runs of 8 empty voxels (all corners of one
  /// sign) are skipped with one 64-bit test, rows of such voxels (row states r0, r1) at once.
  template <class F>
  void for_active_voxels(const std::uint8_t* q0, const std::uint8_t* q1, const std::uint8_t* r0,
                         const std::uint8_t* r1, F&& f) const {
    constexpr std::uint64_t kFull = 0x0F0F0F0F0F0F0F0Full;
    const std::int64_t n = nx_ - 1;
    for (std::int64_t j = 0; j + 1 < ny_; ++j) {
      if (empty_voxel_row(r0, r1, j)) continue;
      const std::uint8_t* a = q0 + j * nx_;
      const std::uint8_t* b = q1 + j * nx_;
      for (std::int64_t i0 = 0; i0 < n; i0 += 8) {
        const std::int64_t m = std::min<std::int64_t>(8, n - i0);
        if (m == 8) {
          std::uint64_t wa, wb;
          std::memcpy(&wa, a + i0, 8);
          std::memcpy(&wb, b + i0, 8);
          if ((wa | wb) == 0 || (wa & wb) == kFull) continue;
        }
        for (std::int64_t i = i0; i < i0 + m; ++i) {
          const int c = a[i] | (b[i] << 4);
          if (c != 0 && c != 255) f(i, j, c);
        }
      }
    }
  }

  /// Decision bits for the ambiguous faces of a voxel (asymptotic decider on face values).
  unsigned decisions(int c, std::int64_t i, std::int64_t j, std::int64_t k) const {
    const unsigned amb = table_.ambiguous(c);
    if (!amb) return 0;
    const std::int64_t base = i + nx_ * (j + ny_ * k);
    double v[8];
    for (int corner = 0; corner < 8; ++corner)
      v[corner] =
          value(base + (corner & 1) + ((corner >> 1) & 1) * nx_ + ((corner >> 2) & 1) * plane_);
    unsigned bits = 0;
    const auto& faces = detail::cube_faces();
    for (int f = 0; f < 6; ++f) {
      if (!(amb & (1u << f))) continue;
      const auto& fc = faces[f].corner;
      if (detail::positive_diagonal_connected(v[fc[0]], v[fc[1]], v[fc[2]], v[fc[3]]))
        bits |= 1u << f;
    }
    return bits;
  }

  /// Ids of plane k's nodes in key order (j, i, axis) into `ids`; the positions of the nodes from
  /// id `base` on into `pos` (3 floats each) unless it is null, their keys into `keys` unless
  /// that is null.
  /// Row states r, r_up (null: none known) let it skip the nodeless rows.
  void plane_nodes(std::int64_t k, const std::uint8_t* s, const std::uint8_t* up,
                   const std::uint8_t* r, const std::uint8_t* r_up, std::int64_t base,
                   PlaneIds& ids, float* pos, std::uint64_t* keys) const {
    auto id = static_cast<std::uint32_t>(base);
    const std::int64_t plane_lin = k * plane_;
    auto emit = [&](std::int64_t p, std::int64_t i, std::int64_t j, int axis) {
      if (pos) {
        const std::int64_t lin0 = plane_lin + p;
        const std::int64_t lin1 = lin0 + (axis == 0 ? 1 : (axis == 1 ? nx_ : plane_));
        const double v0 = value(lin0), v1 = value(lin1);
        double t = v0 / (v0 - v1);
        if (!(t == t)) t = 0.5;  // NaN samples: deterministic midpoint
        t = std::clamp(t, SurfelComplex::kNodeEps, 1.0 - SurfelComplex::kNodeEps);
        Vec3 ijk{static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)};
        ijk[axis] += t;
        const Vec3 w = origin_ + to_world_ * ijk;  // == Grid::to_world(ijk)
        const std::size_t local = id - static_cast<std::uint32_t>(base);
        if (keys)
          keys[local] = 3 * static_cast<std::uint64_t>(lin0) + static_cast<std::uint64_t>(axis);
        pos[3 * local] = static_cast<float>(w.x);
        pos[3 * local + 1] = static_cast<float>(w.y);
        pos[3 * local + 2] = static_cast<float>(w.z);
      }
      ++id;
    };
    for (std::int64_t j = 0; j < ny_; ++j) {
      if (nodeless_row(r, r_up, j)) continue;
      const std::int64_t row = j * nx_;
      const std::uint8_t* a = s + row;
      const std::uint8_t* b = j + 1 < ny_ ? a + nx_ : a;  // no y edges on the last row
      const std::uint8_t* c = up ? up + row : a;          // no z edges on the last plane
      for (std::int64_t i = 0; i < nx_; ++i) {
        if (i + 9 <= nx_) {  // eight points whose x edges all lie in the row
          std::uint64_t wa, wa1, wb, wc;
          std::memcpy(&wa, a + i, 8);
          std::memcpy(&wa1, a + i + 1, 8);
          std::memcpy(&wb, b + i, 8);
          std::memcpy(&wc, c + i, 8);
          if (((wa ^ wa1) | (wa ^ wb) | (wa ^ wc)) == 0) {
            i += 7;
            continue;
          }
        }
        const std::uint8_t si = a[i];
        const bool ex = i + 1 < nx_ && si != a[i + 1];
        const bool ey = si != b[i];
        const bool ez = si != c[i];
        if (!(ex | ey | ez)) continue;
        ids.first[row + i] = id;
        ids.mask[row + i] = static_cast<std::uint8_t>(ex | (ey << 1) | (ez << 2));
        if (ex) emit(row + i, i, j, 0);
        if (ey) emit(row + i, i, j, 1);
        if (ez) emit(row + i, i, j, 2);
      }
    }
  }

  void layer_surfels(std::int64_t k, const std::uint8_t* q0, const std::uint8_t* q1,
                     const std::uint8_t* r0, const std::uint8_t* r1, const PlaneIds& m0,
                     const PlaneIds& m1, std::int64_t surfel_base, std::int64_t entry_base,
                     SurfelComplex& out) const {
    auto s = static_cast<std::int32_t>(surfel_base);
    auto entry = static_cast<std::uint32_t>(entry_base);
    const PlaneIds* maps[2] = {&m0, &m1};
    for_active_voxels(q0, q1, r0, r1, [&](std::int64_t i, std::int64_t j, int c) {
      const std::int64_t p = j * nx_ + i;
      const CellConfig& cfg = table_.config(c, decisions(c, i, j, k), mirrored_);
      const auto voxel = static_cast<std::uint64_t>(k * plane_ + p);
      int idx = 0;
      for (int cy = 0; cy < cfg.num_cycles; ++cy, ++s) {
        out.surfel_offset[s] = entry;
        out.surfel_voxel[s] = voxel;
        for (int n = 0; n < cfg.cycle_len[cy]; ++n, ++idx, ++entry) {
          const int e = cfg.edge[idx];
          const std::uint32_t node = maps[edge_plane_[e]]->id(p + edge_offset_[e], edge_axis_[e]);
          out.surfel_nodes[entry] = node;
          out.node_fan[node][edge_slot_[e]] = s;
          // The same for every surfel of the node; written from the voxel layer of the node's
          // own plane (one slab, no concurrent writes), from below on the top plane.
          if (edge_plane_[e] == 0 || k + 2 == nz_)
            out.node_turn[node] =
                static_cast<std::uint8_t>((cfg.opposite_quadrant[idx] - edge_slot_[e]) & 3);
        }
      }
    });
  }

  /// The direct marching cubes' layer_surfels: the triangles of layer k's surfels, at the place
  /// and in the order marching_cubes(complex) writes them (surfel s with its first polygon entry
  /// e: from triangle e − 2s on), triangulated by the same code from the same node positions.
  void layer_triangles(std::int64_t k, const std::uint8_t* q0, const std::uint8_t* q1,
                       const std::uint8_t* r0, const std::uint8_t* r1, const PlaneIds& m0,
                       const PlaneIds& m1, std::int64_t surfel_base, std::int64_t entry_base,
                       std::uint32_t* triangles) const {
    std::int64_t tri = entry_base - 2 * surfel_base;  // first triangle of the layer
    const PlaneIds* maps[2] = {&m0, &m1};
    detail::PolygonTriangulator triangulator;
    std::array<Vec3, detail::kMaxPolygonNodes> p;
    std::array<int, detail::kMaxPolygonNodes> local_edge;
    std::array<std::uint32_t, detail::kMaxPolygonNodes> ids;
    for_active_voxels(q0, q1, r0, r1, [&](std::int64_t i, std::int64_t j, int c) {
      const std::int64_t point = j * nx_ + i;
      const CellConfig& cfg = table_.config(c, decisions(c, i, j, k), mirrored_);
      int idx = 0;
      for (int cy = 0; cy < cfg.num_cycles; ++cy) {
        const int len = cfg.cycle_len[cy];
        std::uint32_t* t = triangles + 3 * tri;
        tri += len - 2;
        if (len == 3) {
          for (int n = 0; n < 3; ++n, ++idx) {
            const int e = cfg.edge[idx];
            t[n] = maps[edge_plane_[e]]->id(point + edge_offset_[e], edge_axis_[e]);
          }
          continue;
        }
        for (int n = 0; n < len; ++n, ++idx) {
          const int e = cfg.edge[idx];
          const PlaneIds& m = *maps[edge_plane_[e]];
          ids[n] = m.id(point + edge_offset_[e], edge_axis_[e]);
          p[n] = m.position(ids[n]);
          local_edge[n] = e;
        }
        triangulator.run(len, p, local_edge, t, ids.data());
      }
    });
  }

  const T* data_;
  std::int64_t nx_, ny_, nz_, plane_;
  std::unique_ptr<std::uint8_t[]> zeros_;  // nx_ zero bytes (classify_rows counts against it)
  double iso_, sgn_;
  Vec3 origin_;
  Mat3 to_world_;
  bool mirrored_;
  const detail::CellTable& table_;
  Threshold thr_;
  std::int64_t edge_offset_[12];  // point offset of the edge's lower endpoint in its plane
  int edge_axis_[12];
  int edge_plane_[12];
  int edge_slot_[12];
};

void check_id_range(std::int64_t n, std::int64_t limit, const char* what) {
  if (n > limit)
    fail(Status::unsupported, std::string("build_surfels: too many ") + what + " (" +
                                  std::to_string(n) + "); split the volume");
}

/// Runs fn(z0, z1) in parallel over z-slabs of [0, nz): a few per thread for balance; each costs
/// one or two extra plane classifications. The partition depends only on nz and threads.
template <class Fn>
void for_each_slab(std::int64_t nz, int threads, Fn&& fn) {
  const std::int64_t nslabs =
      std::clamp<std::int64_t>(4 * threads, 1, std::max<std::int64_t>(nz / 4, 1));
  tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, nslabs, 1), [&](const auto& r) {
    for (std::int64_t s = r.begin(); s < r.end(); ++s) fn(nz * s / nslabs, nz * (s + 1) / nslabs);
  });
}

/// Passes 1 and 2: the first node, surfel and polygon entry of every plane / layer (size nz + 1).
struct Layout {
  std::vector<std::int64_t> node_base, surfel_base, entry_base;
  std::vector<std::uint8_t> rows;  // row states (Counts::rows)
};

template <class T>
Layout layout(const Extractor<T>& ex, int threads) {
  const std::int64_t nz = ex.nz();
  Counts counts;
  counts.plane_nodes.assign(nz, 0);
  counts.layer_surfels.assign(nz, 0);
  counts.layer_entries.assign(nz, 0);
  counts.rows.assign(nz * ex.ny(), 0);
  for_each_slab(nz, threads, [&](std::int64_t z0, std::int64_t z1) {
    ex.count(z0, z1, counts);
  });

  Layout l;
  l.node_base.assign(nz + 1, 0);
  l.surfel_base.assign(nz + 1, 0);
  l.entry_base.assign(nz + 1, 0);
  for (std::int64_t k = 0; k < nz; ++k) {
    l.node_base[k + 1] = l.node_base[k] + counts.plane_nodes[k];
    l.surfel_base[k + 1] = l.surfel_base[k] + counts.layer_surfels[k];
    l.entry_base[k + 1] = l.entry_base[k] + counts.layer_entries[k];
  }
  check_id_range(l.node_base[nz], std::numeric_limits<std::int32_t>::max(), "nodes");
  check_id_range(l.surfel_base[nz], std::numeric_limits<std::int32_t>::max() - 1, "surfels");
  check_id_range(l.entry_base[nz], std::numeric_limits<std::uint32_t>::max() - 1,
                 "polygon entries");
  l.rows = std::move(counts.rows);
  return l;
}

template <class T>
void extract(const Volume& volume, SurfelComplex& out, int threads) {
  const Extractor<T> ex(volume, out.iso, out.inside_sign);
  const std::int64_t nz = ex.nz();
  const Layout l = layout(ex, threads);
  const std::int64_t num_nodes = l.node_base[nz], num_surfels = l.surfel_base[nz],
                     num_entries = l.entry_base[nz];

  // First touch of the large arrays costs more than the passes themselves: fault them in
  // concurrently, with transparent huge pages where the kernel allows.
  tbb::parallel_invoke([&] { detail::sized(out.node_key, num_nodes); },
                       [&] { detail::sized(out.node_pos, 3 * num_nodes); },
                       [&] {
                         detail::sized(out.node_fan, num_nodes, {-1, -1, -1, -1});
                       },
                       [&] { detail::sized(out.node_turn, num_nodes); },
                       [&] { detail::sized(out.surfel_offset, num_surfels + 1); },
                       [&] { detail::sized(out.surfel_nodes, num_entries); },
                       [&] { detail::sized(out.surfel_voxel, num_surfels); },
                       [&] { detail::sized(out.cvertex, 3 * num_surfels); });
  out.surfel_offset[num_surfels] = static_cast<std::uint32_t>(num_entries);

  for_each_slab(nz, threads, [&](std::int64_t z0, std::int64_t z1) {
    ex.fill(z0, z1, l.node_base, l.surfel_base, l.entry_base, l.rows, &out, nullptr);
  });

  // Link pass: c-vertices from the node positions.
  tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, num_surfels, 4096), [&](const auto& r) {
    for (std::int64_t s = r.begin(); s < r.end(); ++s) {
      const std::uint32_t b = out.surfel_offset[s], e = out.surfel_offset[s + 1];
      double sum[3] = {0, 0, 0};
      for (std::uint32_t x = b; x < e; ++x) {
        const std::uint32_t n = out.surfel_nodes[x];
        for (int a = 0; a < 3; ++a) sum[a] += out.node_pos[3 * std::size_t{n} + a];
      }
      for (int a = 0; a < 3; ++a)
        out.cvertex[3 * s + a] = static_cast<float>(sum[a] / static_cast<double>(e - b));
    }
  });
}

/// The direct marching cubes: passes 1–3 with the mesh as the only output.
template <class T>
void extract_mesh(const Volume& volume, double iso, double inside_sign, int threads, Mesh& mesh,
                  std::size_t& num_surfels) {
  const Extractor<T> ex(volume, iso, inside_sign);
  const std::int64_t nz = ex.nz();
  const Layout l = layout(ex, threads);
  const std::int64_t num_nodes = l.node_base[nz];
  num_surfels = static_cast<std::size_t>(l.surfel_base[nz]);
  const std::int64_t num_triangles = l.entry_base[nz] - 2 * l.surfel_base[nz];
  tbb::parallel_invoke([&] { detail::sized(mesh.positions, 3 * num_nodes); },
                       [&] { detail::sized(mesh.triangles, 3 * num_triangles); });
  for_each_slab(nz, threads, [&](std::int64_t z0, std::int64_t z1) {
    ex.fill(z0, z1, l.node_base, l.surfel_base, l.entry_base, l.rows, nullptr, &mesh);
  });
}

template <class T>
void restore_nodes(const Volume& volume, SurfelComplex& out, int threads) {
  const Extractor<T> ex(volume, out.iso, out.inside_sign);
  const std::int64_t nz = ex.nz();
  std::vector<std::int64_t> counts(nz, 0), node_base(nz + 1, 0);
  for_each_slab(nz, threads, [&](std::int64_t z0, std::int64_t z1) {
    ex.nodes_only(z0, z1, false, counts, node_base, out);
  });
  for (std::int64_t k = 0; k < nz; ++k) node_base[k + 1] = node_base[k] + counts[k];
  const auto num_nodes = static_cast<std::size_t>(node_base[nz]);
  if (num_nodes != out.num_nodes())
    fail(Status::internal, "restore_node_geometry: the volume does not match the complex");
  tbb::parallel_invoke([&] { detail::sized(out.node_key, num_nodes); },
                       [&] { detail::sized(out.node_pos, 3 * num_nodes); });
  for_each_slab(nz, threads, [&](std::int64_t z0, std::int64_t z1) {
    ex.nodes_only(z0, z1, true, counts, node_base, out);
  });
}

}  // namespace

void release_node_geometry(SurfelComplex& complex) {
  std::vector<std::uint64_t>().swap(complex.node_key);
  std::vector<float>().swap(complex.node_pos);
}

void restore_node_geometry(const Volume& volume, SurfelComplex& complex,
                           const ExecutionContext& context) {
  if (complex.num_nodes() == 0 || (!complex.node_key.empty() && !complex.node_pos.empty())) return;
  if (volume.grid.dims != complex.grid.dims)
    fail(Status::invalid_input, "restore_node_geometry: the volume does not match the complex");
  const int threads = context.threads > 0 ? context.threads : tbb::info::default_concurrency();
  tbb::task_arena arena(threads);
  arena.execute([&] {
    dispatch_scalar(volume.type, [&](auto zero) {
      using T = decltype(zero);
      restore_nodes<T>(volume, complex, threads);
    });
  });
}

namespace {

/// The argument checks of build_surfels (also those of marching_cubes(volume), which reports
/// the same errors with the same messages). False when the volume has no voxels.
bool check_arguments(const Volume& volume, double iso, double inside_sign) {
  if (!std::isfinite(iso))
    fail(Status::invalid_input, "build_surfels: the iso-value must be finite");
  if (!(inside_sign == 1 || inside_sign == -1))
    fail(Status::invalid_input, "build_surfels: inside_sign must be +1 or -1");
  // Volumes built by hand bypass the readers' check: positions beyond the float range would give
  // inf vertices (mc) and a NaN surface area (the disk cover).
  check_world_range(volume.grid, volume.source.empty() ? "build_surfels" : volume.source);
  const auto& d = volume.grid.dims;
  if (d[0] < 2 || d[1] < 2 || d[2] < 2) return false;  // no voxels, no surface
  if (!volume.data.data() ||
      volume.data.size() <
          static_cast<std::size_t>(volume.grid.num_samples()) * scalar_size(volume.type))
    fail(Status::internal, "build_surfels: volume sample buffer smaller than its grid");
  return true;
}

}  // namespace

SurfelComplex build_surfels(const Volume& volume, double iso, double inside_sign,
                            const ExecutionContext& context) {
  const bool has_voxels = check_arguments(volume, iso, inside_sign);
  SurfelComplex out;
  out.grid = volume.grid;
  out.iso = iso;
  out.inside_sign = inside_sign;
  out.surfel_offset.assign(1, 0);
  if (!has_voxels) return out;
  const int threads = context.threads > 0 ? context.threads : tbb::info::default_concurrency();
  tbb::task_arena arena(threads);
  arena.execute([&] {
    dispatch_scalar(volume.type, [&](auto zero) {
      using T = decltype(zero);
      extract<T>(volume, out, threads);
    });
  });
  return out;
}

Mesh marching_cubes(const Volume& volume, double iso, double inside_sign,
                    const ExecutionContext& context, std::size_t* num_surfels) {
  if (num_surfels) *num_surfels = 0;
  Mesh mesh;
  if (!check_arguments(volume, iso, inside_sign)) return mesh;
  const int threads = context.threads > 0 ? context.threads : tbb::info::default_concurrency();
  tbb::task_arena arena(threads);
  std::size_t surfels = 0;
  arena.execute([&] {
    dispatch_scalar(volume.type, [&](auto zero) {
      using T = decltype(zero);
      extract_mesh<T>(volume, iso, inside_sign, threads, mesh, surfels);
    });
  });
  if (num_surfels) *num_surfels = surfels;
  return mesh;
}

std::int64_t SurfelComplex::find_node(std::uint64_t key) const noexcept {
  const auto it = std::lower_bound(node_key.begin(), node_key.end(), key);
  if (it == node_key.end() || *it != key) return -1;
  return it - node_key.begin();
}

std::size_t SurfelComplex::num_border_segments() const noexcept {
  std::size_t count = 0;
  for (std::size_t s = 0; s < num_surfels(); ++s)
    for (const std::int32_t o : opposites_of(s)) count += o < 0;
  return count;
}

}  // namespace adamesh
