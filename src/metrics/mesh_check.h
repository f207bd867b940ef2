// Precondition check shared by the metric entry points: a mesh with bad indices or non-finite
// coordinates is refused with Error(invalid_input) instead of producing garbage numbers.
#pragma once

#include <cmath>
#include <string>

#include "adamesh/error.h"
#include "adamesh/mesh.h"

namespace adamesh::detail {

inline void check_mesh(const Mesh& m, const char* what = "mesh") {
  if (m.positions.size() % 3 != 0 || m.triangles.size() % 3 != 0)
    fail_input(what, "positions or triangles array length is not a multiple of 3");
  const std::size_t nv = m.num_vertices();
  for (std::size_t i = 0; i < m.triangles.size(); ++i)
    if (m.triangles[i] >= nv)
      fail_input(what, "triangle " + std::to_string(i / 3) + " refers to vertex " +
                           std::to_string(m.triangles[i]) + " of " + std::to_string(nv));
  for (std::size_t i = 0; i < m.positions.size(); ++i)
    if (!std::isfinite(m.positions[i]))
      fail_input(what, "vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
}

}  // namespace adamesh::detail
