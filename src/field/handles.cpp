// Topology control in the volume: small handles and tunnels are removed before the surface is
// extracted (docs/TOPOLOGY.md).
//
// The measure of a handle is the length of its shortest non-separating loop (Wood, Hoppe,
// Desbrun & Schröder 2004). For a strand of material of diameter d that loop is the meridian,
// about π·d, and a strand thinner than 2r is exactly what a morphological opening with a ball of
// radius r removes. So a handle shorter than L is found as a place where the material — or, for
// a tunnel, the outside — is thinner than 2r = L/π:
//
//   1. M = the voxels of one side (inside, then outside); O = the opening of M by the ball of
//      radius r (two exact Euclidean distance transforms). O keeps the thick parts of M and
//      loses its thin strands; a component of M with nothing left in O keeps its deepest voxel.
//   2. M is grown back from O one voxel at a time, deepest first (largest distance to the other
//      side), and a voxel is added only when that does not create a loop: with χ the Euler
//      characteristic of the union of closed voxel cubes (the 26-connected side) and b0 its
//      components (union-find), adding a voxel changes b1 − b2 by Δb0 − Δχ, which must be ≤ 0.
//      Rejected voxels are tried again when a neighbour joins.
//   3. The voxels of M that never join are the cuts: each strand keeps one thin layer, at about
//      its narrowest place (it is reached last), and those voxels change side.
//
// The inside side is cut first (strands of material: handles), then the outside (tunnels are
// plugged). The topology of each side is the surfels' own (docs/TOPOLOGY.md): samples joined by
// grid edges and, on ambiguous faces, by the diagonal the asymptotic decider connects; the
// Euler characteristic is summed over the grid's open cells (vertices, edges, faces, cubes),
// each cell contributing the compactly supported χ of its part of the side, where the part of a
// closed face or cube has one contractible piece per connected piece of its corners. A digital
// model with plain 26/6-connectivity misses the handles that pass through ambiguous faces: on
// the MRI scalp it left 13–26 of them.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <queue>
#include <type_traits>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "adamesh/error.h"
#include "adamesh/input.h"
#include "adamesh/stats.h"
#include "../surfels/cell_table.h"  // the asymptotic decider the surfels use

namespace adamesh {
namespace {

constexpr float kFar = std::numeric_limits<float>::max() / 4;

struct Dims {
  std::int64_t nx, ny, nz;
  std::int64_t n() const { return nx * ny * nz; }
};

// 1D squared Euclidean distance transform of f (Felzenszwalb & Huttenlocher 2012) over `len`
// samples at `stride`; with `border`, virtual zero samples sit at positions −1 and len (the
// outside beyond the volume's faces).
void edt_line(float* f, std::int64_t len, std::int64_t stride, bool border, std::vector<float>& in,
              std::vector<float>& pos, std::vector<int>& v, std::vector<float>& z) {
  const std::int64_t m = len + (border ? 2 : 0);
  in.resize(m);
  pos.resize(m);
  for (std::int64_t i = 0, k = border ? 1 : 0; i < len; ++i, ++k) {
    in[k] = f[i * stride];
    pos[k] = static_cast<float>(i);
  }
  if (border) {
    in[0] = 0, pos[0] = -1;
    in[m - 1] = 0, pos[m - 1] = static_cast<float>(len);
  }
  v.assign(m, 0);
  z.assign(m + 1, 0);
  // Lower envelope of the parabolas through the finite samples.
  int k = -1;
  for (std::int64_t q = 0; q < m; ++q) {
    if (in[q] >= kFar) continue;
    for (;;) {
      if (k < 0) {
        k = 0;
        v[0] = static_cast<int>(q);
        z[0] = -kFar;
        z[1] = kFar;
        break;
      }
      const int p = v[k];
      const float s =
          ((in[q] + pos[q] * pos[q]) - (in[p] + pos[p] * pos[p])) / (2 * (pos[q] - pos[p]));
      if (s <= z[k]) {
        --k;
        continue;
      }
      ++k;
      v[k] = static_cast<int>(q);
      z[k] = s;
      z[k + 1] = kFar;
      break;
    }
  }
  if (k < 0) return;  // no finite sample on the line: everything stays far
  int j = 0;
  for (std::int64_t i = 0; i < len; ++i) {
    const float x = static_cast<float>(i);
    while (z[j + 1] < x) ++j;
    const float d = x - pos[v[j]];
    f[i * stride] = std::min(kFar, d * d + in[v[j]]);
  }
}

// Squared distance (voxel units) from every voxel to the nearest voxel where `zero` holds;
// `border`: the outside of the volume counts as such a voxel.
template <class Zero>
std::vector<float> distance_transform(const Dims& d, Zero zero, bool border) {
  std::vector<float> f(static_cast<std::size_t>(d.n()));
  for (std::int64_t i = 0; i < d.n(); ++i) f[i] = zero(i) ? 0.f : kFar;
  auto pass = [&](std::int64_t lines, std::int64_t len, std::int64_t stride, auto start_of) {
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, lines, 64), [&](const auto& r) {
      std::vector<float> in, pos, z;
      std::vector<int> v;
      for (std::int64_t l = r.begin(); l != r.end(); ++l)
        edt_line(f.data() + start_of(l), len, stride, border, in, pos, v, z);
    });
  };
  pass(d.ny * d.nz, d.nx, 1, [&](std::int64_t l) { return l * d.nx; });
  pass(d.nx * d.nz, d.ny, d.nx,
       [&](std::int64_t l) { return (l / d.nx) * d.nx * d.ny + l % d.nx; });
  pass(d.nx * d.ny, d.nz, d.nx * d.ny, [&](std::int64_t l) { return l; });
  return f;
}

