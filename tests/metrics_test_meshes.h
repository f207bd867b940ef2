// Hand-made meshes with known answers for the metrics tests, and an analytic sphere field.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <numbers>
#include <utility>
#include <vector>

#include "adamesh/field.h"
#include "adamesh/mesh.h"

namespace adamesh::testmesh {

inline Mesh from(std::initializer_list<Vec3> verts, std::initializer_list<std::array<std::uint32_t, 3>> tris) {
  Mesh m;
  for (const auto& v : verts) m.add_vertex(v);
  for (const auto& t : tris) m.add_triangle(t[0], t[1], t[2]);
  return m;
}

/// Unit cube [0,1]³, 12 triangles, counter-clockwise seen from outside.
inline Mesh cube(Vec3 offset = {}) {
  Mesh m;
  for (int i = 0; i < 8; ++i) m.add_vertex(offset + Vec3{double(i & 1), double((i >> 1) & 1), double((i >> 2) & 1)});
  const std::uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                     {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.add_triangle(q[0], q[1], q[2]);
    m.add_triangle(q[0], q[2], q[3]);
  }
  return m;
}

/// Appends b to a (indices shifted).
inline Mesh merged(Mesh a, const Mesh& b) {
  const auto base = static_cast<std::uint32_t>(a.num_vertices());
  a.positions.insert(a.positions.end(), b.positions.begin(), b.positions.end());
  for (auto i : b.triangles) a.triangles.push_back(i + base);
  return a;
}

/// Torus grid: n × m quads, R major and r minor radius, outward orientation.
inline Mesh torus(int n, int m, double R = 1, double r = 0.3) {
  Mesh t;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double u = 2 * std::numbers::pi * i / n, v = 2 * std::numbers::pi * j / m;
      t.add_vertex({(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>((i % n) * m + (j % m)); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      t.add_triangle(id(i, j), id(i + 1, j), id(i + 1, j + 1));
      t.add_triangle(id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  return t;
}

/// Icosahedron subdivided `level` times, vertices on the sphere of radius r, outward.
inline Mesh icosphere(int level, double r = 1, Vec3 c = {}) {
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                         {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<std::array<std::uint32_t, 3>> f = {
      {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
      {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (auto& p : v) p = normalized(p);
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(normalized(v[a] + v[b]));
      return mid[key] = static_cast<std::uint32_t>(v.size() - 1);
    };
    std::vector<std::array<std::uint32_t, 3>> next;
    for (const auto& t : f) {
      const std::uint32_t ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({t[1], bc, ab});
      next.push_back({t[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    f = std::move(next);
  }
  Mesh m;
  for (const auto& p : v) m.add_vertex(c + r * p);
  for (const auto& t : f) m.add_triangle(t[0], t[1], t[2]);
  return m;
}

/// UV sphere with nu segments around and nv rings (2·nu·(nv − 1) triangles), outward.
inline Mesh uv_sphere(int nu, int nv, double r = 1) {
  Mesh m;
  m.add_vertex({0, 0, r});
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = std::numbers::pi * j / nv, ph = 2 * std::numbers::pi * i / nu;
      m.add_vertex({r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th)});
    }
  m.add_vertex({0, 0, -r});
  const auto south = static_cast<std::uint32_t>(m.num_vertices() - 1);
  auto id = [&](int j, int i) { return static_cast<std::uint32_t>(1 + (j - 1) * nu + (i % nu)); };
  m.triangles.reserve(6ull * nu * nv);
  for (int i = 0; i < nu; ++i) m.add_triangle(0, id(1, i), id(1, i + 1));
  for (int j = 1; j + 1 < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      m.add_triangle(id(j, i), id(j + 1, i), id(j + 1, i + 1));
      m.add_triangle(id(j, i), id(j + 1, i + 1), id(j, i + 1));
    }
  for (int i = 0; i < nu; ++i) m.add_triangle(south, id(nv - 1, i + 1), id(nv - 1, i));
  return m;
}

inline Mesh flipped(Mesh m) {
  for (std::size_t t = 0; t < m.num_triangles(); ++t) std::swap(m.triangles[3 * t + 1], m.triangles[3 * t + 2]);
  return m;
}

/// Exact signed distance to a sphere: f = |p − c| − r, negative inside (inside_sign −1).
class SphereField : public ScalarField {
 public:
  explicit SphereField(double r, Vec3 c = {}) : r_(r), c_(c) {}
  double value(const Vec3& p) const override { return norm(p - c_) - r_; }
  Vec3 gradient(const Vec3& p) const override { return normalized(p - c_); }
  bool is_analytic() const noexcept override { return true; }
  Box domain() const override { return {c_ - Vec3{2 * r_, 2 * r_, 2 * r_}, c_ + Vec3{2 * r_, 2 * r_, 2 * r_}}; }

 private:
  double r_;
  Vec3 c_;
};

}  // namespace adamesh::testmesh
