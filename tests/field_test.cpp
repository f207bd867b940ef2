// Tests for src/field: sampled-volume fields (trilinear value, interpolated central-difference
// gradient), signed distance and Newton projection, the built-in shapes (gradients, location and
// topology of the sampled solid), muparser expressions and volume statistics.
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

#include "adamesh/error.h"
#include "adamesh/field.h"
#include "adamesh/input.h"
#include "adamesh/stats.h"
#include "testing.h"

using namespace adamesh;

namespace {

/// A volume on `grid` of type T with samples fn(i, j, k).
template <class T, class Fn>
Volume make_volume(const Grid& grid, Fn fn) {
  ScalarType type{};
  for (ScalarType t : {ScalarType::u8, ScalarType::i8, ScalarType::u16, ScalarType::i16, ScalarType::u32,
                       ScalarType::i32, ScalarType::f32, ScalarType::f64})
    dispatch_scalar(t, [&](auto tag) {
      if constexpr (std::is_same_v<decltype(tag), T>) type = t;
    });
  Volume v = allocate_volume(grid, type, "test");
  T* s = v.samples<T>();
  for (std::int64_t k = 0; k < grid.dims[2]; ++k)
    for (std::int64_t j = 0; j < grid.dims[1]; ++j)
      for (std::int64_t i = 0; i < grid.dims[0]; ++i)
        s[grid.linear_index(i, j, k)] = static_cast<T>(fn(double(i), double(j), double(k)));
  return v;
}

Grid rotated_grid(std::array<std::int64_t, 3> dims) {
  Grid g;
  g.dims = dims;
  g.spacing = {0.5, 1.25, 2.0};
  g.origin = {-3, 1, 7};
  const double c = std::cos(0.4), s = std::sin(0.4);
  // Rotation about z by 0.4 rad, then about x by 0.4 rad.
  const Mat3 rz = Mat3::from_columns({c, s, 0}, {-s, c, 0}, {0, 0, 1});
  const Mat3 rx = Mat3::from_columns({1, 0, 0}, {0, c, s}, {0, -s, c});
  g.direction = rx * rz;
  return g;
}

void expect_vec_near(const Vec3& a, const Vec3& b, double tol, const char* what = "") {
  EXPECT_NEAR(a.x, b.x, tol) << what;
  EXPECT_NEAR(a.y, b.y, tol) << what;
  EXPECT_NEAR(a.z, b.z, tol) << what;
}

template <class T>
void check_linear_field_exact() {
  const Grid g = rotated_grid({6, 5, 4});
  // s = 2i + 3j + k + 5 (in [5, 30]: representable in every type).
  const Volume v = make_volume<T>(g, [](double i, double j, double k) { return 2 * i + 3 * j + k + 5; });
  const auto f = make_volume_field(v);
  const Vec3 grad_index{2, 3, 1};
  const Vec3 expected_grad = g.index_to_world_matrix().inverse().transposed() * grad_index;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int n = 0; n < 200; ++n) {
    const Vec3 q{u(rng) * 5, u(rng) * 4, u(rng) * 3};
    const Vec3 p = g.to_world(q);
    EXPECT_NEAR(f->value(p), 2 * q.x + 3 * q.y + q.z + 5, 1e-9) << to_string(v.type);
    expect_vec_near(f->gradient(p), expected_grad, 1e-9, to_string(v.type));
  }
  // World gradient is consistent with finite differences of value() in world space.
  const Vec3 p = g.to_world({2.3, 1.7, 1.2});
  const double h = 1e-5;
  for (int a = 0; a < 3; ++a) {
    Vec3 e{};
    e[a] = h;
    EXPECT_NEAR((f->value(p + e) - f->value(p - e)) / (2 * h), expected_grad[a], 1e-6);
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Volume field

TEST(VolumeField, LinearFieldIsExactForEveryScalarType) {
  check_linear_field_exact<std::uint8_t>();
  check_linear_field_exact<std::int8_t>();
  check_linear_field_exact<std::uint16_t>();
  check_linear_field_exact<std::int16_t>();
  check_linear_field_exact<std::uint32_t>();
  check_linear_field_exact<std::int32_t>();
  check_linear_field_exact<float>();
  check_linear_field_exact<double>();
}

TEST(VolumeField, CentralDifferencesExactForQuadraticAtGridPoints) {
  Grid g;
  g.dims = {7, 6, 5};
  g.spacing = {0.5, 2, 1};
  const Volume v = make_volume<double>(g, [](double i, double j, double k) { return i * i + 3 * j * j - k * k; });
  const auto f = make_volume_field(v);
  for (int k = 1; k < 4; ++k)
    for (int j = 1; j < 5; ++j)
      for (int i = 1; i < 6; ++i) {
        const Vec3 p = g.to_world({double(i), double(j), double(k)});
        // d/dx = (2i)/sx, d/dy = 6j/sy, d/dz = -2k/sz.
        expect_vec_near(f->gradient(p), {2.0 * i / 0.5, 6.0 * j / 2, -2.0 * k / 1}, 1e-12);
        EXPECT_DOUBLE_EQ(f->value(p), i * i + 3 * j * j - k * k);
      }
  // One-sided at the border: i = 0 uses s[1] - s[0] = 1.
  EXPECT_NEAR(f->gradient(g.to_world({0, 2, 2})).x, 1 / 0.5, 1e-12);
  EXPECT_NEAR(f->gradient(g.to_world({6, 2, 2})).x, (36 - 25) / 0.5, 1e-12);
}

TEST(VolumeField, GradientConvergesToAnalyticWithResolution) {
  // f(p) = sin(2x) cos(y) + z², sampled on [-1,1]^3 at increasing resolution.
  auto analytic = [](const Vec3& p) {
    return Vec3{2 * std::cos(2 * p.x) * std::cos(p.y), -std::sin(2 * p.x) * std::sin(p.y), 2 * p.z};
  };
  double previous = 0;
  for (int n : {17, 33, 65}) {
    Grid g;
    g.dims = {n, n, n};
    const double h = 2.0 / (n - 1);
    g.spacing = {h, h, h};
    g.origin = {-1, -1, -1};
    const Volume v = make_volume<float>(g, [&](double i, double j, double k) {
      const Vec3 p = g.to_world({i, j, k});
      return std::sin(2 * p.x) * std::cos(p.y) + p.z * p.z;
    });
    const auto f = make_volume_field(v);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.8, 0.8);
    double err = 0;
    for (int s = 0; s < 500; ++s) {
      const Vec3 p{u(rng), u(rng), u(rng)};
      err = std::max(err, norm(f->gradient(p) - analytic(p)));
    }
    if (previous > 0) {
      EXPECT_LT(err, previous / 2.5) << "n=" << n;
    }
    previous = err;
  }
  EXPECT_LT(previous, 0.01);
}

TEST(VolumeField, ClampsOutsideAndHandlesSingleSampleAxes) {
  Grid g;
  g.dims = {4, 3, 1};
  const Volume v = make_volume<std::int16_t>(g, [](double i, double j, double) { return 10 * i + j; });
  const auto f = make_volume_field(v);
  EXPECT_DOUBLE_EQ(f->value({-5, 1, 0}), 1);       // clamped to i = 0
  EXPECT_DOUBLE_EQ(f->value({100, 2, 9}), 32);     // clamped to the corner (3, 2, 0)
  EXPECT_DOUBLE_EQ(f->value({1.5, 0.5, -3}), 15.5);
  const Vec3 gr = f->gradient({1.5, 0.5, 0});
  EXPECT_DOUBLE_EQ(gr.x, 10);
  EXPECT_DOUBLE_EQ(gr.y, 1);
  EXPECT_EQ(gr.z, 0);  // one sample along z: no derivative
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(std::isfinite(f->value({nan, 0, 0})));
  const Box d = f->domain();
  EXPECT_EQ(d.hi.x, 3);
  EXPECT_EQ(d.hi.y, 2);
}

TEST(VolumeField, SharedOwnershipKeepsVolumeAlive) {
  Grid g;
  g.dims = {3, 3, 3};
  std::shared_ptr<const ScalarField> f;
  {
    auto v = std::make_shared<Volume>(make_volume<float>(g, [](double i, double, double) { return i; }));
    f = make_volume_field(std::shared_ptr<const Volume>(v));
  }
  EXPECT_DOUBLE_EQ(f->value({1.25, 1, 1}), 1.25);
  EXPECT_FALSE(f->is_analytic());
}

// ---------------------------------------------------------------------------------------------
// Signed distance and projection

TEST(Projection, SignedDistanceOfDistanceFieldIsExact) {
  const auto s = make_shape_field("sphere");
  EXPECT_NEAR(signed_distance(*s, 0, {0.5, 0, 0}), -0.3, 1e-12);
  EXPECT_NEAR(signed_distance(*s, 0.1, {0, 1.0, 0}), 0.1, 1e-12);
  EXPECT_EQ(signed_distance(*s, 0, {0.8, 0, 0}), 0);
  const auto flat = make_expr_field("2", Box{{-1, -1, -1}, {1, 1, 1}});
  EXPECT_EQ(signed_distance(*flat, 0, {0, 0, 0}, 1e9), 1e9);
  EXPECT_EQ(signed_distance(*flat, 5, {0, 0, 0}, 1e9), -1e9);
}

TEST(Projection, ConvergesOntoSphereAndTorus) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const char* name : {"sphere", "torus"}) {
    const auto f = make_shape_field(name);
    int tried = 0;
    while (tried < 200) {
      const Vec3 p{u(rng), u(rng), u(rng)};
      const double d0 = std::abs(signed_distance(*f, 0, p));
      if (d0 > 0.2 || d0 < 1e-3) continue;
      ++tried;
      const ProjectResult r = project_to_iso(*f, 0, p);
      ASSERT_TRUE(r.converged) << name;
      EXPECT_LT(std::abs(f->value(r.point)), 1e-3) << name;
      EXPECT_LE(distance(r.point, p), d0 * 1.01 + 1e-3) << name;  // lands on the closest sheet
      EXPECT_GE(r.steps, 1);
    }
  }
}