// The 26 neighbour offsets (frontier and grouping of cut voxels).
struct Neighbourhood26 {
  int off[26][3];
  Neighbourhood26() {
    int k = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (dx || dy || dz) off[k][0] = dx, off[k][1] = dy, off[k][2] = dz, ++k;
  }
};

const Neighbourhood26& neighbourhood26() {
  static const Neighbourhood26 nb;
  return nb;
}

// Local view of one side X during a pass: in(i) and the signed value r(i) = inside_sign·(f − iso)
// the sample will have if nothing else changes.
struct Side {
  Dims d;
  bool x_is_inside;  // X = the inside (r >= 0) or the outside (r < 0)
};

// Face term: χ_c of X ∩ (open face), corners in cyclic order.
inline int face_term(bool x_is_inside, const bool in[4], const double r[4]) {
  const int nin = in[0] + in[1] + in[2] + in[3];
  if (nin == 0) return 0;
  const int e = (in[0] && in[1]) + (in[1] && in[2]) + (in[2] && in[3]) + (in[3] && in[0]);
  int comps = 1;
  if (nin == 2 && in[0] == in[2]) {
    const bool pos = detail::positive_diagonal_connected(r[0], r[1], r[2], r[3]);
    comps = (x_is_inside ? pos : !pos) ? 1 : 2;
  }
  return comps - (nin - e);
}

