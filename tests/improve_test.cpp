// Shape improvement (include/adamesh/improve.h): flips, moves with projection, collapses and
// splits keep the topology, the vertices on the surface and in the box, and raise the smallest
// angles.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <numbers>
#include <string>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/field.h"
#include "adamesh/improve.h"
#include "adamesh/input.h"
#include "adamesh/metrics.h"
#include "adamesh/simplify.h"
#include "adamesh/surfels.h"
#include "mesh_checks.h"

namespace adamesh {
namespace {

using testutil::MeshTopo;
using testutil::mesh_topo;

double min_angle_deg(const Mesh& m) { return quality(m).min_angle.min; }
double pct_below_20(const Mesh& m) { return quality(m).pct_min_angle_below[1]; }
double detail_min_angle_deg(const Vec3& a, const Vec3& b, const Vec3& c) {
  auto at = [](const Vec3& o, const Vec3& u, const Vec3& w) {
    return std::atan2(norm(cross(u - o, w - o)), dot(u - o, w - o));
  };
  const double x = at(a, b, c), y = at(b, c, a);
  return std::min({x, y, std::numbers::pi - x - y}) * 180 / std::numbers::pi;
}

/// A flat n×n grid of squares split along one diagonal, with every other interior vertex pushed
/// along x by `shift` of a cell: many slivers, all fixable by flips and moves in the plane.
Mesh sheared_grid(int n, double shift) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      double x = i, y = j;
      if (i > 0 && i < n && j > 0 && j < n && (i + j) % 2 == 0) x += shift;
      m.add_vertex({x, y, 0});
    }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.add_triangle(id(i, j), id(i + 1, j), id(i + 1, j + 1));
      m.add_triangle(id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  return m;
}

TEST(Improve, FlatGridSliversAreRemovedWithoutAField) {
  Mesh m = sheared_grid(12, 0.8);
  const MeshTopo before = mesh_topo(m);
  const double pct_before = pct_below_20(m);
  ASSERT_GT(pct_before, 10.0);
  ImproveOptions o;
  o.max_deviation = 1e-9;  // flat: any flip keeps the surface
  o.collapse_below_deg = 0;
  const ImproveStats st = improve_mesh(m, {}, nullptr, 0, o);
  EXPECT_GT(st.flips + st.moves, 0u);
  const MeshTopo after = mesh_topo(m);
  EXPECT_EQ(after.triangles, before.triangles);
  EXPECT_EQ(after.chi, before.chi);
  EXPECT_EQ(after.boundary_loops, 1);
  EXPECT_TRUE(after.oriented);
  EXPECT_EQ(after.nonmanifold_edges, 0);
  EXPECT_LT(pct_below_20(m), 1.0);
  EXPECT_GT(min_angle_deg(m), 20.0);
  // Everything stays in the plane z = 0, and the boundary vertices where they were.
  for (std::size_t v = 0; v < m.num_vertices(); ++v) EXPECT_EQ(m.vertex(v).z, 0.0);
  EXPECT_EQ(m.vertex(0).x, 0.0);
  EXPECT_EQ(m.vertex(12).x, 12.0);
}

TEST(Improve, FixedVerticesStayAndTheBoxHolds) {
  Mesh m = sheared_grid(8, 0.7);
  std::vector<std::uint8_t> fixed(m.num_vertices(), 0);
  fixed[4 * 9 + 4] = 1;  // the centre (i = j = 4), pushed by 0.7
  const Vec3 centre = m.vertex(4 * 9 + 4);
  ImproveOptions o;
  o.max_deviation = 1e-9;
  o.box = Box{{0, 0, -1}, {8, 8, 1}};
  improve_mesh(m, fixed, nullptr, 0, o);
  EXPECT_EQ(m.vertex(4 * 9 + 4), centre);
  for (std::size_t v = 0; v < m.num_vertices(); ++v) {
    const Vec3 p = m.vertex(v);
    EXPECT_TRUE(p.x >= 0 && p.x <= 8 && p.y >= 0 && p.y <= 8) << v;
  }
}

// A speck (docs/QUALITY.md "Rescue"): a closed needle 0.18 long and 0.008 thick — under two
// voxels of 0.1 — has no well-shaped mesh on its surface. The rescue replaces it with a
// tetrahedron in its principal box: sphere topology and orientation kept, every angle ≥ 25°,
// the vertices within a voxel of the surface.
TEST(Improve, RescueReplacesASpeckKeepingTopologyAndOrientation) {
  const Box box{{-1, -1, -1}, {1, 1, 1}};
  const auto f = make_expr_field("(x/0.09)^2+(y/0.004)^2+(z/0.004)^2-1", box);
  Mesh m;
  m.add_vertex({0.09, 0, 0});
  m.add_vertex({-0.09, 0, 0});
  for (int k = 0; k < 3; ++k) {
    const double a = 2 * std::numbers::pi * k / 3;
    m.add_vertex({0, 0.004 * std::cos(a), 0.004 * std::sin(a)});
  }
  for (std::uint32_t k = 0; k < 3; ++k) {
    m.add_triangle(0, 2 + k, 2 + (k + 1) % 3);
    m.add_triangle(1, 2 + (k + 1) % 3, 2 + k);
  }
  auto volume = [](const Mesh& x) {
    double v = 0;
    for (std::size_t t = 0; t < x.num_triangles(); ++t)
      v += dot(x.vertex(x.triangles[3 * t]),
               cross(x.vertex(x.triangles[3 * t + 1]), x.vertex(x.triangles[3 * t + 2])));
    return v;
  };
  ASSERT_GT(volume(m), 0);
  ASSERT_LT(min_angle_deg(m), 5);
  ImproveOptions o;
  o.voxel = 0.1;
  o.box = box;
  const ImproveStats plain = [&] {
    Mesh copy = m;
    return improve_mesh(copy, {}, f.get(), 0.0, o);
  }();
  EXPECT_LT(plain.min_angle_after_deg, 10);  // on the surface, nothing fixes it
  EXPECT_EQ(plain.specks, 0u);
  o.rescue_below_deg = 20;
  // A fixed triangle elsewhere: its flags follow the renumbering (remap_vertex_flags).
  const Vec3 far[3] = {{0.5, 0.5, 0.5}, {0.6, 0.5, 0.5}, {0.5, 0.6, 0.5}};
  for (const Vec3& p : far) m.add_vertex(p);
  m.add_triangle(5, 6, 7);
  std::vector<std::uint8_t> fixed(8, 0);
  fixed[5] = fixed[6] = fixed[7] = 1;
  std::vector<std::uint32_t> map;
  const ImproveStats st = improve_mesh(m, fixed, f.get(), 0.0, o, &map);
  const std::vector<std::uint8_t> kept = remap_vertex_flags(fixed, map, m.num_vertices());
  ASSERT_EQ(kept.size(), m.num_vertices());
  int flagged = 0;
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    if (kept[v]) {
      ++flagged;
      const Vec3 p = m.vertex(v);
      EXPECT_LT(std::min({distance(p, far[0]), distance(p, far[1]), distance(p, far[2])}), 1e-6) << v;
    }
  EXPECT_EQ(flagged, 3);
  ASSERT_EQ(m.num_triangles(), 5u);
  {  // the speck alone
    Mesh speck;
    speck.positions = m.positions;
    for (std::size_t t = 0; t < m.num_triangles(); ++t)
      if (!kept[m.triangles[3 * t]])
        speck.add_triangle(m.triangles[3 * t], m.triangles[3 * t + 1], m.triangles[3 * t + 2]);
    for (auto& i : speck.triangles) ASSERT_FALSE(kept[i]);
    m = std::move(speck);
  }
  EXPECT_EQ(st.specks, 1u);
  EXPECT_EQ(m.num_triangles(), 4u);
  const MeshTopo t = mesh_topo(m);
  EXPECT_EQ(t.chi, 2);
  EXPECT_EQ(t.components, 1);
  EXPECT_TRUE(t.oriented);
  EXPECT_GT(volume(m), 0);
  EXPECT_GE(min_angle_deg(m), 25);
  for (std::uint32_t v : m.triangles)
    EXPECT_LT(std::abs(signed_distance(*f, 0.0, m.vertex(v))), o.voxel);
}


/// Base mesh of a sampled noisy shape: the improvement keeps the topology and the count, puts
/// the moved vertices on the surface and raises the smallest angles.
TEST(Improve, NoisyBaseMeshKeepsTopologyAndGetsBetter) {
  // A sphere with voxel-scale bumps, sampled (not analytic: the trilinear field is bumpy).
  InputOptions io;
  io.resolution = 48;
  const Input in = load_input("expr:x^2+y^2+z^2-0.6+0.02*sin(40*x)*sin(37*y)*sin(43*z)", io);
  const SurfelComplex sc = build_surfels(*in.volume, 0.0, in.inside_sign);
  BaseMesh base = simplify(sc, in.field.get());
  const MeshTopo before = mesh_topo(base.mesh);
  const double worst_before = min_angle_deg(base.mesh);
  Mesh m = base.mesh;
  ImproveOptions o;
  o.voxel = sc.grid.min_spacing();
  o.box = in.field->domain();
  o.target_triangles = m.num_triangles();
  std::vector<std::uint8_t> fixed = base.border;
  const ImproveStats st = improve_mesh(m, fixed, in.field.get(), 0.0, o);
  const MeshTopo after = mesh_topo(m);
  EXPECT_EQ(after.chi, before.chi);
  EXPECT_EQ(after.components, before.components);
  EXPECT_EQ(after.boundary_loops, before.boundary_loops);
  EXPECT_EQ(after.nonmanifold_edges, 0);
  EXPECT_TRUE(after.oriented);
  EXPECT_LE(std::abs(after.triangles - before.triangles), 1);
  EXPECT_GE(min_angle_deg(m), worst_before);
  EXPECT_LE(st.pct_below_20_after, st.pct_below_20_before);
  // Vertices on the iso-surface (moved ones are projected, the others were already on it).
  double worst = 0;
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    worst = std::max(worst, std::abs(signed_distance(*in.field, 0.0, m.vertex(v))));
  EXPECT_LT(worst, 0.05 * o.voxel);
}

TEST(Fit, ReportsProgressAndHonoursCancelWithAThreadCount) {
  // fit_least_squares() with context.threads > 0 runs itself inside a task arena; that inner
  // call used to get a default context, so neither progress nor cancellation reached it.
  InputOptions io;
  io.resolution = 32;
  const Input in = load_input("shape:sphere", io);
  const SurfelComplex sc = build_surfels(*in.volume, 0.0, in.inside_sign);
  const BaseMesh base = simplify(sc, in.field.get());
  FitOptions fo;
  fo.max_step = 0.5 * sc.grid.min_spacing();
  for (const int threads : {0, 1, 2}) {
    SCOPED_TRACE(threads);
    Mesh m = base.mesh;
    int reports = 0;
    ExecutionContext ctx;
    ctx.threads = threads;
    ctx.progress = [&](const char* stage, double) { reports += std::string(stage) == "fit"; };
    const FitStats st = fit_least_squares(m, base.border, *in.field, 0.0, fo, ctx);
    EXPECT_EQ(st.passes, fo.passes);
    EXPECT_EQ(reports, fo.passes);
    std::atomic<bool> stop{true};
    ExecutionContext cancelled;
    cancelled.threads = threads;
    cancelled.cancel = &stop;
    try {
      (void)fit_least_squares(m, base.border, *in.field, 0.0, fo, cancelled);
      ADD_FAILURE() << "not cancelled";
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::cancelled);
    }
  }
}

