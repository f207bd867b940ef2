// Generation of the face-consistent voxel configurations (see cell_table.h).
//
// References: Lorensen & Cline 1987 (marching cubes cases); Nielson & Hamann 1991 (asymptotic
// decider). The table is derived at first use from the face rules; nothing is typed in by hand.
#include "surfels/cell_table.h"

#include <cassert>
#include <vector>

namespace adamesh::detail {

namespace {

int corner_index(int x, int y, int z) { return x + 2 * y + 4 * z; }

int edge_index(int axis, int o1, int o2) { return 4 * axis + o1 + 2 * o2; }

/// Edge joining two corners that differ in exactly one coordinate.
int edge_between(int c0, int c1) {
  const int diff = c0 ^ c1;
  const int axis = diff == 1 ? 0 : (diff == 2 ? 1 : 2);
  const int lo = c0 < c1 ? c0 : c1;
  const int p[3] = {lo & 1, (lo >> 1) & 1, (lo >> 2) & 1};
  const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
  return edge_index(axis, p[a1], p[a2]);
}

struct Geometry {
  std::array<CubeEdge, 12> edges{};
  std::array<CubeFace, 6> faces{};
  std::array<std::array<std::int8_t, 12>, 12> common{};
  std::array<std::array<bool, 12>, 12> allowed{};

  Geometry() {
    for (int axis = 0; axis < 3; ++axis) {
      const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
      for (int o2 = 0; o2 < 2; ++o2)
        for (int o1 = 0; o1 < 2; ++o1) {
          CubeEdge& e = edges[edge_index(axis, o1, o2)];
          e.axis = static_cast<std::uint8_t>(axis);
          std::array<int, 3> p{0, 0, 0};
          p[a1] = o1;
          p[a2] = o2;
          e.lower = {static_cast<std::uint8_t>(p[0]), static_cast<std::uint8_t>(p[1]),
                     static_cast<std::uint8_t>(p[2])};
          e.corner0 = static_cast<std::uint8_t>(corner_index(p[0], p[1], p[2]));
          e.corner1 = static_cast<std::uint8_t>(e.corner0 + (1 << axis));
          e.faces = {static_cast<std::uint8_t>(2 * a1 + p[a1]),
                     static_cast<std::uint8_t>(2 * a2 + p[a2])};
        }
    }
    for (int axis = 0; axis < 3; ++axis) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int side = 0; side < 2; ++side) {
        // (u, v) = (0,0) (1,0) (1,1) (0,1) is counter-clockwise seen from +axis (u × v = axis).
        static const int uv_ccw[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        CubeFace& f = faces[2 * axis + side];
        for (int k = 0; k < 4; ++k) {
          const int kk = side == 1 ? k : (4 - k) % 4;  // reversed walk for the low face
          std::array<int, 3> p{};
          p[axis] = side;
          p[u] = uv_ccw[kk][0];
          p[v] = uv_ccw[kk][1];
          f.corner[k] = static_cast<std::uint8_t>(corner_index(p[0], p[1], p[2]));
        }
        for (int k = 0; k < 4; ++k)
          f.edge[k] = static_cast<std::uint8_t>(edge_between(f.corner[k], f.corner[(k + 1) % 4]));
      }
    }
    for (int e1 = 0; e1 < 12; ++e1)
      for (int e2 = 0; e2 < 12; ++e2) {
        common[e1][e2] = -1;
        if (e1 == e2) continue;
        for (int f1 : edges[e1].faces)
          for (int f2 : edges[e2].faces)
            if (f1 == f2) common[e1][e2] = static_cast<std::int8_t>(f1);
      }
    for (int e1 = 0; e1 < 12; ++e1)
      for (int e2 = 0; e2 < 12; ++e2) {
        const int f = common[e1][e2];
        if (f < 0) {
          allowed[e1][e2] = true;
          continue;
        }
        int k1 = 0, k2 = 0;
        for (int k = 0; k < 4; ++k) {
          if (faces[f].edge[k] == e1) k1 = k;
          if (faces[f].edge[k] == e2) k2 = k;
        }
        const bool crossing = (k1 - k2 + 4) % 4 == 2;
        allowed[e1][e2] = crossing == (f % 2 == 1);
      }
    for (int e = 0; e < 12; ++e)
      edges[e].quadrant = static_cast<std::uint8_t>(quadrant(e, {0, 0, 0}));
  }