TEST(Projection, ConvergesOnSampledSphere) {
  Grid g;
  g.dims = {41, 41, 41};
  g.spacing = {0.05, 0.05, 0.05};
  g.origin = {-1, -1, -1};
  const Volume v = make_volume<std::uint8_t>(g, [&](double i, double j, double k) {
    return 100.0 + 100.0 * (0.8 - norm(g.to_world({i, j, k})));  // bright inside
  });
  const auto f = make_volume_field(v);
  ProjectOptions o;
  o.tolerance = 1e-3 * 0.05;
  o.max_step = 0.5 * 0.05;
  for (const Vec3 p : {Vec3{0.83, 0.01, 0.02}, Vec3{0.1, -0.77, 0.05}, Vec3{0.4, 0.4, 0.4}}) {
    const ProjectResult r = project_to_iso(*f, 100, p, o);
    EXPECT_TRUE(r.converged);
    EXPECT_NEAR(norm(r.point), 0.8, 0.01);
    EXPECT_LT(std::abs(f->value(r.point) - 100), 0.1);
  }
}

TEST(Projection, RespectsStepCap) {
  const auto f = make_shape_field("sphere");
  ProjectOptions o;
  o.max_step = 0.1;
  o.max_steps = 3;
  const Vec3 p{2.5, 0, 0};
  const ProjectResult r = project_to_iso(*f, 0, p, o);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.steps, 3);
  EXPECT_NEAR(distance(r.point, p), 0.3, 1e-12);
  EXPECT_NEAR(r.residual, 2.5 - 0.8 - 0.3, 1e-12);
}

