#include "adamesh/mesh.h"

namespace adamesh {

const VertexAttribute* Mesh::attribute(const std::string& name) const noexcept {
  for (const auto& a : attributes)
    if (a.name == name) return &a;
  return nullptr;
}

Box Mesh::bounds() const noexcept {
  if (num_vertices() == 0) return {};
  Box b{vertex(0), vertex(0)};
  for (std::size_t v = 1; v < num_vertices(); ++v) {
    b.lo = vmin(b.lo, vertex(v));
    b.hi = vmax(b.hi, vertex(v));
  }
  return b;
}

}  // namespace adamesh