// Free moves (FitOptions::free_moves, the default) on a crease: the roof z = 1 − |x| meshed by a
// grid whose columns straddle the ridge (x = ±0.25), so the triangles between them cut under it.
// Moving along the vertex normal only cannot bring a vertex onto the ridge; moving in the span of
// the sample normals (x and z here) can. Measured (the fit's RMS): 0.0457 on the surface, 0.0400
// after the normal-only fit, 0.0162 after the free one.
// Asserted: the free fit is much closer, no vertex moves along y (no normal has a y component,
// so that direction is not constrained and must not move), the boundary stays, no triangle
// below min(its angle, 20°), and the same result for 1 and 2 threads.
TEST(Fit, FreeMovesReachACreaseAndMoveOnlyWhereNormalsConstrain) {
  class Roof : public ScalarField {
   public:
    double value(const Vec3& p) const override { return p.z - (1 - std::abs(p.x)); }
    Vec3 gradient(const Vec3& p) const override { return {p.x < 0 ? -1.0 : 1.0, 0, 1}; }
    bool is_analytic() const noexcept override { return true; }
    Box domain() const override { return {{-2, -1, -1}, {2, 5, 3}}; }
  } roof;
  const std::vector<double> xs = {-1.25, -0.75, -0.25, 0.25, 0.75, 1.25};
  const int ny = 9;  // y = 0, 0.5, …, 4
  Mesh m;
  for (int j = 0; j < ny; ++j)
    for (const double x : xs) m.add_vertex({x, 0.5 * j, 1 - std::abs(x)});
  const auto nx = static_cast<std::uint32_t>(xs.size());
  for (std::uint32_t j = 0; j + 1 < ny; ++j)
    for (std::uint32_t i = 0; i + 1 < nx; ++i) {
      const std::uint32_t a = j * nx + i, b = a + 1, c = a + nx, d = c + 1;
      m.add_triangle(a, b, d);
      m.add_triangle(a, d, c);
    }
  FitOptions normal_only;
  normal_only.free_moves = false;
  normal_only.max_step = 0.25;
  FitOptions free = normal_only;
  free.free_moves = true;
  Mesh a = m, b = m, c = m;
  const FitStats sa = fit_least_squares(a, {}, roof, 0.0, normal_only);
  ExecutionContext one;
  one.threads = 1;
  const FitStats sb = fit_least_squares(b, {}, roof, 0.0, free, one);
  ExecutionContext two;
  two.threads = 2;
  (void)fit_least_squares(c, {}, roof, 0.0, free, two);
  EXPECT_EQ(b.positions, c.positions);
  EXPECT_NEAR(sa.rms_before, sb.rms_before, 1e-12);
  EXPECT_LT(sa.rms_after, sa.rms_before);
  EXPECT_LT(sb.rms_after, 0.5 * sa.rms_after) << sa.rms_before << " " << sa.rms_after << " " << sb.rms_after;
  const double e_on = field_error(m, roof, 0.0).distance.rms;
  EXPECT_LT(field_error(b, roof, 0.0).distance.rms, 0.5 * field_error(a, roof, 0.0).distance.rms)
      << e_on;
  for (std::size_t v = 0; v < m.num_vertices(); ++v) {
    EXPECT_EQ(b.vertex(v).y, m.vertex(v).y) << v;
    const std::size_t i = v % nx, j = v / nx;
    if (i == 0 || i + 1 == nx || j == 0 || j + 1 == ny) EXPECT_EQ(b.vertex(v), m.vertex(v)) << v;
  }
  for (std::size_t t = 0; t < m.num_triangles(); ++t) {
    auto angle = [&](const Mesh& x) {
      return detail_min_angle_deg(x.vertex(x.triangles[3 * t]), x.vertex(x.triangles[3 * t + 1]),
                                  x.vertex(x.triangles[3 * t + 2]));
    };
    EXPECT_GE(angle(b), std::min(angle(m), 20.0) - 1e-4) << t;
  }
}