TEST(Projection, PlaneConstraintKeepsThePlane) {
  const auto f = make_shape_field("sphere");
  ProjectOptions o;
  o.plane_normal = {0, 0, 2};  // not unit: normalised internally
  o.tolerance = 1e-9;
  const Vec3 p{0.3, 0.2, 0.5};
  const ProjectResult r = project_to_iso(*f, 0, p, o);
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR(r.point.z, 0.5, 1e-12);
  EXPECT_NEAR(norm(r.point), 0.8, 1e-8);
  // The in-plane circle has radius sqrt(0.64 - 0.25); the point moved radially within the plane.
  EXPECT_NEAR(std::atan2(r.point.y, r.point.x), std::atan2(0.2, 0.3), 1e-9);
}

TEST(Projection, FlatGradientDoesNotMove) {
  const auto flat = make_expr_field("1.5", Box{{-1, -1, -1}, {1, 1, 1}});
  const Vec3 p{0.1, 0.2, 0.3};
  const ProjectResult r = project_to_iso(*flat, 0, p);
  EXPECT_EQ(r.point, p);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.steps, 0);
  EXPECT_FALSE(std::isnan(r.residual));
  // Constant sampled volume too.
  Grid g;
  g.dims = {4, 4, 4};
  const Volume v = make_volume<float>(g, [](double, double, double) { return 3; });
  const auto fv = make_volume_field(v);
  const ProjectResult rv = project_to_iso(*fv, 1, {1, 1, 1});
  EXPECT_EQ(rv.point, (Vec3{1, 1, 1}));
  EXPECT_FALSE(rv.converged);
}

TEST(Projection, FarPointsAndOvershootUseCapAndBisection) {
  const auto s = make_shape_field("sphere");
  const Vec3 far{100, 100, 100};
  const ProjectResult r = project_to_iso(*s, 0, far);
  EXPECT_NEAR(distance(r.point, far), 5 * 0.5, 1e-9);  // five capped steps towards the centre
  EXPECT_LT(r.residual, norm(far) - 0.8);
  ProjectOptions big;
  big.max_step = 1000;
  EXPECT_TRUE(project_to_iso(*s, 0, far, big).converged);

  // A steep step: Newton from x = 0 jumps far past the crossing at x = 0.3 (capped at 0.5);
  // the sign change is resolved by bisection along the step.
  const auto step = make_expr_field("tanh(20*(x-0.3))", Box{{-1, -1, -1}, {1, 1, 1}});
  const ProjectResult rs = project_to_iso(*step, 0, {0, 0.1, 0.2});
  EXPECT_TRUE(rs.converged);
  EXPECT_NEAR(rs.point.x, 0.3, 1e-3);
  EXPECT_EQ(rs.point.y, 0.1);
}