  int quadrant(int e, const std::array<int, 3>& voxel) const {
    const CubeEdge& ce = edges[e];
    const int u = (ce.axis + 1) % 3, v = (ce.axis + 2) % 3;
    // The voxel spans [voxel, voxel+1]; it lies on the + side of the edge along u when it starts
    // at the edge's u coordinate, on the − side when it ends there.
    const bool up = voxel[u] == ce.lower[u];
    const bool vp = voxel[v] == ce.lower[v];
    assert(up || voxel[u] == ce.lower[u] - 1);
    assert(vp || voxel[v] == ce.lower[v] - 1);
    // Quadrants (−,−), (+,−), (+,+), (−,+).
    if (!up && !vp) return 0;
    if (up && !vp) return 1;
    if (up && vp) return 2;
    return 3;
  }
};

const Geometry& geometry() {
  static const Geometry g;
  return g;
}

CellConfig build_config(int c, unsigned decisions, bool mirrored) {
  const Geometry& g = geometry();
  std::array<int, 12> next, seg_face, exits;
  next.fill(-1);
  seg_face.fill(-1);
  exits.fill(0);
  auto link = [&](int entry, int exit, int f) {
    assert(next[entry] == -1);
    next[entry] = exit;
    seg_face[entry] = f;
    ++exits[exit];
  };
  for (int f = 0; f < 6; ++f) {
    const CubeFace& fc = g.faces[f];
    int s[4];
    for (int k = 0; k < 4; ++k) s[k] = (c >> fc.corner[k]) & 1;
    int crossings = 0;
    for (int k = 0; k < 4; ++k) crossings += s[k] != s[(k + 1) % 4];
    if (crossings == 2) {
      int entry = -1, exit = -1;
      for (int k = 0; k < 4; ++k) {
        if (!s[k] && s[(k + 1) % 4]) entry = fc.edge[k];
        if (s[k] && !s[(k + 1) % 4]) exit = fc.edge[k];
      }
      link(entry, exit, f);
    } else if (crossings == 4) {
      // Connected positive diagonal: cut off the negative corners; else the positive ones.
      const int cut_sign = (decisions >> f) & 1 ? 0 : 1;
      for (int p = 0; p < 4; ++p) {
        if (s[p] != cut_sign) continue;
        const int before = fc.edge[(p + 3) % 4], after = fc.edge[p];
        if (s[p])
          link(before, after, f);  // positive corner: − → + then + → −
        else
          link(after, before, f);  // negative corner
      }
    }
  }
  CellConfig cfg;
  std::array<bool, 12> seen{};
  int n = 0;
  for (int e0 = 0; e0 < 12; ++e0) {
    const CubeEdge& ce = g.edges[e0];
    const bool crossing = ((c >> ce.corner0) & 1) != ((c >> ce.corner1) & 1);
    assert(crossing == (next[e0] != -1));
    assert(!crossing || exits[e0] == 1);
    if (!crossing || seen[e0]) continue;
    int cyc[12], len = 0;
    for (int e = e0; !seen[e]; e = next[e]) {
      seen[e] = true;
      cyc[len++] = e;
    }
    assert(len >= 3);
    for (int k = 0; k < len; ++k) {
      // Mirrored (index-to-world map with negative determinant): reversed cycle, same start.
      const int e = mirrored ? cyc[(len - k) % len] : cyc[k];
      const int f = mirrored ? seg_face[cyc[(len - k - 1 + len) % len]] : seg_face[e];
      const int axis = f / 2, side = f % 2;
      // The voxel across face f, relative to this voxel.
      std::array<int, 3> across{0, 0, 0};
      across[axis] = side ? 1 : -1;
      cfg.edge[n] = static_cast<std::uint8_t>(e);
      cfg.face[n] = static_cast<std::uint8_t>(f);
      cfg.opposite_quadrant[n] = static_cast<std::uint8_t>(g.quadrant(e, across));
      ++n;
    }
    cfg.cycle_len[cfg.num_cycles++] = static_cast<std::uint8_t>(len);
  }
  cfg.num_entries = static_cast<std::uint8_t>(n);
  return cfg;
}

}  // namespace

CellTable::CellTable() {
  const Geometry& g = geometry();
  for (int c = 0; c < 256; ++c) {
    std::uint8_t m = 0;
    for (int f = 0; f < 6; ++f) {
      const auto& fc = g.faces[f].corner;
      const int s0 = (c >> fc[0]) & 1, s1 = (c >> fc[1]) & 1, s2 = (c >> fc[2]) & 1,
                s3 = (c >> fc[3]) & 1;
      if (s0 == s2 && s1 == s3 && s0 != s1) m = static_cast<std::uint8_t>(m | (1u << f));
    }
    ambiguous_[c] = m;
    int crossing = 0;
    for (const auto& e : g.edges) crossing += ((c >> e.corner0) & 1) != ((c >> e.corner1) & 1);
    entries_[c] = static_cast<std::uint8_t>(crossing);
    offset_[c] = static_cast<std::uint32_t>(configs_[0].size());
    const int bits = __builtin_popcount(m);
    for (unsigned local = 0; local < (1u << bits); ++local) {
      // Expand the compressed decision bits onto the ambiguous faces.
      unsigned decisions = 0;
      int b = 0;
      for (int f = 0; f < 6; ++f)
        if (m & (1u << f)) {
          if (local & (1u << b)) decisions |= 1u << f;
          ++b;
        }
      configs_[0].push_back(build_config(c, decisions, false));
      configs_[1].push_back(build_config(c, decisions, true));
    }
  }
}

const CellTable& cell_table() noexcept {
  static const CellTable t;
  return t;
}

const std::array<CubeEdge, 12>& cube_edges() noexcept { return geometry().edges; }
const std::array<CubeFace, 6>& cube_faces() noexcept { return geometry().faces; }
int common_face(int e1, int e2) noexcept { return geometry().common[e1][e2]; }
bool diagonal_allowed(int e1, int e2) noexcept { return geometry().allowed[e1][e2]; }
int fan_quadrant(int e, const std::array<int, 3>& voxel) noexcept {
  return geometry().quadrant(e, voxel);
}

}  // namespace adamesh::detail
