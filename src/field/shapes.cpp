// Built-in implicit shapes (`shape:NAME`): analytic value and gradient, negative inside, close to
// a signed distance (|∇f| ≈ 1 near the surface). Formulas, default boxes and expected topology
// are tabulated in docs/CONVENTIONS.md; tests/field_test.cpp checks the topology numerically.
//
// Building blocks (q = p − centre): sphere |q| − r; torus sqrt((ρ − R)² + h²) − r with ρ the
// distance to the torus axis and h the height along it; box (Inigo Quilez's exact box SDF);
// union = min, intersection = max, difference = max(a, −b). The gradient of min/max is the
// gradient of the active branch (one-sided on the crease).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "adamesh/error.h"
#include "adamesh/field.h"
#include "adamesh/input.h"

namespace adamesh {

namespace {

struct VG {
  double v;
  Vec3 g;
};

VG sphere(const Vec3& q, double r) {
  const double len = norm(q);
  return {len - r, len > 0 ? q / len : Vec3{}};
}

/// Torus of major radius R and tube radius r around axis `axis` (0=x, 1=y, 2=z) through the
/// origin of q; the ring lies in the plane orthogonal to the axis.
VG torus(const Vec3& q, int axis, double R, double r) {
  const int u = (axis + 1) % 3, w = (axis + 2) % 3;
  const double rho = std::hypot(q[u], q[w]);
  const double a = rho - R, h = q[axis];
  const double len = std::hypot(a, h);
  Vec3 g;
  if (len > 0) {
    if (rho > 0) {
      g[u] = a / len * q[u] / rho;
      g[w] = a / len * q[w] / rho;
    }
    g[axis] = h / len;
  }
  return {len - r, g};
}

/// Axis-aligned box of half-sizes `half` centred at the origin of q.
VG box(const Vec3& q, const Vec3& half) {
  Vec3 d, sgn;
  for (int a = 0; a < 3; ++a) {
    d[a] = std::abs(q[a]) - half[a];
    sgn[a] = q[a] < 0 ? -1 : 1;
  }
  const Vec3 out = vmax(d, Vec3{});
  const double out_len = norm(out);
  if (out_len > 0) return {out_len, cmul(sgn, out) / out_len};
  int a = 0;
  if (d[1] > d[a]) a = 1;
  if (d[2] > d[a]) a = 2;
  Vec3 g;
  g[a] = sgn[a];
  return {d[a], g};
}

VG unite(const VG& a, const VG& b) { return a.v <= b.v ? a : b; }
VG intersect(const VG& a, const VG& b) { return a.v >= b.v ? a : b; }
VG negate(const VG& a) { return {-a.v, -a.g}; }

// ---- The shapes. ----

VG shape_sphere(const Vec3& p) { return sphere(p, 0.8); }

VG shape_torus(const Vec3& p) { return torus(p, 2, 0.6, 0.25); }

VG shape_two_tori(const Vec3& p) {
  return unite(torus(p - Vec3{-0.5, 0, 0}, 2, 0.32, 0.12), torus(p - Vec3{0.5, 0, 0}, 2, 0.32, 0.12));
}

VG shape_linked_tori(const Vec3& p) {
  // Ring A in the xy-plane around (−0.25,0,0), ring B in the xz-plane around (0.25,0,0): each ring
  // passes through the other's hole; the rings are 0.4 apart at their closest, the tubes 0.16.
  return unite(torus(p - Vec3{-0.25, 0, 0}, 2, 0.45, 0.12),
               torus(p - Vec3{0.25, 0, 0}, 1, 0.45, 0.12));
}

// Gyroid labyrinth g < 0 capped by a ball. The phase (shift by −3/8 along (1,1,1)) and the
// radius 0.93 were chosen by scanning: the sphere then cuts the labyrinth transversally and the
// sampled topology is the same at every resolution from 24 to 256 (χ = −24, genus 13, one
// component). With phase 0 the ball centre sits on the surface and tangencies make tiny pieces.
constexpr double kGyroidK = 2 * std::numbers::pi;  // period 1: two periods across [-1,1]
constexpr double kGyroidPhase = 0.75 * std::numbers::pi;
constexpr double kGyroidScale = 1.5 * kGyroidK;     // |∇g| on g = 0 lies in [√2, √3]·k
constexpr double kGyroidBall = 0.93;

VG shape_gyroid(const Vec3& p) {
  const double x = kGyroidK * p.x + kGyroidPhase, y = kGyroidK * p.y + kGyroidPhase,
               z = kGyroidK * p.z + kGyroidPhase;
  const double sx = std::sin(x), cx = std::cos(x), sy = std::sin(y), cy = std::cos(y);
  const double sz = std::sin(z), cz = std::cos(z);
  const double g = sx * cy + sy * cz + sz * cx;
  const Vec3 dg{cx * cy - sz * sx, -sx * sy + cy * cz, -sy * sz + cz * cx};  // ∇g / k
  const VG gyroid{g / kGyroidScale, dg * (kGyroidK / kGyroidScale)};
  return intersect(gyroid, sphere(p, kGyroidBall));
}

VG shape_genus2(const Vec3& p) {
  return unite(torus(p - Vec3{-0.45, 0, 0}, 2, 0.45, 0.18), torus(p - Vec3{0.45, 0, 0}, 2, 0.45, 0.18));
}

VG shape_cube_minus_sphere(const Vec3& p) {
  return intersect(box(p, {0.6, 0.6, 0.6}), negate(sphere(p, 0.75)));
}

VG shape_wavy_sheet(const Vec3& p) {
  const double pi = std::numbers::pi;
  const double sx = std::sin(pi * p.x), cx = std::cos(pi * p.x);
  const double sy = std::sin(pi * p.y), cy = std::cos(pi * p.y);
  return {p.z - 0.2 * sx * sy - 0.05, {-0.2 * pi * cx * sy, -0.2 * pi * sx * cy, 1}};
}

struct ShapeDef {
  const char* name;
  VG (*eval)(const Vec3&);
  Box bounds;
};

constexpr Box kUnitBox{{-1, -1, -1}, {1, 1, 1}};

const ShapeDef kShapes[] = {
    {"sphere", shape_sphere, kUnitBox},
    {"torus", shape_torus, kUnitBox},
    {"two_tori", shape_two_tori, kUnitBox},
    {"linked_tori", shape_linked_tori, kUnitBox},
    {"gyroid", shape_gyroid, kUnitBox},
    {"genus2", shape_genus2, Box{{-1.2, -0.9, -0.5}, {1.2, 0.9, 0.5}}},
    {"cube_minus_sphere", shape_cube_minus_sphere, kUnitBox},
    {"wavy_sheet", shape_wavy_sheet, kUnitBox},
};

class ShapeField final : public ScalarField {
 public:
  ShapeField(const ShapeDef& def, const Box& domain) : def_(def), domain_(domain) {}
  double value(const Vec3& p) const override { return def_.eval(p).v; }
  Vec3 gradient(const Vec3& p) const override { return def_.eval(p).g; }
  bool is_analytic() const noexcept override { return true; }
  Box domain() const override { return domain_; }

 private:
  const ShapeDef& def_;
  Box domain_;
};

}  // namespace

std::vector<std::string> shape_names() {
  std::vector<std::string> names;
  for (const auto& s : kShapes) names.emplace_back(s.name);
  return names;
}

std::shared_ptr<const ScalarField> make_shape_field(const std::string& name,
                                                    const std::optional<Box>& domain) {
  for (const auto& s : kShapes)
    if (name == s.name) return std::make_shared<ShapeField>(s, domain.value_or(s.bounds));
  std::ostringstream os;
  os << "unknown shape (valid: ";
  for (std::size_t i = 0; i < std::size(kShapes); ++i) os << (i ? ", " : "") << kShapes[i].name;
  os << ")";
  fail_input("shape:" + name, os.str());
}

}  // namespace adamesh