TEST(Projection, NeverIncreasesResidual) {
  const auto f = make_shape_field("gyroid");
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.95, 0.95);
  ProjectOptions o;
  o.max_step = 0.05;
  for (int n = 0; n < 500; ++n) {
    const Vec3 p{u(rng), u(rng), u(rng)};
    const double before = std::abs(signed_distance(*f, 0, p, std::numeric_limits<double>::max()));
    const ProjectResult r = project_to_iso(*f, 0, p, o);
    EXPECT_LE(r.residual, before);
    EXPECT_TRUE(std::isfinite(r.point.x) && std::isfinite(r.point.y) && std::isfinite(r.point.z));
  }
}

// ---------------------------------------------------------------------------------------------
// Shapes

namespace {

struct Topology {
  std::int64_t euler_solid = 0;  ///< χ of the cubical complex of inside samples
  int components = 0;            ///< 6-connected components of inside samples
  bool touches_box = false;      ///< some inside sample lies on the box border
};

/// Inside samples (f ≤ 0) of the shape on a res^3-ish grid over its default box, and the Euler
/// characteristic of the cubical complex they span (vertices − edges + squares − cubes). For a
/// well-resolved solid that complex is homotopy equivalent to the solid, and the closed surface
/// bounding it has χ = 2·χ(solid).
Topology sampled_topology(const ScalarField& f, int res) {
  const Box b = f.domain();
  const Vec3 ext = b.size();
  const double h = std::max({ext.x, ext.y, ext.z}) / (res - 1);
  const int nx = int(std::lround(ext.x / h)) + 1, ny = int(std::lround(ext.y / h)) + 1,
            nz = int(std::lround(ext.z / h)) + 1;
  std::vector<char> in(std::size_t(nx) * ny * nz);
  auto id = [&](int i, int j, int k) { return (std::size_t(k) * ny + j) * nx + i; };
  Topology t;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const Vec3 p{b.lo.x + i * h, b.lo.y + j * h, b.lo.z + k * h};
        in[id(i, j, k)] = f.value(p) <= 0;
        if (in[id(i, j, k)] && (i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1))
          t.touches_box = true;
      }
  auto at = [&](int i, int j, int k) { return i < nx && j < ny && k < nz && in[id(i, j, k)]; };
  std::int64_t v = 0, e = 0, s = 0, c = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (!at(i, j, k)) continue;
        ++v;
        e += at(i + 1, j, k) + at(i, j + 1, k) + at(i, j, k + 1);
        s += (at(i + 1, j, k) && at(i, j + 1, k) && at(i + 1, j + 1, k)) +
             (at(i + 1, j, k) && at(i, j, k + 1) && at(i + 1, j, k + 1)) +
             (at(i, j + 1, k) && at(i, j, k + 1) && at(i, j + 1, k + 1));
        bool cube = true;
        for (int q = 1; q < 8; ++q) cube = cube && at(i + (q & 1), j + (q >> 1 & 1), k + (q >> 2 & 1));
        c += cube;
      }
  t.euler_solid = v - e + s - c;
  std::vector<char> seen(in.size(), 0);
  std::vector<std::array<int, 3>> stack;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (!in[id(i, j, k)] || seen[id(i, j, k)]) continue;
        ++t.components;
        stack.push_back({i, j, k});
        seen[id(i, j, k)] = 1;
        while (!stack.empty()) {
          const auto [a, bb, cc] = stack.back();
          stack.pop_back();
          const int nb[6][3] = {{a - 1, bb, cc}, {a + 1, bb, cc}, {a, bb - 1, cc},
                                {a, bb + 1, cc}, {a, bb, cc - 1}, {a, bb, cc + 1}};
          for (const auto& q : nb) {
            if (q[0] < 0 || q[1] < 0 || q[2] < 0 || !at(q[0], q[1], q[2]) || seen[id(q[0], q[1], q[2])])
              continue;
            seen[id(q[0], q[1], q[2])] = 1;
            stack.push_back({q[0], q[1], q[2]});
          }
        }
      }
  return t;
}

}  // namespace

TEST(Shapes, NamesAndUnknownShapeError) {
  const auto names = shape_names();
  EXPECT_EQ(names.size(), 8u);
  for (const auto& n : names) EXPECT_TRUE(make_shape_field(n)->is_analytic()) << n;
  try {
    make_shape_field("blob");
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::invalid_input);
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("shape:blob: unknown shape", 0), 0u) << m;
    for (const auto& n : names) EXPECT_NE(m.find(n), std::string::npos) << m;
  }
}

TEST(Shapes, AnalyticGradientMatchesFiniteDifferences) {
  std::mt19937 rng(2);
  for (const auto& name : shape_names()) {
    const auto f = make_shape_field(name);
    const Box b = f->domain();
    std::uniform_real_distribution<double> ux(b.lo.x, b.hi.x), uy(b.lo.y, b.hi.y), uz(b.lo.z, b.hi.z);
    int checked = 0;
    for (int n = 0; n < 400; ++n) {
      const Vec3 p{ux(rng), uy(rng), uz(rng)};
      const double h = 1e-6, v0 = f->value(p);
      Vec3 fd, fwd, bwd;
      for (int a = 0; a < 3; ++a) {
        Vec3 e{};
        e[a] = h;
        const double vp = f->value(p + e), vm = f->value(p - e);
        fd[a] = (vp - vm) / (2 * h);
        fwd[a] = (vp - v0) / h;
        bwd[a] = (v0 - vm) / h;
      }
      if (norm(fwd - bwd) > 1e-3) continue;  // on a crease of min/max: not differentiable
      ++checked;
      expect_vec_near(f->gradient(p), fd, 1e-5, name.c_str());
    }
    EXPECT_GT(checked, 380) << name;
  }
}

