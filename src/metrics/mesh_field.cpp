// A mesh as a scalar field (make_mesh_distance_field, include/adamesh/metrics.h): the signed
// distance to its closest triangle, through the same BVH as the Hausdorff distances. The sign
// is the side of the smooth normal at the closest point (the vertices' area-weighted normals
// interpolated there), so a point whose closest point is an edge or a vertex gets the side of
// the surface around it, not of one triangle; the gradient is the unit direction from the
// closest point (the normal at distance zero), so a Newton step lands on the closest point.
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>

#include "adamesh/metrics.h"
#include "bvh.h"

namespace adamesh {

namespace {

/// Closest point of triangle abc to p and its barycentric weights (Ericson, Real-Time
/// Collision Detection, 5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& w) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return w = {1, 0, 0}, a;
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return w = {0, 1, 0}, b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    w = {1 - v, v, 0};
    return a + v * ab;
  }
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return w = {0, 0, 1}, c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    w = {1 - t, 0, t};
    return a + t * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    w = {0, 1 - t, t};
    return b + t * (c - b);
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) {  // degenerate: the nearest of the three corners
    const double da = norm2(p - a), db = norm2(p - b), dc = norm2(p - c);
    if (da <= db && da <= dc) return w = {1, 0, 0}, a;
    if (db <= dc) return w = {0, 1, 0}, b;
    return w = {0, 0, 1}, c;
  }
  const double v = vb / sum, t = vc / sum;
  w = {1 - v - t, v, t};
  return a + v * ab + t * ac;
}

class MeshDistanceField final : public ScalarField {
 public:
  MeshDistanceField(Mesh mesh, const Box& domain)
      : mesh_(std::move(mesh)), bvh_(mesh_), domain_(domain), normal_(mesh_.num_vertices()) {
    for (std::size_t t = 0; t < mesh_.num_triangles(); ++t) {
      const std::uint32_t* v = &mesh_.triangles[3 * t];
      const Vec3 n = cross(mesh_.vertex(v[1]) - mesh_.vertex(v[0]), mesh_.vertex(v[2]) - mesh_.vertex(v[0]));
      for (int k = 0; k < 3; ++k) normal_[v[k]] = normal_[v[k]] + n;  // area-weighted
    }
  }

  double value(const Vec3& p) const override {
    Vec3 c, n;
    if (!closest(p, c, n)) return 0;
    const double d = distance(p, c);
    return dot(p - c, n) < 0 ? -d : d;
  }

  Vec3 gradient(const Vec3& p) const override {
    Vec3 c, n;
    if (!closest(p, c, n)) return {};
    const Vec3 d = p - c;
    const double len = norm(d);
    if (len <= 1e-12 * (1 + norm(p))) return normalized(n);
    return (dot(d, n) < 0 ? -1.0 / len : 1.0 / len) * d;
  }

  Box domain() const override { return domain_; }

 private:
  /// The closest point c on the mesh and the smooth normal n there; false without triangles.
  /// Callers ask for value() and gradient() at the same point, and then at a point nearby: the
  /// thread's last answer is reused for the same point and seeds the search for the next.
  bool closest(const Vec3& p, Vec3& c, Vec3& n) const {
    struct Last {
      const MeshDistanceField* field = nullptr;
      std::uint64_t generation = 0;
      Vec3 p, c, n;
      std::uint32_t triangle = detail::kNoTriangle;
    };
    thread_local Last last;
    const bool mine = last.field == this && last.generation == generation_;
    if (mine && last.p == p && last.triangle != detail::kNoTriangle) {
      c = last.c;
      n = last.n;
      return true;
    }
    const detail::TriangleBvh::Closest r =
        bvh_.closest(p, mine ? last.triangle : detail::kNoTriangle);
    if (r.triangle == detail::kNoTriangle) return false;
    const std::uint32_t* v = &mesh_.triangles[3 * static_cast<std::size_t>(r.triangle)];
    Vec3 w;
    c = closest_on_triangle(p, mesh_.vertex(v[0]), mesh_.vertex(v[1]), mesh_.vertex(v[2]), w);
    n = w.x * normal_[v[0]] + w.y * normal_[v[1]] + w.z * normal_[v[2]];
    if (!(norm2(n) > 0))  // opposite normals cancel: the triangle's own
      n = cross(mesh_.vertex(v[1]) - mesh_.vertex(v[0]), mesh_.vertex(v[2]) - mesh_.vertex(v[0]));
    last = Last{this, generation_, p, c, n, r.triangle};
    return true;
  }

  /// Distinguishes this field from an earlier one at the same address (the thread's cache).
  static std::uint64_t next_generation() {
    static std::atomic<std::uint64_t> g{0};
    return ++g;
  }
  const std::uint64_t generation_ = next_generation();

  Mesh mesh_;
  detail::TriangleBvh bvh_;
  Box domain_;
  std::vector<Vec3> normal_;
};

}  // namespace

std::unique_ptr<ScalarField> make_mesh_distance_field(Mesh mesh, const Box& domain) {
  return std::make_unique<MeshDistanceField>(std::move(mesh), domain);
}

}  // namespace adamesh
