// Reference marching cubes: triangulates each surfel polygon over the shared node vertices.
//
// References: Lorensen & Cline, "Marching Cubes" (SIGGRAPH 1987); the polygons come from the
// face-consistent surfel complex (Nielson & Hamann's asymptotic decider on faces), so the mesh is
// crack-free. Polygons with more than three nodes are triangulated without new vertices by the
// classic O(k³) dynamic programme over the k-gon (Klincsek 1980) maximising the minimum angle.
//
// Manifoldness: polygon edges are face segments, shared by exactly the two surfels across the
// face (one on the volume border). A diagonal joins two nodes of one voxel; it could also be used
// by the neighbour only if both nodes lie on their common face — which happens on ambiguous faces
// (four nodes, two segments). Some cycles (116 of the 1026 configuration cycles, e.g. the 8- and
// 9-node saddles) cannot avoid such a diagonal, so the two voxels of a face split the four
// candidate pairs (detail::diagonal_allowed); the DP minimises the use of the other side's
// pairs first (always zero, checked for every configuration by tests/mc_test.cpp), so no edge
// has more than two triangles and no triangle is repeated.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <cassert>

#include "adamesh/surfels.h"
#include "surfels/cell_table.h"
#include "surfels/polygon_triangulator.h"
#include "surfels/sized.h"

namespace adamesh {

Mesh marching_cubes(const SurfelComplex& cx) {
  Mesh mesh;
  const std::size_t ns = cx.num_surfels();
  const std::size_t ntri = cx.surfel_nodes.size() - 2 * ns;
  tbb::parallel_invoke([&] { detail::sized(mesh.triangles, 3 * ntri); },
                       [&] { detail::sized(mesh.positions, cx.node_pos.size()); });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cx.node_pos.size(), 1 << 16),
                    [&](const auto& r) {
                      std::copy(cx.node_pos.begin() + r.begin(), cx.node_pos.begin() + r.end(),
                                mesh.positions.begin() + r.begin());
                    });
  const std::int64_t nx = cx.grid.dims[0], plane = cx.grid.dims[0] * cx.grid.dims[1];

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ns, 4096), [&](const auto& r) {
    detail::PolygonTriangulator tri;
    std::array<Vec3, detail::kMaxPolygonNodes> p;
    std::array<int, detail::kMaxPolygonNodes> local_edge;
    for (std::size_t s = r.begin(); s < r.end(); ++s) {
      const auto nodes = cx.nodes_of(s);
      const int len = static_cast<int>(nodes.size());
      std::uint32_t* out = mesh.triangles.data() + 3 * (cx.surfel_offset[s] - 2 * s);
      if (len == 3) {
        out[0] = nodes[0];
        out[1] = nodes[1];
        out[2] = nodes[2];
        continue;
      }
      assert(len <= detail::kMaxPolygonNodes);
      const auto voxel = static_cast<std::int64_t>(cx.surfel_voxel[s]);
      for (int k = 0; k < len; ++k) {
        const std::uint32_t n = nodes[k];
        p[k] = cx.node_position(n);
        const std::uint64_t key = cx.node_key[n];
        const int axis = static_cast<int>(key % 3);
        std::int64_t d = static_cast<std::int64_t>(key / 3) - voxel;  // lower endpoint − voxel
        const int dz = d >= plane;
        d -= dz * plane;
        const int dy = d >= nx;
        const int dx = static_cast<int>(d - dy * nx);
        const int o[3] = {dx, dy, dz};
        const int a1 = axis == 0 ? 1 : 0, a2 = axis == 2 ? 1 : 2;
        local_edge[k] = 4 * axis + o[a1] + 2 * o[a2];
      }
      tri.run(len, p, local_edge, out, nodes.data());
    }
  });
  return mesh;
}

}  // namespace adamesh