TEST(Shapes, DistanceLikeNearTheSurface) {
  std::mt19937 rng(4);
  for (const auto& name : shape_names()) {
    const auto f = make_shape_field(name);
    const Box b = f->domain();
    std::uniform_real_distribution<double> ux(b.lo.x, b.hi.x), uy(b.lo.y, b.hi.y), uz(b.lo.z, b.hi.z);
    int near = 0;
    for (int n = 0; n < 20000 && near < 200; ++n) {
      const Vec3 p{ux(rng), uy(rng), uz(rng)};
      if (std::abs(f->value(p)) > 0.02) continue;
      ++near;
      const double g = norm(f->gradient(p));
      EXPECT_GT(g, 0.9) << name;
      EXPECT_LT(g, 1.2) << name;
    }
    EXPECT_GE(near, 50) << name;
  }
}

TEST(Shapes, SurfaceWhereDocumented) {
  EXPECT_NEAR(make_shape_field("sphere")->value({0, 0.8, 0}), 0, 1e-15);
  EXPECT_NEAR(make_shape_field("torus")->value({0, 0.85, 0}), 0, 1e-15);
  EXPECT_NEAR(make_shape_field("torus")->value({0.6, 0, 0.25}), 0, 1e-15);
  EXPECT_NEAR(make_shape_field("two_tori")->value({0.5 + 0.32 + 0.12, 0, 0}), 0, 1e-15);
  EXPECT_NEAR(make_shape_field("linked_tori")->value({0.25, 0, 0.45 + 0.12}), 0, 1e-15);
  EXPECT_NEAR(make_shape_field("linked_tori")->value({-0.25, 0.45 - 0.12, 0}), 0, 1e-15);
  EXPECT_NEAR(make_shape_field("genus2")->value({0.45 + 0.45 + 0.18, 0, 0}), 0, 1e-15);
  EXPECT_NEAR(make_shape_field("cube_minus_sphere")->value({0.6, 0.5, 0.55}), 0, 1e-15);
  EXPECT_NEAR(make_shape_field("cube_minus_sphere")->value({0.5, 0.55, 0}), 0.75 - std::hypot(0.5, 0.55), 1e-15);
  EXPECT_NEAR(make_shape_field("wavy_sheet")->value({0.5, 0.5, 0.25}), 0, 1e-15);
  // Gyroid: g = 0 where k·x + 3π/4 = 0 on every axis (inside the ball); outside the ball f ≥ |p| − 0.93.
  EXPECT_NEAR(make_shape_field("gyroid")->value({-0.375, -0.375, -0.375}), 0, 1e-15);
  EXPECT_GE(make_shape_field("gyroid")->value({0.95, 0, 0}), 0.02 - 1e-15);
  EXPECT_NEAR(make_shape_field("gyroid")->value({0, 0, 0}), -1 / (2 * std::numbers::pi), 1e-15);
  // Inside is negative.
  EXPECT_LT(make_shape_field("sphere")->value({0, 0, 0}), 0);
  EXPECT_LT(make_shape_field("torus")->value({0.6, 0, 0}), 0);
  EXPECT_LT(make_shape_field("wavy_sheet")->value({0, 0, -0.5}), 0);
}

