// Internal: the geodesic Voronoi covering VC_G (ALGORITHM.md 2.5) with incremental updates and
// the local tests that detect violated cells, plus the junction scan that yields the dual.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "adamesh/context.h"
#include "adamesh/simplify.h"

namespace adamesh::detail {

enum ViolationKind : int {
  kOk = 0,
  kPairBoundary = 1,   ///< a u-boundary in two or more arcs
  kFewNeighbours = 2,  ///< fewer than 3 neighbour cells (2 on the volume border)
  kNotDisk = 3,        ///< cell disconnected, pinched or not simply connected
  kFanPinch = 4,       ///< a node whose fan holds a cell twice apart, or an unsplittable quad
  kDuplicate = 5,      ///< two junctions with the same three cells
  kBorderArcs = 6,     ///< a cell meeting the volume border in two arcs; short border loop
};

/// Cells of the fan of node n in counter-clockwise order seen from outside; false when the
/// fan is not complete (node on the volume border).
bool ccw_fan(const SurfelComplex& sc, std::uint32_t n, std::array<std::int32_t, 4>& out);

class Voronoi {
 public:
  static constexpr std::uint32_t kNone = 0xffffffffu;

  Voronoi(const SurfelComplex& sc, const ConnectivityGraph& g);
  /// Optional: ticked in the long loops (cancellation, progress); never changes the result.
  StageTicker* ticker = nullptr;

  /// Adds cells with the given centres (cell id → centre c-vertex) by multi-source Dijkstra from
  /// the new centres only: a vertex changes cell only when it gets strictly closer (ties: the
  /// smaller centre id). Cells whose members or boundary changed are marked touched.
  void add_cells(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& cells);
  /// Removes fan pinches left by the discrete metric: a node whose complete fan holds one cell in
  /// two separate runs (cells touching themselves at a corner only) gets one of its surfels moved
  /// to a neighbouring cell, the move with the smallest increase of geodesic distance. Scans the
  /// nodes of the vertices changed since the last call. Returns the number of moves.
  std::size_t regularize();
  /// Takes a finished assignment (cell per vertex, kNone allowed) for checking only.
  void set_assignment(const std::vector<std::uint32_t>& cell, const std::vector<std::uint32_t>& centres);
  /// Removes vertices from every cell (fallback components).
  void remove_vertices(const std::vector<std::uint32_t>& vertices);

  std::uint32_t cell(std::uint32_t v) const { return cell_[v]; }
  double dist(std::uint32_t v) const { return dist_[v]; }
  std::uint32_t centre(std::uint32_t c) const { return centre_[c]; }
  std::size_t num_cells() const { return centre_.size(); }
  bool cell_alive(std::uint32_t c) const { return c < size_.size() && size_[c] > 0; }

  /// Cells touched since the last call (sorted, unique).
  std::vector<std::uint32_t> take_touched();

  /// Local closed-ball tests of one cell: returns a ViolationKind; fills the neighbour cells.
  int check_cell(std::uint32_t c, std::vector<std::uint32_t>& neighbours);

  const std::vector<std::uint32_t>& cells() const { return cell_; }
  /// Distinct cells adjacent (in G) to the members of cell c.
  void neighbour_cells(std::uint32_t c, std::vector<std::uint32_t>& out);

 private:
  void touch(std::uint32_t c) {
    if (c != kNone && c < touched_flag_.size() && !touched_flag_[c]) {
      touched_flag_[c] = 1;
      touched_.push_back(c);
    }
  }
  bool better(double d, std::uint32_t centre_vertex, std::uint32_t v) const;
  std::uint32_t next_stamp() {
    if (++gen_ == 0) {
      std::fill(stamp_.begin(), stamp_.end(), 0);
      gen_ = 1;
    }
    return gen_;
  }
  /// Members of cell c (BFS in G from its centre), stamped with the current generation.
  void members_of(std::uint32_t c, std::vector<std::uint32_t>& out);

  const SurfelComplex& sc_;
  const ConnectivityGraph& g_;
  std::vector<std::uint32_t> cell_;
  std::vector<double> dist_;
  std::vector<std::uint32_t> centre_;   // per cell
  std::vector<std::uint32_t> size_;     // per cell
  std::vector<std::uint8_t> touched_flag_;
  std::vector<std::uint32_t> touched_;
  /// Bit per node: a node of a vertex whose cell changed since the last regularize pass.
  std::vector<std::uint64_t> dirty_;
  bool any_dirty_ = false;
  void reassign(std::uint32_t v, std::uint32_t c, double d);
  // scratch for check_cell
  std::vector<std::uint32_t> stamp_;  ///< generation stamps; heap slots inside add_cells
  std::uint32_t gen_ = 0;
};

}  // namespace adamesh::detail

namespace adamesh::detail {

/// Global checks of the dual of a cell assignment: 3-junctions give one triangle, 4-junctions a
/// quad split along the shorter centre diagonal unless that pair is already an edge of the
/// dual. Cells involved in unsplittable quads, fan pinches or duplicate triangles are added to
/// `violated` (sorted, unique; kinds 4 and 5 counted in `kinds`).
void dual_violations(const SurfelComplex& sc, const std::vector<std::uint32_t>& cell,
                     const std::vector<std::uint32_t>& centre_of_cell,
                     std::vector<std::uint32_t>& violated, std::vector<std::size_t>* kinds,
                     StageTicker* ticker = nullptr);

}  // namespace adamesh::detail

namespace adamesh::detail {

struct HybridResult {
  /// Triangles over vertex ids: cell c → c, kept node kept_nodes[i] → num_cells + i.
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<std::uint32_t> kept_nodes;
  std::vector<std::uint32_t> problem_cells;  ///< cells whose links disagree with a neighbour's
};

/// Hybrid dual/cone triangulation (hybrid.cpp): the dual of the cells, except that cone cells
/// are triangulated as cones over their boundary nodes (which then become vertices).
HybridResult hybrid_triangles(const SurfelComplex& sc, const std::vector<std::uint32_t>& cell,
                              const std::vector<std::uint32_t>& centre,
                              const std::vector<std::uint8_t>& cone);

}  // namespace adamesh::detail
