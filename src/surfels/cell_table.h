// Local geometry of one voxel and the face-consistent surfel configurations (ALGORITHM.md 2.2).
//
// References: Lorensen & Cline, "Marching Cubes" (SIGGRAPH 1987) for the cell/case layout;
// Nielson & Hamann, "The asymptotic decider" (Visualization 1991) for ambiguous faces.
//
// Every configuration is generated from the rules below, not typed in: a voxel's 8 corner signs
// (case bit i = corner x + 2y + 4z positive) plus one decision bit per ambiguous face determine
// the face segments; following them gives the cycles (surfels).
//
// Segment orientation (the combinatorial orientation rule): each face is walked counter-clockwise
// seen from outside the voxel; an edge of that walk going from a negative to a positive corner
// is the segment's *entry*, one going from positive to negative its *exit*, and every segment runs
// entry -> exit (positive corners on its right seen from outside the voxel). A voxel edge is
// walked in opposite directions by its two faces, so each node is the entry on exactly one face
// and the exit on the other: "next" is a permutation and the segments chain into cycles. The
// neighbouring voxel sees the shared face from the other side, so it traverses the shared segment
// in the opposite direction. The resulting polygons have their Newell normal pointing from the
// positive region to the negative one (counter-clockwise seen from the negative side) in index
// space, and in world space when the index-to-world map preserves orientation (else the cycles
// are stored reversed, see cell_config).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace adamesh::detail {

// ---- Local cube geometry. Corner c = x + 2y + 4z. ----
// Edge e = 4·axis + (o1 + 2·o2), (o1, o2) the corner offsets along the two other axes in
// increasing axis order (x edges: y, z; y edges: x, z; z edges: x, y).
// Face f = 2·axis + side (side 0 = low, 1 = high).

struct CubeEdge {
  std::uint8_t axis;
  std::array<std::uint8_t, 3> lower;  ///< offset of the lower endpoint in the voxel (0/1 each)
  std::uint8_t corner0, corner1;      ///< lower and upper corner index
  std::array<std::uint8_t, 2> faces;  ///< the two faces containing the edge
  std::uint8_t quadrant;  ///< this voxel's slot in node_fan of a node on this edge (0..3)
};

struct CubeFace {
  std::array<std::uint8_t, 4> corner;  ///< counter-clockwise seen from outside the voxel
  std::array<std::uint8_t, 4> edge;    ///< edge k joins corner[k] and corner[k+1 mod 4]
};

const std::array<CubeEdge, 12>& cube_edges() noexcept;
const std::array<CubeFace, 6>& cube_faces() noexcept;
/// Face shared by two different edges, or -1.
int common_face(int e1, int e2) noexcept;
/// May a polygon of this voxel use the diagonal between nodes on edges e1 and e2 (not joined by a
/// segment)? Always when the edges share no face. Two nodes on one face (an ambiguous face has
/// four nodes and two segments) could be joined by the neighbour across that face too, giving an
/// edge of four triangles; the two voxels therefore split those four pairs: the voxel below the
/// face (face side 1) may use the two diagonals crossing the face (nodes on opposite face edges),
/// the voxel above it (side 0) the two pairs on adjacent face edges. Every configuration has a
/// triangulation within these rules (tests/mc_test.cpp checks all of them).
bool diagonal_allowed(int e1, int e2) noexcept;
/// Quadrant (node_fan slot) of the voxel at integer offset `voxel` (relative to the reference
/// voxel's lower corner) around the reference voxel's edge e. Precondition: that voxel touches e.
int fan_quadrant(int e, const std::array<int, 3>& voxel) noexcept;

/// One voxel configuration: up to four cycles (surfels), 3..12 nodes in total.
struct CellConfig {
  std::uint8_t num_cycles = 0;
  std::uint8_t num_entries = 0;             ///< total nodes over all cycles
  std::array<std::uint8_t, 4> cycle_len{};  ///< nodes per cycle, cycles concatenated below
  std::array<std::uint8_t, 12> edge{};      ///< local edge of each polygon node, in cycle order
  std::array<std::uint8_t, 12> face{};      ///< face of the segment from node k to node k+1
  /// node_fan slot (around node k's edge) of the voxel across face[k]: the opposite surfel of
  /// polygon edge k is node_fan[node k][opposite_quadrant[k]].
  std::array<std::uint8_t, 12> opposite_quadrant{};
};

/// All configurations, generated once (cell_table()).
class CellTable {
 public:
  CellTable();
  /// Bit f set when face f has alternating corner signs for this case.
  std::uint8_t ambiguous(int cell_case) const noexcept { return ambiguous_[cell_case]; }
  /// Number of sign-changing edges (= polygon entries) of a case, whatever the decisions.
  std::uint8_t entries(int cell_case) const noexcept { return entries_[cell_case]; }
  /// Configuration for `cell_case` with `decisions` (bit f set: on ambiguous face f the positive
  /// diagonal is connected through the face, i.e. the saddle value is >= 0). Bits of unambiguous
  /// faces are ignored. `mirrored`: the index-to-world map reverses orientation (negative
  /// determinant); every cycle is then reversed so polygons stay counter-clockwise seen from the
  /// negative side in world space.
  const CellConfig& config(int cell_case, unsigned decisions, bool mirrored) const noexcept {
    const unsigned m = ambiguous_[cell_case];
    unsigned local = 0;
    if (m) {
      int b = 0;
      for (int f = 0; f < 6; ++f)
        if (m & (1u << f)) {
          if (decisions & (1u << f)) local |= 1u << b;
          ++b;
        }
    }
    return configs_[mirrored][offset_[cell_case] + local];
  }

 private:
  std::array<std::uint8_t, 256> ambiguous_{};
  std::array<std::uint8_t, 256> entries_{};
  std::array<std::uint32_t, 256> offset_{};
  std::vector<CellConfig> configs_[2];  // [mirrored]
};

const CellTable& cell_table() noexcept;

inline std::uint8_t ambiguous_faces(int cell_case) noexcept {
  return cell_table().ambiguous(cell_case);
}
inline const CellConfig& cell_config(int cell_case, unsigned decisions, bool mirrored) noexcept {
  return cell_table().config(cell_case, decisions, mirrored);
}

/// Asymptotic decider on one face with its four values (minus iso, times inside_sign) in cyclic
/// order, signs alternating. Returns true when the positive diagonal is connected, i.e. the
/// bilinear saddle value s = (a·c − b·d)/(a + c − b − d) is >= 0 (s = 0 counts as positive).
/// With (a, c) the positive pair and (b, d) the strictly negative one, the denominator is > 0,
/// so the test is a·c − b·d >= 0: evaluated in long double without a division, symmetric in the
/// labelling, hence bit-identical for the two voxels sharing the face.
inline bool positive_diagonal_connected(double a, double b, double c, double d) noexcept {
  // Normalise so (a, c) is the positive pair.
  if (!(a >= 0)) {
    const double t = a;
    a = b;
    b = c;
    c = d;
    d = t;
  }
  const long double pos = static_cast<long double>(a) * static_cast<long double>(c);
  const long double neg = static_cast<long double>(b) * static_cast<long double>(d);
  return pos - neg >= 0;
}

}  // namespace adamesh::detail