TEST(Shapes, SampledTopologyMatchesTheCatalogue) {
  struct Expect {
    const char* name;
    int euler_surface;
    int components;
  };
  // χ of the closed surface = 2·χ(solid); tori: solid ≃ circle (χ 0); genus 2: ≃ figure eight
  // (χ −1); cube minus sphere: ≃ the cube's 12-edge frame (χ 8 − 12 = −4).
  for (const Expect& x : {Expect{"sphere", 2, 1}, Expect{"torus", 0, 1}, Expect{"two_tori", 0, 2},
                          Expect{"linked_tori", 0, 2}, Expect{"genus2", -2, 1},
                          Expect{"cube_minus_sphere", -8, 1}}) {
    for (int res : {48, 80}) {
      const Topology t = sampled_topology(*make_shape_field(x.name), res);
      EXPECT_EQ(2 * t.euler_solid, x.euler_surface) << x.name << " res " << res;
      EXPECT_EQ(t.components, x.components) << x.name << " res " << res;
      EXPECT_FALSE(t.touches_box) << x.name << " res " << res;
    }
  }
  // Gyroid: closed, one component, genus 13 (χ −24: measured, identical at every resolution
  // from 24 to 256 when the phase and radius were chosen; see shapes.cpp).
  for (int res : {32, 64, 96}) {
    const Topology g = sampled_topology(*make_shape_field("gyroid"), res);
    EXPECT_EQ(2 * g.euler_solid, -24) << "gyroid res " << res;
    EXPECT_EQ(g.components, 1) << "gyroid res " << res;
    EXPECT_FALSE(g.touches_box) << "gyroid res " << res;
  }
  // Wavy sheet: the solid below it is a ball cut by the box (χ 1) and the sheet leaves the box
  // through the four side faces only.
  const auto w = make_shape_field("wavy_sheet");
  const Topology tw = sampled_topology(*w, 48);
  EXPECT_EQ(tw.euler_solid, 1);
  EXPECT_EQ(tw.components, 1);
  for (double x : {-1.0, 1.0}) {
    EXPECT_LT(w->value({x, 0.3, 0}), 0);
    EXPECT_GT(w->value({x, 0.3, 0.1}), 0);
    EXPECT_LT(w->value({0.3, x, 0}), 0);
    EXPECT_GT(w->value({0.3, x, 0.1}), 0);
  }
  for (double x : {-1.0, -0.5, 0.0, 0.5, 1.0})
    for (double y : {-1.0, -0.5, 0.0, 0.5, 1.0}) {
      EXPECT_GT(w->value({x, y, 1}), 0);   // top face outside
      EXPECT_LT(w->value({x, y, -1}), 0);  // bottom face inside
    }
}

TEST(Shapes, CustomDomain) {
  const Box b{{0, 0, 0}, {2, 3, 4}};
  const Box d = make_shape_field("torus", b)->domain();
  EXPECT_EQ(d.hi.z, 4);
  EXPECT_EQ(make_shape_field("genus2")->domain().hi.x, 1.2);
}

// ---------------------------------------------------------------------------------------------
// Expressions

TEST(Expression, ValueAndFiniteDifferenceGradient) {
  const auto f = make_expr_field("x^2 + 2*y^2 + sin(z) - 0.25 + 0*pi", Box{{-1, -1, -1}, {1, 1, 1}});
  EXPECT_TRUE(f->is_analytic());
  const Vec3 p{0.3, -0.4, 0.7};
  EXPECT_NEAR(f->value(p), 0.09 + 0.32 + std::sin(0.7) - 0.25, 1e-14);
  expect_vec_near(f->gradient(p), {0.6, -1.6, std::cos(0.7)}, 1e-8);
  const auto lin = make_expr_field("3*x - y + 2*z", Box{{-1, -1, -1}, {1, 1, 1}});
  expect_vec_near(lin->gradient({0.1, 0.2, 0.3}), {3, -1, 2}, 1e-8);
  EXPECT_NEAR(make_expr_field("pi", Box{{0, 0, 0}, {1, 1, 1}})->value({}), std::numbers::pi, 1e-15);
}

TEST(Expression, ParseErrorsNameTheExpression) {
  for (const char* bad : {"x +* y", "w + 1", "sin(x", "", "x y"}) {
    try {
      make_expr_field(bad, Box{{-1, -1, -1}, {1, 1, 1}});
      ADD_FAILURE() << "no error for " << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::invalid_input);
      const std::string m = e.what();
      EXPECT_EQ(m.rfind(std::string("expr:'") + bad + "': ", 0), 0u) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
      EXPECT_GT(m.size(), std::string(bad).size() + 10) << m;
    }
  }
}

TEST(Expression, ConcurrentEvaluationEqualsSerial) {
  const auto f = make_expr_field("sin(3*x)*cos(2*y) + z^3 - x*y*z", Box{{-1, -1, -1}, {1, 1, 1}});
  const int n = 200000;
  std::vector<Vec3> pts(n);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  for (auto& p : pts) p = {u(rng), u(rng), u(rng)};
  std::vector<double> serial(n), parallel(n), threads(n);
  for (int i = 0; i < n; ++i) serial[i] = f->value(pts[i]);
  tbb::parallel_for(0, n, [&](int i) { parallel[i] = f->value(pts[i]) + 0 * f->gradient(pts[i]).x; });
  std::vector<std::thread> pool;
  for (int t = 0; t < 4; ++t)
    pool.emplace_back([&, t] {
      for (int i = t; i < n; i += 4) threads[i] = f->value(pts[i]);
    });
  for (auto& t : pool) t.join();
  EXPECT_EQ(serial, parallel);
  EXPECT_EQ(serial, threads);
}

// ---------------------------------------------------------------------------------------------
// Statistics