TEST(Improve, Deterministic) {
  Mesh a = sheared_grid(10, 0.75), b = sheared_grid(10, 0.75);
  ImproveOptions o;
  o.max_deviation = 1e-9;
  improve_mesh(a, {}, nullptr, 0, o);
  improve_mesh(b, {}, nullptr, 0, o);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.triangles, b.triangles);
}

TEST(Improve, DecimationReachesTheTargetAndKeepsTopology) {
  const Input in = load_input("shape:torus");
  const SurfelComplex sc = build_surfels(*in.volume, 0.0, in.inside_sign);
  BaseMesh base = simplify(sc, in.field.get());
  const MeshTopo before = mesh_topo(base.mesh);
  const std::size_t target = base.mesh.num_triangles() / 3;
  ImproveOptions o;
  o.voxel = sc.grid.min_spacing();
  o.box = in.field->domain();
  const ImproveStats st = improve_base_mesh(base, in.field.get(), 0.0, o, target);
  EXPECT_GT(st.decimated, 0u);
  EXPECT_LE(base.mesh.num_triangles(), target + 2);
  const MeshTopo after = mesh_topo(base.mesh);
  EXPECT_EQ(after.chi, before.chi);
  EXPECT_EQ(after.components, before.components);
  EXPECT_TRUE(after.oriented);
  EXPECT_EQ(after.nonmanifold_edges, 0);
  ASSERT_EQ(base.anchor.size(), base.mesh.num_vertices());
  ASSERT_EQ(base.border.size(), base.mesh.num_vertices());
  EXPECT_GT(min_angle_deg(base.mesh), 15.0);
}