// Corners of a cube: bit 0 = x, 1 = y, 2 = z offset. Faces in cyclic corner order.
constexpr int kCubeFace[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                 {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
constexpr int kCubeEdge[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                  {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

// Cube term: χ_c of X ∩ (open cube) = pieces of X in the closed cube − χ(X ∩ its boundary).
inline int cube_term(bool x_is_inside, const bool in[8], const double r[8]) {
  int nin = 0;
  for (int c = 0; c < 8; ++c) nin += in[c];
  if (nin == 0) return 0;
  if (nin == 8) return -1;
  int parent[8] = {0, 1, 2, 3, 4, 5, 6, 7};
  auto find = [&](int a) {
    while (parent[a] != a) a = parent[a];
    return a;
  };
  auto unite = [&](int a, int b) { parent[find(a)] = find(b); };
  int chi = nin;
  for (const auto& e : kCubeEdge)
    if (in[e[0]] && in[e[1]]) --chi, unite(e[0], e[1]);
  for (const auto& f : kCubeFace) {
    const bool fi[4] = {in[f[0]], in[f[1]], in[f[2]], in[f[3]]};
    const double fr[4] = {r[f[0]], r[f[1]], r[f[2]], r[f[3]]};
    const int t = face_term(x_is_inside, fi, fr);
    chi += t;
    // An ambiguous face whose X-diagonal is connected joins it.
    if (fi[0] + fi[1] + fi[2] + fi[3] == 2 && fi[0] == fi[2]) {
      const bool pos = detail::positive_diagonal_connected(fr[0], fr[1], fr[2], fr[3]);
      if (x_is_inside ? pos : !pos) {
        if (fi[0]) unite(f[0], f[2]);
        else unite(f[1], f[3]);
      }
    }
  }
  int comps = 0;
  for (int c = 0; c < 8; ++c) comps += in[c] && find(c) == c;
  return comps - chi;
}

// The 6 face neighbours and the 12 face-diagonal neighbours with the two corners they share a
// face with: a diagonal pair is joined when both are in X and, the other two corners being out
// of X, the decider connects it (with a third corner in X the pair is joined through it).
struct Offsets {
  int face[6][3];
  int diag[12][3];
  int other[12][2][3];
  Offsets() {
    int f = 0, g = 0;
    for (int a = 0; a < 3; ++a)
      for (int s = -1; s <= 1; s += 2) {
        int o[3] = {0, 0, 0};
        o[a] = s;
        std::copy(o, o + 3, face[f++]);
      }
    for (int a = 0; a < 3; ++a)
      for (int b = a + 1; b < 3; ++b)
        for (int sa = -1; sa <= 1; sa += 2)
          for (int sb = -1; sb <= 1; sb += 2) {
            int o[3] = {0, 0, 0}, p[3] = {0, 0, 0}, q[3] = {0, 0, 0};
            o[a] = sa, o[b] = sb;
            p[a] = sa;
            q[b] = sb;
            std::copy(o, o + 3, diag[g]);
            std::copy(p, p + 3, other[g][0]);
            std::copy(q, q + 3, other[g][1]);
            ++g;
          }
  }
};

const Offsets& offsets() {
  static const Offsets o;
  return o;
}

// One pass over side X (marked by `side`): M = X's voxels. r_now(i) is the signed value of a
// voxel as it is, r_moved(i) the value it gets if it changes side. Returns the voxels of M that
// change side (the cuts), in index order, and how many 26-connected groups they form.
template <class Now, class Moved>
std::vector<std::int64_t> cut_thin_loops(const Dims& d, const std::vector<std::uint8_t>& side,
                                         bool x_is_inside, double radius, Now r_now,
                                         Moved r_moved, std::int64_t& groups) {
  const Offsets& off = offsets();
  const std::int64_t n = d.n();
  const float r2 = static_cast<float>(radius * radius);
  // Depth of every voxel of M: squared distance to the other side (and, for the inside, to the
  // volume's outside beyond its faces).
  const std::vector<float> depth =
      distance_transform(d, [&](std::int64_t i) { return !side[i]; }, x_is_inside);
  // Opening: within r of a voxel deeper than r.
  std::vector<float> open =
      distance_transform(d, [&](std::int64_t i) { return depth[i] > r2; }, false);

  auto at = [&](std::int64_t i, const int o[3]) -> std::int64_t {
    const std::int64_t x = i % d.nx + o[0], y = (i / d.nx) % d.ny + o[1],
                       z = i / (d.nx * d.ny) + o[2];
    if (x < 0 || y < 0 || z < 0 || x >= d.nx || y >= d.ny || z >= d.nz) return -1;
    return (z * d.ny + y) * d.nx + x;
  };
  // label: −1 = not in S, else a union-find node. The state of a voxel for the topology: in S,
  // or out with its value as it is (not in M) or as it will be if it changes side (M ∖ S).
  std::vector<std::int32_t> label(static_cast<std::size_t>(n), -1);
  std::vector<std::int32_t> parent;
  auto in_s = [&](std::int64_t i) { return label[i] >= 0; };
  auto r_of = [&](std::int64_t i) { return side[i] && !in_s(i) ? r_moved(i) : r_now(i); };
  // Calls f(j) for every neighbour j joined to i when both i and j are in the set `in`, with
  // values `r` (for the decider).
  auto for_joined = [&](std::int64_t i, auto in, auto r, auto f) {
    for (const auto& o : off.face) {
      const std::int64_t j = at(i, o);
      if (j >= 0 && in(j)) f(j);
    }
    for (int g = 0; g < 12; ++g) {
      const std::int64_t j = at(i, off.diag[g]);
      if (j < 0 || !in(j)) continue;
      const std::int64_t p = at(i, off.other[g][0]), q = at(i, off.other[g][1]);
      if (in(p) || in(q)) continue;  // joined through p or q
      const bool pos = detail::positive_diagonal_connected(r(i), r(p), r(j), r(q));
      if (x_is_inside ? pos : !pos) f(j);
    }
  };
  std::vector<std::int64_t> stack;
  auto flood = [&](std::int64_t start, auto in, auto r) {
    const auto id = static_cast<std::int32_t>(parent.size());
    parent.push_back(id);
    label[start] = id;
    stack.assign(1, start);
    while (!stack.empty()) {
      const std::int64_t i = stack.back();
      stack.pop_back();
      for_joined(i, in, r, [&](std::int64_t j) {
        if (label[j] < 0) label[j] = id, stack.push_back(j);
      });
    }
  };
  // Components of M (all of M in X, values as they are) that the opening misses are kept whole.
  {
    auto in_m = [&](std::int64_t i) { return side[i] != 0; };
    std::vector<std::uint8_t> touched;
    for (std::int64_t i = 0; i < n; ++i) {
      if (!side[i] || label[i] >= 0) continue;
      flood(i, in_m, r_now);
      touched.push_back(0);
    }
    for (std::int64_t i = 0; i < n; ++i)
      if (side[i] && open[i] <= r2) touched[label[i]] = 1;
    // S0 = O ∪ the deepest voxel (the first in index order) of every component O misses: thin
    // components grow back from there, so a thin ring is cut too.
    std::vector<std::int64_t> seed(touched.size(), -1);
    for (std::int64_t i = 0; i < n; ++i) {
      if (!side[i] || touched[label[i]]) continue;
      std::int64_t& best = seed[label[i]];
      if (best < 0 || depth[i] > depth[best]) best = i;
    }
    for (std::int64_t i = 0; i < n; ++i)
      if (side[i] && open[i] > r2 && seed[label[i]] != i) label[i] = -1;
    // Label S0's components with S0's own connectivity.
    std::vector<std::uint8_t> s0(static_cast<std::size_t>(n), 0);
    for (std::int64_t i = 0; i < n; ++i) s0[i] = label[i] >= 0;
    std::fill(label.begin(), label.end(), -1);
    parent.clear();
    auto in_s0 = [&](std::int64_t i) { return s0[i] != 0; };
    auto r_s0 = [&](std::int64_t i) { return side[i] && !s0[i] ? r_moved(i) : r_now(i); };
    for (std::int64_t i = 0; i < n; ++i)
      if (s0[i] && label[i] < 0) flood(i, in_s0, r_s0);
  }
  std::vector<float>().swap(open);

  auto find = [&](std::int32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  // Δχ of adding v to S: the cells whose closure holds v — v, 6 edges, 12 faces, 8 cubes.
  const std::int64_t nx = d.nx, ny = d.ny, nz = d.nz;
  auto delta_chi = [&](std::int64_t v) {
    const std::int64_t x = v % nx, y = (v / nx) % ny, z = v / (nx * ny);
    bool in[27];
    double r[27];
    bool exists[27];
    for (int dz = -1, k = 0; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx, ++k) {
          const std::int64_t a = x + dx, b = y + dy, c = z + dz;
          exists[k] = a >= 0 && b >= 0 && c >= 0 && a < nx && b < ny && c < nz;
          if (!exists[k]) continue;
          const std::int64_t i = (c * ny + b) * nx + a;
          in[k] = in_s(i);
          r[k] = r_of(i);
        }
    auto cells = [&] {
      int chi = 0;
      auto idx = [](int a, int b, int c) { return (c + 1) * 9 + (b + 1) * 3 + (a + 1); };
      // edges from v
      for (const auto& o : off.face) {
        const int k = idx(o[0], o[1], o[2]);
        if (exists[k] && in[13] && in[k]) --chi;
      }
      // faces with v as a corner
      for (int g = 0; g < 12; ++g) {
        const int* o = off.diag[g];
        const int* p = off.other[g][0];
        const int* q = off.other[g][1];
        const int ks[4] = {13, idx(p[0], p[1], p[2]), idx(o[0], o[1], o[2]), idx(q[0], q[1], q[2])};
        if (!exists[ks[1]] || !exists[ks[2]] || !exists[ks[3]]) continue;
        const bool fi[4] = {in[ks[0]], in[ks[1]], in[ks[2]], in[ks[3]]};
        const double fr[4] = {r[ks[0]], r[ks[1]], r[ks[2]], r[ks[3]]};
        chi += face_term(x_is_inside, fi, fr);
      }
      // cubes with v as a corner
      for (int sz = -1; sz <= 1; sz += 2)
        for (int sy = -1; sy <= 1; sy += 2)
          for (int sx = -1; sx <= 1; sx += 2) {
            bool ci[8];
            double cr[8];
            bool ok = true;
            for (int c = 0; c < 8; ++c) {
              // corner c of the cube spanned by v and v + s: lower corner min(0, s) per axis
              const int ox = (sx < 0 ? -1 : 0) + (c & 1), oy = (sy < 0 ? -1 : 0) + ((c >> 1) & 1),
                        oz = (sz < 0 ? -1 : 0) + ((c >> 2) & 1);
              const int k = idx(ox, oy, oz);
              ok &= exists[k];
              ci[c] = ok && in[k];
              cr[c] = ok ? r[k] : 0;
            }
            if (ok) chi += cube_term(x_is_inside, ci, cr);
          }
      return chi + in[13];
    };
    const int before = cells();
    in[13] = true;
    r[13] = r_now(v);
    return cells() - before;
  };

  // Grow M back, deepest first; ties by index (deterministic).
  using Item = std::pair<float, std::int64_t>;
  auto later = [](const Item& a, const Item& b) {
    return a.first != b.first ? a.first < b.first : a.second > b.second;
  };
  std::priority_queue<Item, std::vector<Item>, decltype(later)> queue(later);
  // 0 = not queued, 1 = queued; rejected voxels are queued again when a neighbour joins.
  std::vector<std::uint8_t> queued(static_cast<std::size_t>(n), 0);
  const Neighbourhood26& nb = neighbourhood26();
  auto push_neighbours = [&](std::int64_t i) {
    for (const auto& o : nb.off) {
      const std::int64_t k = at(i, o);
      if (k >= 0 && side[k] && label[k] < 0 && !queued[k]) {
        queued[k] = 1;
        queue.push({depth[k], k});
      }
    }
  };
  for (std::int64_t i = 0; i < n; ++i)
    if (label[i] >= 0) push_neighbours(i);
  auto in_after = [&](std::int64_t v) {
    return [&, v](std::int64_t i) { return i == v || in_s(i); };
  };
  while (!queue.empty()) {
    const std::int64_t v = queue.top().second;
    queue.pop();
    queued[v] = 0;
    if (label[v] >= 0) continue;
    std::int32_t roots[26];
    int k = 0;
    auto r_after = [&](std::int64_t i) { return i == v ? r_now(v) : r_of(i); };
    for_joined(v, in_after(v), r_after, [&](std::int64_t j) {
      const std::int32_t root = find(label[j]);
      if (std::find(roots, roots + k, root) == roots + k) roots[k++] = root;
    });
    if (k == 0 || (1 - k) - delta_chi(v) > 0) continue;  // rejected (for now)
    for (int j = 1; j < k; ++j) parent[roots[j]] = roots[0];
    label[v] = roots[0];
    push_neighbours(v);
  }
  std::vector<std::int64_t> cuts;
  for (std::int64_t i = 0; i < n; ++i)
    if (side[i] && label[i] < 0) cuts.push_back(i);
  // Groups of cut voxels (26-connected): about one per handle.
  groups = 0;
  std::fill(queued.begin(), queued.end(), 0);
  for (const std::int64_t c : cuts) queued[c] = 1;
  for (const std::int64_t c : cuts) {
    if (queued[c] != 1) continue;
    ++groups;
    queued[c] = 2;
    stack.assign(1, c);
    while (!stack.empty()) {
      const std::int64_t a = stack.back();
      stack.pop_back();
      for (const auto& o : nb.off) {
        const std::int64_t k = at(a, o);
        if (k >= 0 && queued[k] == 1) queued[k] = 2, stack.push_back(k);
      }
    }
  }
  return cuts;
}

// χ of the inside (r >= 0) with the surfels' topology: the sum of the cell terms over the grid.
template <class R>
std::int64_t inside_euler(const Dims& d, R r_of) {
  const std::int64_t nx = d.nx, ny = d.ny, nz = d.nz;
  return tbb::parallel_reduce(
      tbb::blocked_range<std::int64_t>(0, nz), std::int64_t{0},
      [&](const auto& range, std::int64_t chi) {
        for (std::int64_t z = range.begin(); z != range.end(); ++z)
          for (std::int64_t y = 0; y < ny; ++y)
            for (std::int64_t x = 0; x < nx; ++x) {
              const std::int64_t i = (z * ny + y) * nx + x;
              auto corner = [&](int c) {
                return i + (c & 1) + ((c >> 1) & 1) * nx + ((c >> 2) & 1) * nx * ny;
              };
              const double rv = r_of(i);
              chi += rv >= 0;
              const bool hx = x + 1 < nx, hy = y + 1 < ny, hz = z + 1 < nz;
              if (hx) chi -= rv >= 0 && r_of(i + 1) >= 0;
              if (hy) chi -= rv >= 0 && r_of(i + nx) >= 0;
              if (hz) chi -= rv >= 0 && r_of(i + nx * ny) >= 0;
              auto face = [&](int c0, int c1, int c2, int c3) {
                const double fr[4] = {r_of(corner(c0)), r_of(corner(c1)), r_of(corner(c2)),
                                      r_of(corner(c3))};
                const bool fi[4] = {fr[0] >= 0, fr[1] >= 0, fr[2] >= 0, fr[3] >= 0};
                return face_term(true, fi, fr);
              };
              if (hx && hy) chi += face(0, 1, 3, 2);
              if (hx && hz) chi += face(0, 1, 5, 4);
              if (hy && hz) chi += face(0, 2, 6, 4);
              if (hx && hy && hz) {
                double cr[8];
                bool ci[8];
                for (int c = 0; c < 8; ++c) cr[c] = r_of(corner(c)), ci[c] = cr[c] >= 0;
                chi += cube_term(true, ci, cr);
              }
            }
        return chi;
      },
      std::plus<>());
}

}  // namespace

Input remove_handles(const Input& in, double iso, double max_loop, HandleReport& report) {
  report = {};
  if (!(max_loop > 0) || !std::isfinite(max_loop))
    fail(Status::usage, "remove_handles: the loop length must be positive and finite");
  const Volume& src = *in.volume;
  const Grid& g = src.grid;
  const Dims d{g.dims[0], g.dims[1], g.dims[2]};
  const double radius = max_loop / (2 * std::numbers::pi);
  report.radius = radius;
  auto copy = std::make_shared<Volume>(allocate_volume(g, src.type, src.source));
  copy->format = src.format;
  copy->source = src.source;
  std::copy(src.data.data(), src.data.data() + src.data.size(), copy->data.data());
  const VolumeStats st = compute_stats(src);
  const double eps = 1e-3 * (st.max - st.min);
  const double sgn = in.inside_sign > 0 ? 1.0 : -1.0;

  dispatch_scalar(src.type, [&](auto tag) {
    using T = decltype(tag);
    T* s = copy->samples<T>();
    // A voxel changes side by its value mirrored across the iso-value (at least eps from it), so
    // the surface stays as smooth as the data around the cut; the volume's extreme on that side
    // when the mirror does not fit the sample type.
    auto moved = [&](std::int64_t i) -> T {
      const double f = static_cast<double>(s[i]);
      const double side_sign = f >= iso ? -1.0 : 1.0;  // the value's side of iso, flipped
      double v = iso + side_sign * std::max(std::abs(f - iso), eps);
      if constexpr (std::is_integral_v<T>) v = side_sign > 0 ? std::ceil(v) : std::floor(v);
      const bool fits = v >= static_cast<double>(std::numeric_limits<T>::lowest()) &&
                        v <= static_cast<double>(std::numeric_limits<T>::max());
      if (!fits || side_sign * (v - iso) <= 0) v = side_sign > 0 ? st.max : st.min;
      return static_cast<T>(v);
    };
    auto r_now = [&](std::int64_t i) { return sgn * (static_cast<double>(s[i]) - iso); };
    auto r_moved = [&](std::int64_t i) { return sgn * (static_cast<double>(moved(i)) - iso); };
    std::vector<std::uint8_t> side(static_cast<std::size_t>(d.n()));
    auto mark = [&](bool inside) {
      for (std::int64_t i = 0; i < d.n(); ++i) side[i] = (r_now(i) >= 0) == inside;
    };
    report.inside_euler_before = inside_euler(d, r_now);
    // Handles: thin strands of material are cut.
    mark(true);
    auto cuts = cut_thin_loops(d, side, true, radius, r_now, r_moved, report.handles_cut);
    for (const std::int64_t i : cuts) s[i] = moved(i);
    report.cut_voxels = static_cast<std::int64_t>(cuts.size());
    // Tunnels: thin strands of the outside are plugged.
    mark(false);
    cuts = cut_thin_loops(d, side, false, radius, r_now, r_moved, report.tunnels_filled);
    for (const std::int64_t i : cuts) s[i] = moved(i);
    report.plug_voxels = static_cast<std::int64_t>(cuts.size());
    report.inside_euler_after = inside_euler(d, r_now);
  });
  Input out = in;
  out.volume = copy;
  out.field = make_volume_field(std::shared_ptr<const Volume>(copy));
  return out;
}

}  // namespace adamesh