namespace {

/// Nearest-rank percentiles by sorting a copy (reference implementation).
std::array<double, 7> reference_percentiles(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  std::array<double, 7> r{};
  for (std::size_t q = 0; q < 7; ++q) {
    const double level = VolumeStats::kPercentileLevels[q];
    const auto rank = std::max<std::int64_t>(1, std::int64_t(std::ceil(level * double(v.size()) / 100 - 1e-9)));
    r[q] = v[std::size_t(rank - 1)];
  }
  return r;
}

template <class T, class Gen>
Volume random_volume(std::array<std::int64_t, 3> dims, Gen gen, std::vector<double>* values) {
  Grid g;
  g.dims = dims;
  std::mt19937 rng(1);
  Volume v = make_volume<T>(g, [&](double, double, double) { return gen(rng); });
  for (std::int64_t i = 0; i < g.num_samples(); ++i)
    if (std::isfinite(v.at(i))) values->push_back(v.at(i));
  return v;
}

}  // namespace

TEST(Stats, ExactPercentilesOnSmallIntegerVolume) {
  Grid g;
  g.dims = {10, 10, 1};
  // Values 1..100: the P-th nearest-rank percentile is P.
  const Volume v = make_volume<std::uint8_t>(g, [](double i, double j, double) { return 1 + i + 10 * j; });
  const VolumeStats s = compute_stats(v);
  EXPECT_EQ(s.samples, 100);
  EXPECT_EQ(s.finite, 100);
  EXPECT_EQ(s.min, 1);
  EXPECT_EQ(s.max, 100);
  EXPECT_DOUBLE_EQ(s.mean, 50.5);
  const std::array<double, 7> expect{1, 5, 25, 50, 75, 95, 99};
  EXPECT_EQ(s.percentiles, expect);
  EXPECT_EQ(s.percentile_error, 0);
}

TEST(Stats, PercentilesMatchSortingForEveryType) {
  std::vector<double> a, b, c, d, e, f;
  std::normal_distribution<double> nd(500, 120);
  const Volume v16 = random_volume<std::int16_t>({30, 20, 17}, [&](auto& r) { return std::round(nd(r)); }, &a);
  const Volume vu32 = random_volume<std::uint32_t>(
      {30, 20, 17}, [](auto& r) { return double(r() % 4000000000u); }, &b);
  const Volume vi32 = random_volume<std::int32_t>({9, 9, 9}, [](auto& r) { return double(int(r() % 1000) - 500); }, &c);
  const Volume vf = random_volume<float>({40, 30, 20}, [&](auto& r) { return nd(r); }, &d);
  std::uniform_real_distribution<double> ud(0, 1);
  // Heavy outliers: 1% huge values, so the first histogram level is useless and refinement works.
  const Volume vd = random_volume<double>(
      {25, 25, 25}, [&](auto& r) { return ud(r) < 0.01 ? 1e300 * ud(r) : ud(r); }, &e);
  const Volume vi8 = random_volume<std::int8_t>({5, 7, 3}, [](auto& r) { return double(int(r() % 256) - 128); }, &f);
  for (auto [vol, vals] : {std::pair{&v16, &a}, {&vu32, &b}, {&vi32, &c}, {&vf, &d}, {&vd, &e}, {&vi8, &f}}) {
    const VolumeStats s = compute_stats(*vol);
    const auto ref = reference_percentiles(*vals);
    for (std::size_t q = 0; q < 7; ++q)
      EXPECT_NEAR(s.percentiles[q], ref[q], s.percentile_error) << to_string(vol->type) << " q" << q;
    EXPECT_EQ(s.percentile_error, 0) << to_string(vol->type);
    EXPECT_EQ(s.min, *std::min_element(vals->begin(), vals->end()));
    EXPECT_EQ(s.max, *std::max_element(vals->begin(), vals->end()));
    double sum = 0;
    for (double x : *vals) sum += x;
    EXPECT_NEAR(s.mean, sum / double(vals->size()), 1e-9 * std::abs(s.max)) << to_string(vol->type);
  }
}

TEST(Stats, OtsuLiesBetweenModes) {
  std::normal_distribution<double> lo(100, 15), hi(900, 40);
  std::bernoulli_distribution coin(0.3);
  std::vector<double> vals;
  const Volume vi = random_volume<std::int16_t>(
      {32, 32, 32}, [&](auto& r) { return std::round(coin(r) ? hi(r) : lo(r)); }, &vals);
  const VolumeStats si = compute_stats(vi);
  EXPECT_GT(si.otsu, 250);
  EXPECT_LT(si.otsu, 750);
  EXPECT_EQ(si.otsu - std::floor(si.otsu), 0.5);  // integer data: half-integer iso
  const Volume vf = random_volume<float>({32, 32, 32}, [&](auto& r) { return coin(r) ? hi(r) : lo(r); }, &vals);
  const VolumeStats sf = compute_stats(vf);
  EXPECT_GT(sf.otsu, 250);
  EXPECT_LT(sf.otsu, 750);
  // Two spikes: the optimum is flat across the empty gap; the middle of it is chosen.
  Grid g;
  g.dims = {10, 10, 10};
  const Volume two = make_volume<std::uint8_t>(g, [](double i, double, double) { return i < 5 ? 10 : 200; });
  EXPECT_EQ(compute_stats(two).otsu, 104.5);
}