// The decimation goes by quadric error (docs/QUALITY.md "Decimation by quadric error"): on a
// plane with a bump it removes the flat part's triangles first, so the bump keeps its density and
// the flat part ends much coarser (shortest edge first left both about as dense).
TEST(Improve, DecimationKeepsTrianglesWhereTheSurfaceBends) {
  InputOptions io;
  io.resolution = 96;
  const Input in = load_input("expr:z - 0.4*exp(-(x^2+y^2)/0.02)", io);
  const SurfelComplex sc = build_surfels(*in.volume, 0.0, in.inside_sign);
  BaseMesh base = simplify(sc, in.field.get());
  // Triangles per unit area on the bump (centroid within 0.2 of the axis) and on the flat part
  // (beyond 0.5 from it, inside the box's margin).
  auto densities = [](const Mesh& m) {
    double area[2] = {0, 0};
    std::size_t count[2] = {0, 0};
    for (std::size_t t = 0; t < m.num_triangles(); ++t) {
      const Vec3 a = m.vertex(m.triangles[3 * t]), b = m.vertex(m.triangles[3 * t + 1]),
                 c = m.vertex(m.triangles[3 * t + 2]);
      const Vec3 g = (a + b + c) / 3.0;
      const double r = std::hypot(g.x, g.y);
      const int k = r < 0.2 ? 0 : (r > 0.5 && std::abs(g.x) < 0.9 && std::abs(g.y) < 0.9) ? 1 : -1;
      if (k < 0) continue;
      area[k] += 0.5 * norm(cross(b - a, c - a));
      ++count[k];
    }
    return std::array<double, 2>{count[0] / area[0], count[1] / area[1]};
  };
  const auto before = densities(base.mesh);
  const MeshTopo topo = mesh_topo(base.mesh);
  ImproveOptions o;
  o.voxel = sc.grid.min_spacing();
  o.box = in.field->domain();
  const std::size_t target = base.mesh.num_triangles() / 3;
  const ImproveStats st = improve_base_mesh(base, in.field.get(), 0.0, o, target);
  EXPECT_GT(st.decimated, 0u);
  EXPECT_LE(base.mesh.num_triangles(), target + 2);
  const auto after = densities(base.mesh);
  // The covering's disks make M0 about as dense on the bump as on the flat part.
  EXPECT_LT(before[0], 2.0 * before[1]);
  // 272 against 58 triangles per unit area (shortest edge first: 99 against 81).
  EXPECT_GT(after[0], 3.0 * after[1]) << after[0] << " " << after[1];
  const MeshTopo t = mesh_topo(base.mesh);
  EXPECT_EQ(t.chi, topo.chi);
  EXPECT_EQ(t.boundary_loops, topo.boundary_loops);
  EXPECT_GT(min_angle_deg(base.mesh), 15.0);
}

