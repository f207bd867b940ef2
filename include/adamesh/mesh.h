// Index-based triangle mesh (struct of arrays).
//
// Conventions: positions are world coordinates (the units of the input file); triangles are
// counter-clockwise seen from outside the object, so the right-hand normal points out.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "adamesh/vec.h"

namespace adamesh {

/// A per-vertex scalar. Exactly one of f32 / i32 holds num_vertices() values.
struct VertexAttribute {
  std::string name;
  std::vector<float> f32;
  std::vector<std::int32_t> i32;
  bool is_integer() const noexcept { return !i32.empty() || f32.empty(); }
  std::size_t size() const noexcept { return i32.empty() ? f32.size() : i32.size(); }
};

struct Mesh {
  std::vector<float> positions;         ///< x0 y0 z0 x1 y1 z1 ...
  std::vector<std::uint32_t> triangles;  ///< a0 b0 c0 a1 b1 c1 ...
  std::vector<float> normals;           ///< empty, or 3 per vertex (unit, pointing out)
  std::vector<VertexAttribute> attributes;

  std::size_t num_vertices() const noexcept { return positions.size() / 3; }
  std::size_t num_triangles() const noexcept { return triangles.size() / 3; }
  Vec3 vertex(std::size_t v) const noexcept {
    return {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]};
  }
  std::uint32_t add_vertex(const Vec3& p) {
    positions.push_back(static_cast<float>(p.x));
    positions.push_back(static_cast<float>(p.y));
    positions.push_back(static_cast<float>(p.z));
    return static_cast<std::uint32_t>(num_vertices() - 1);
  }
  void add_triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    triangles.push_back(a);
    triangles.push_back(b);
    triangles.push_back(c);
  }
  const VertexAttribute* attribute(const std::string& name) const noexcept;
  /// Axis-aligned bounding box of the vertices (empty box at the origin when there are none).
  Box bounds() const noexcept;
};

}  // namespace adamesh