TEST(Stats, NonFiniteSamplesAreCountedAndIgnored) {
  Grid g;
  g.dims = {4, 3, 2};
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  Volume v = make_volume<float>(g, [&](double i, double j, double k) {
    if (i == 2 && j == 1 && k == 1) return nan;
    if (i == 3 && j == 2 && k == 1) return -inf;
    return i + j + k;
  });
  const VolumeStats s = compute_stats(v);
  EXPECT_EQ(s.nonfinite, 2);
  EXPECT_EQ(s.finite, 22);
  EXPECT_EQ(s.max, 5);  // 6 would be at (3,2,1), which is -inf
  std::array<std::int64_t, 3> first{};
  EXPECT_EQ(count_nonfinite(v, &first), 2);
  EXPECT_EQ(first, (std::array<std::int64_t, 3>{2, 1, 1}));
  EXPECT_EQ(replace_nonfinite(v, -7), 2);
  EXPECT_EQ(count_nonfinite(v), 0);
  EXPECT_EQ(v.at(2, 1, 1), -7);
  EXPECT_EQ(compute_stats(v).min, -7);
  // Integer volumes never have non-finite samples.
  const Volume vi = make_volume<std::int16_t>(g, [](double, double, double) { return 1; });
  EXPECT_EQ(count_nonfinite(vi), 0);
}

TEST(Stats, IndependentOfThreadCount) {
  std::vector<double> vals;
  std::normal_distribution<double> nd(0, 1);
  const Volume v = random_volume<float>({64, 64, 40}, [&](auto& r) { return nd(r); }, &vals);
  const VolumeStats many = compute_stats(v);
  VolumeStats one;
  tbb::task_arena arena(1);
  arena.execute([&] { one = compute_stats(v); });
  EXPECT_EQ(one.mean, many.mean);
  EXPECT_EQ(one.percentiles, many.percentiles);
  EXPECT_EQ(one.otsu, many.otsu);
}

namespace adamesh {
namespace {

// Label sets (--label, Python's label=): values and inclusive ranges, merged; anything else is
// a usage error naming the text.
TEST(LabelSet, ParsesValuesAndRangesAndMergesThem) {
  EXPECT_EQ(parse_label_set("5").to_string(), "5");
  EXPECT_EQ(parse_label_set("1-15").to_string(), "1-15");
  EXPECT_EQ(parse_label_set("9,1,3-5,4-7").to_string(), "1,3-7,9");
  EXPECT_EQ(parse_label_set("3,4,5").to_string(), "3-5");
  EXPECT_EQ(parse_label_set("-3--1,0").to_string(), "-3-0");
  const LabelSet s = parse_label_set("1,3,5-9");
  for (std::int64_t v : {1, 3, 5, 7, 9}) EXPECT_TRUE(s.contains(v)) << v;
  for (std::int64_t v : {0, 2, 4, 10}) EXPECT_FALSE(s.contains(v)) << v;
  for (const char* bad : {"", ",", "1,", ",1", "a", "1-", "5-3", "1-2-3", "1 ", "1;2",
                          "99999999999999999999"}) {
    try {
      parse_label_set(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::usage) << bad;
      EXPECT_NE(std::string(e.what()).find(std::string("'") + bad + "'"), std::string::npos) << e.what();
    }
  }
}

// The note for an iso-value on a label map: only with several labels on one side.
TEST(LabelSet, IsoValueNoteOnlyForSeveralLabelsOnOneSide) {
  auto volume = [](std::vector<std::uint8_t> values) {
    Grid g;
    g.dims = {static_cast<std::int64_t>(values.size()), 1, 1};
    Volume v = allocate_volume(g, ScalarType::u8, "v.raw");
    std::copy(values.begin(), values.end(), v.samples<std::uint8_t>());
    return v;
  };
  EXPECT_EQ(label_map_iso_note(volume({0, 1, 0, 1}), 0.5, +1), "");  // a mask
  // Two labels below, one above: the surface still depends on which one meets label 2.
  const std::string one = label_map_iso_note(volume({0, 1, 2, 0}), 1.5, +1);
  EXPECT_NE(one.find("`--label 2` meshes that label's boundary as a 0/1 mask"), std::string::npos) << one;
  EXPECT_EQ(label_map_iso_note(volume({0, 3, 3, 0}), 1.5, +1), "");       // one value each side
  EXPECT_NE(label_map_iso_note(volume({0, 1, 2, 0}), 0.5, +1), "");  // 1 and 2 above
  const std::string n = label_map_iso_note(volume({0, 4, 2, 9, 0}), 3.0, -1);  // inside: below 3
  EXPECT_NE(n.find("v.raw: looks like a label map (4 integer values, 2 of them below the iso-value 3)"),
            std::string::npos) << n;
  EXPECT_NE(n.find("`--label 0-2`"), std::string::npos) << n;
}

}  // namespace
}  // namespace adamesh