TEST(Improve, UntangleRemovesAFoldAndKeepsTopology) {
  // A flat 10×10 grid whose vertex (5, 5) is dragged across its neighbour (6, 5): the triangles
  // around it overlap their neighbours. Untangling (no field: plain averaging) unfolds them.
  Mesh m = sheared_grid(10, 0.0);
  const std::uint32_t v = 5 * 11 + 5;
  m.positions[3 * v] += 1.6f;
  ASSERT_GT(self_intersections(m).pairs, 0);
  std::vector<std::uint8_t> fixed(m.num_vertices(), 0);
  for (std::uint32_t j = 0; j <= 10; ++j)
    for (std::uint32_t i = 0; i <= 10; ++i) fixed[j * 11 + i] = i == 0 || j == 0 || i == 10 || j == 10;
  const MeshTopo before = mesh_topo(m);
  ImproveOptions o;
  o.untangle = true;
  o.collapse_below_deg = 0;
  const ImproveStats st = improve_mesh(m, fixed, nullptr, 0, o);
  EXPECT_GT(st.intersections_before, 0u);
  EXPECT_EQ(st.intersections_after, 0u);
  EXPECT_EQ(self_intersections(m).pairs, 0);
  const MeshTopo after = mesh_topo(m);
  EXPECT_EQ(after.chi, before.chi);
  EXPECT_EQ(after.triangles, before.triangles);
  // Without untangling the fold stays (the shape moves do not aim at it).
  Mesh n = sheared_grid(10, 0.0);
  n.positions[3 * v] += 1.6f;
  o.untangle = false;
  const ImproveStats plain = improve_mesh(n, fixed, nullptr, 0, o);
  EXPECT_EQ(plain.intersections_before, 0u);  // not measured
}

/// A flat 8×8 grid at z = 0 whose centre vertex is raised to `lift`, and a small square sheet
/// (two triangles) at z = 0.1 over the centre: the raised vertex's triangles poke through it.
Mesh poked_sheet(double lift) {
  Mesh m = sheared_grid(8, 0.0);
  const std::uint32_t centre = 4 * 9 + 4;
  m.positions[3 * centre + 2] = static_cast<float>(lift);
  const std::uint32_t a = m.add_vertex({3.6, 3.6, 0.1}), b = m.add_vertex({4.4, 3.6, 0.1}),
                      c = m.add_vertex({4.4, 4.4, 0.1}), d = m.add_vertex({3.6, 4.4, 0.1});
  m.add_triangle(a, b, c);
  m.add_triangle(a, c, d);
  return m;
}

TEST(Separate, PushesAPokingVertexBackAcrossThePlane) {
  Mesh m = poked_sheet(0.15);
  const Mesh before = m;
  ASSERT_GT(self_intersections(m).pairs, 0);
  std::vector<std::uint8_t> fixed(m.num_vertices(), 0);
  SeparateOptions o;
  o.voxel = 1;
  const SeparateStats st = separate_crossings(m, fixed, o);
  EXPECT_GT(st.intersections_before, 0u);
  EXPECT_EQ(st.intersections_after, 0u);
  EXPECT_EQ(self_intersections(m).pairs, 0);
  EXPECT_EQ(st.moved, 1u);  // the centre, just below the sheet's plane
  const std::uint32_t centre = 4 * 9 + 4;
  EXPECT_LT(m.positions[3 * centre + 2], 0.1f);
  EXPECT_GT(m.positions[3 * centre + 2], 0.09f);
  EXPECT_NEAR(st.max_move, 0.05 + 1e-3, 1e-6);
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    if (v != centre)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(m.positions[3 * v + k], before.positions[3 * v + k]);
  EXPECT_EQ(m.triangles, before.triangles);
  EXPECT_GE(min_angle_deg(m), std::min(20.0, min_angle_deg(before)));
  // The same for any thread count.
  Mesh again = poked_sheet(0.15);
  ExecutionContext one;
  one.threads = 1;
  separate_crossings(again, fixed, o, one);
  EXPECT_EQ(again.positions, m.positions);
}

TEST(Separate, FixedVerticesReachAndTheBoxHold) {
  const std::uint32_t centre = 4 * 9 + 4;
  // The centre fixed (the sheet's vertices are on the mesh's boundary): it stays, and what
  // separates the pair is the next option, its neighbours lifted over the sheet.
  {
    Mesh m = poked_sheet(0.15);
    std::vector<std::uint8_t> fixed(m.num_vertices(), 0);
    fixed[centre] = 1;
    const Mesh before = m;
    const SeparateStats st = separate_crossings(m, fixed, SeparateOptions{});
    EXPECT_EQ(m.vertex(centre), before.vertex(centre));
    EXPECT_EQ(st.intersections_after, static_cast<std::size_t>(self_intersections(m).pairs));
    EXPECT_LE(st.max_move, 0.5 + 1e-9);
  }
  // Every push longer than the reach (half of a 0.01 voxel): nothing moves.
  {
    Mesh m = poked_sheet(0.15);
    SeparateOptions o;
    o.voxel = 0.01;
    const Mesh before = m;
    const SeparateStats st = separate_crossings(m, {}, o);
    EXPECT_GT(st.intersections_after, 0u);
    EXPECT_EQ(st.intersections_after, st.intersections_before);
    EXPECT_EQ(m.positions, before.positions);
  }
  // A box the cheapest push would leave (the centre to z = 0.099): no vertex moves out of it.
  {
    Mesh m = poked_sheet(0.15);
    SeparateOptions o;
    o.box = Box{{-1, -1, 0.0995}, {9, 9, 1}};
    const Mesh before = m;
    separate_crossings(m, {}, o);
    EXPECT_GE(m.positions[3 * centre + 2], 0.0995f);
    for (std::size_t v = 0; v < m.num_vertices(); ++v)
      if (m.vertex(v) != before.vertex(v)) EXPECT_GE(m.positions[3 * v + 2], 0.0995f) << v;
  }
  SeparateOptions bad;
  bad.voxel = 0;
  Mesh m = poked_sheet(0.15);
  EXPECT_THROW(separate_crossings(m, {}, bad), Error);
}

}  // namespace
}  // namespace adamesh
