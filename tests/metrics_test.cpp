// Metrics on hand-made meshes with known answers: topology (χ, components, loops, genus,
// non-manifold, duplicates, orientation), triangle quality, area/volume, error against an
// analytic sphere field, Hausdorff distances, thread-count independence, and timings.
#include <chrono>
#include <cmath>
#include <ctime>
#include <numbers>
#include <random>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/metrics.h"
#include "mesh_checks.h"
#include "metrics/bvh.h"
#include "metrics_test_meshes.h"
#include "testing.h"

using namespace adamesh;
using namespace adamesh::testmesh;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

// ------------------------------------------------------------------------------ quality

TEST(Quality, EquilateralTriangle) {
  const Mesh m = from({{0, 0, 0}, {1, 0, 0}, {0.5, std::sqrt(3.0) / 2, 0}}, {{0, 1, 2}});
  const QualityReport q = quality(m);
  EXPECT_NEAR(q.q_mean, 1.0, 1e-7);
  EXPECT_NEAR(q.min_angle.min, 60, 1e-5);
  EXPECT_NEAR(q.min_angle.median, 60, 1e-5);
  EXPECT_NEAR(q.max_angle, 60, 1e-5);
  EXPECT_EQ(q.q_hist[19], 1);
  EXPECT_EQ(q.pct_min_angle_below[2], 0.0);
}

TEST(Quality, RightIsoscelesTriangle) {
  const Mesh m = from({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  const QualityReport q = quality(m);
  EXPECT_NEAR(q.q_mean, 2 * (std::sqrt(2.0) - 1), 1e-12);  // 0.8284
  EXPECT_NEAR(q.min_angle.min, 45, 1e-12);
  EXPECT_NEAR(q.max_angle, 90, 1e-12);
  EXPECT_EQ(q.q_hist[16], 1);  // [0.80, 0.85)
  EXPECT_EQ(q.pct_min_angle_below[0], 0.0);
}

TEST(Quality, SliversPercentilesAndDegenerates) {
  // 100 isosceles triangles with apex angle a_k = k + 0.5 degrees: smallest angle
  // min(a_k, (180 − a_k)/2).
  Mesh m;
  std::vector<double> expect;
  for (int k = 1; k <= 100; ++k) {
    const double apex = (k + 0.5) * std::numbers::pi / 180;
    const auto base = static_cast<std::uint32_t>(m.num_vertices());
    m.add_vertex({0, 0, double(k)});
    m.add_vertex({std::cos(apex / 2), std::sin(apex / 2), double(k)});
    m.add_vertex({std::cos(apex / 2), -std::sin(apex / 2), double(k)});
    m.add_triangle(base, base + 1, base + 2);
    expect.push_back(std::min(k + 0.5, (180.0 - k - 0.5) / 2));
  }
  const QualityReport q = quality(m);
  std::sort(expect.begin(), expect.end());
  EXPECT_NEAR(q.min_angle.min, 1.5, 1e-9);
  EXPECT_NEAR(q.min_angle.p1, expect[0], 1e-5);
  EXPECT_NEAR(q.min_angle.p5, expect[4], 1e-5);      // nearest rank: ceil(0.05·100) = 5th
  EXPECT_NEAR(q.min_angle.median, expect[49], 1e-5);  // 50th of 100
  EXPECT_NEAR(q.pct_min_angle_below[0], 9, 1e-12);    // 1.5° .. 9.5°
  EXPECT_NEAR(q.pct_min_angle_below[1], 19, 1e-12);
  EXPECT_NEAR(q.pct_min_angle_below[2], 29, 1e-12);
  std::int64_t total = 0;
  for (auto c : q.q_hist) total += c;
  EXPECT_EQ(total, 100);

  const Mesh flat = from({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {3, 3, 1}});
  const QualityReport d = quality(flat);
  EXPECT_EQ(d.min_angle.min, 0);
  EXPECT_EQ(d.max_angle, 180);
  EXPECT_EQ(d.q_hist[0], 2);
  EXPECT_EQ(d.q_mean, 0);
  const TopologyReport t = topology(flat);
  EXPECT_EQ(t.degenerate_triangles, 2);
  EXPECT_EQ(t.collapsed_triangles, 1);
  EXPECT_EQ(t.edges, 3);  // the collapsed triangle is not part of the topology
}

// ------------------------------------------------------------------------------ topology

TEST(Topology, UnitCube) {
  const Mesh m = cube();
  const TopologyReport t = topology(m);
  EXPECT_EQ(t.vertices, 8);
  EXPECT_EQ(t.edges, 18);
  EXPECT_EQ(t.triangles, 12);
  EXPECT_EQ(t.euler, 2);
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.genus, 0);
  ASSERT_EQ(t.component_list.size(), 1u);
  EXPECT_EQ(t.component_list[0].genus, 0);
  EXPECT_TRUE(t.closed);
  EXPECT_TRUE(t.oriented);
  EXPECT_EQ(t.nonmanifold_edges + t.nonmanifold_vertices + t.degenerate_triangles + t.duplicate_triangles, 0);
  EXPECT_NEAR(surface_area(m), 6, 1e-12);
  EXPECT_NEAR(signed_volume(m), 1, 1e-12);
  EXPECT_NEAR(*enclosed_volume(m, t), 1, 1e-12);
  EXPECT_NEAR(signed_volume(flipped(m)), -1, 1e-12);
}

TEST(Topology, CubeWithOneFlippedTriangle) {
  Mesh m = cube();
  std::swap(m.triangles[1], m.triangles[2]);
  const TopologyReport t = topology(m);
  EXPECT_FALSE(t.oriented);
  EXPECT_EQ(t.inconsistent_edges, 3);
  EXPECT_TRUE(t.closed);
  EXPECT_TRUE(t.component_list[0].orientable);
  EXPECT_FALSE(t.component_list[0].oriented);
  EXPECT_EQ(t.genus, 0);  // still a sphere
  EXPECT_FALSE(enclosed_volume(m, t).has_value());
}

TEST(Topology, Tetrahedron) {
  const Mesh m = from({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
  const TopologyReport t = topology(m);
  EXPECT_EQ(t.vertices, 4);
  EXPECT_EQ(t.edges, 6);
  EXPECT_EQ(t.euler, 2);
  EXPECT_EQ(t.genus, 0);
  EXPECT_TRUE(t.oriented);
  EXPECT_NEAR(*enclosed_volume(m, t), 1.0 / 6, 1e-12);
  EXPECT_NEAR(surface_area(m), 1.5 + std::sqrt(3.0) / 2, 1e-12);
}

TEST(Topology, OpenSquare) {
  const Mesh m = from({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}});
  const TopologyReport t = topology(m);
  EXPECT_EQ(t.euler, 1);
  EXPECT_EQ(t.boundary_loops, 1);
  EXPECT_EQ(t.boundary_edges, 4);
  EXPECT_FALSE(t.closed);
  EXPECT_TRUE(t.oriented);
  EXPECT_EQ(t.component_list[0].genus, 0);  // a disk: χ 1 = 2 − 2g − 1
  EXPECT_EQ(t.genus, 0);
  EXPECT_FALSE(enclosed_volume(m, t).has_value());
}

TEST(Topology, TwoTrianglesSharingOnlyAVertex) {
  const Mesh m = from({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}}, {{0, 1, 2}, {0, 3, 4}});
  const TopologyReport t = topology(m);
  EXPECT_EQ(t.nonmanifold_vertices, 1);
  EXPECT_EQ(t.nonmanifold_edges, 0);
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.euler, 1);           // 5 − 6 + 2
  EXPECT_EQ(t.boundary_loops, 2);  // split at the pinch: one loop per triangle
}

TEST(Topology, ThreeTrianglesOnOneEdge) {
  // Edge 0-1 shared by three triangles: one non-manifold edge; both its endpoints have three
  // fans (non-manifold vertices); cut along the edge, each triangle is a disk of its own:
  // three boundary loops (docs/METRICS.md).
  const Mesh m = from({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}, {0.5, 0, 1}}, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}});
  const TopologyReport t = topology(m);
  EXPECT_EQ(t.nonmanifold_edges, 1);
  EXPECT_EQ(t.nonmanifold_vertices, 2);
  EXPECT_EQ(t.boundary_edges, 6);
  EXPECT_EQ(t.boundary_loops, 3);
  EXPECT_EQ(t.euler, 5 - 7 + 3);
  EXPECT_FALSE(t.component_list[0].manifold);
}

TEST(Topology, ClosedSurfacesGluedAlongAnEdgeHaveNoBoundaryLoop) {
  // Two tetrahedra sharing edge 0-1: the edge has four triangles; cutting there leaves only
  // cycles of non-manifold sides, which are not boundary loops.
  Mesh m = from({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0.5, 1}, {0.5, -1, 0}, {0.5, -0.5, -1}},
                {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {0, 1, 4}, {0, 5, 1}, {0, 4, 5}, {1, 5, 4}});
  const TopologyReport t = topology(m);
  EXPECT_EQ(t.nonmanifold_edges, 1);
  EXPECT_EQ(t.boundary_edges, 0);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_FALSE(t.closed);
  EXPECT_FALSE(t.component_list[0].genus.has_value());
}

TEST(Topology, DuplicateTriangles) {
  Mesh m = cube();
  m.add_triangle(m.triangles[3], m.triangles[5], m.triangles[4]);  // triangle 1 reversed
  const TopologyReport t = topology(m);
  EXPECT_EQ(t.duplicate_triangles, 1);
  EXPECT_EQ(t.nonmanifold_edges, 3);
  EXPECT_EQ(t.triangles, 13);
  const Mesh pillow = from({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 1}, {1, 2, 0}});
  const TopologyReport p = topology(pillow);
  EXPECT_EQ(p.duplicate_triangles, 2);
}

TEST(Topology, TorusHasGenusOne) {
  const Mesh m = torus(24, 12);
  const TopologyReport t = topology(m);
  EXPECT_EQ(t.vertices, 24 * 12);
  EXPECT_EQ(t.edges, 3 * 24 * 12);
  EXPECT_EQ(t.euler, 0);
  EXPECT_EQ(t.genus, 1);
  EXPECT_TRUE(t.closed);
  EXPECT_TRUE(t.oriented);
  EXPECT_GT(signed_volume(m), 0);
  // Exact volume of the polyhedral torus is below 2π²Rr² and approaches it.
  EXPECT_NEAR(signed_volume(m), 2 * std::numbers::pi * std::numbers::pi * 0.09, 0.1);
}

TEST(Topology, TwoDisjointCubes) {
  const Mesh m = merged(cube(), cube({3, 0, 0}));
  const TopologyReport t = topology(m);
  EXPECT_EQ(t.components, 2);
  EXPECT_EQ(t.euler, 4);
  EXPECT_EQ(t.genus, 0);
  ASSERT_EQ(t.component_list.size(), 2u);
  for (const auto& c : t.component_list) {
    EXPECT_EQ(c.euler, 2);
    EXPECT_EQ(c.genus, 0);
    EXPECT_EQ(c.triangles, 12);
  }
  EXPECT_NEAR(*enclosed_volume(m, t), 2, 1e-12);
  // A torus next to a sphere: genus per component 1 and 0, total 1.
  const TopologyReport u = topology(merged(torus(16, 8), icosphere(1, 0.5, {5, 0, 0})));
  ASSERT_EQ(u.component_list.size(), 2u);
  EXPECT_EQ(u.component_list[0].genus, 1);
  EXPECT_EQ(u.component_list[1].genus, 0);
  EXPECT_EQ(u.genus, 1);
}

TEST(Topology, CubesTouchingAtAVertexArePinched) {
  const Mesh m = merged(cube(), cube({1, 1, 1}));
  Mesh welded = m;  // merge vertex 7 of the first cube with vertex 0 of the second
  for (auto& i : welded.triangles)
    if (i == 8) i = 7;
  const TopologyReport t = topology(welded);
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.nonmanifold_vertices, 1);
  EXPECT_EQ(t.unreferenced_vertices, 1);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_TRUE(t.closed);  // every edge has two triangles ...
  EXPECT_FALSE(t.component_list[0].manifold);  // ... but the vertex is pinched: no genus
  EXPECT_FALSE(t.component_list[0].genus.has_value());
}

TEST(Topology, MoebiusStripIsNotOrientable) {
  const int n = 12;
  Mesh m;
  for (int i = 0; i < n; ++i) {
    const double u = 2 * std::numbers::pi * i / n;
    for (int s : {-1, 1}) {
      const double w = 0.3 * s;
      m.add_vertex({(1 + w * std::cos(u / 2)) * std::cos(u), (1 + w * std::cos(u / 2)) * std::sin(u), w * std::sin(u / 2)});
    }
  }
  for (int i = 0; i < n; ++i) {
    const std::uint32_t a = 2 * i, b = 2 * i + 1;
    // The strip closes with a half twist: the last quad connects to the swapped pair.
    const std::uint32_t c = i + 1 < n ? 2 * (i + 1) : 1, d = i + 1 < n ? 2 * (i + 1) + 1 : 0;
    m.add_triangle(a, c, d);
    m.add_triangle(a, d, b);
  }
  const TopologyReport t = topology(m);
  EXPECT_EQ(t.euler, 0);
  EXPECT_EQ(t.boundary_loops, 1);
  EXPECT_FALSE(t.oriented);
  EXPECT_FALSE(t.component_list[0].orientable);
}

TEST(Topology, AgreesWithTheSimpleOracleOnRandomSoups) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    Mesh m = icosphere(2);
    std::uniform_int_distribution<std::uint32_t> vert(0, static_cast<std::uint32_t>(m.num_vertices() - 1));
    for (int k = 0; k < 30; ++k) m.add_triangle(vert(rng), vert(rng), vert(rng));  // noise
    m.triangles.erase(m.triangles.begin(), m.triangles.begin() + 3 * (trial * 7));
    const TopologyReport t = topology(m);
    const testutil::MeshTopo o = testutil::mesh_topo(m);
    EXPECT_EQ(t.vertices, o.vertices);
    EXPECT_EQ(t.edges, o.edges);
    EXPECT_EQ(t.euler + t.collapsed_triangles, o.chi);  // the oracle counts collapsed triangles as faces
    EXPECT_EQ(t.components, o.components);
    EXPECT_EQ(t.nonmanifold_edges, o.nonmanifold_edges);
    EXPECT_EQ(t.degenerate_triangles, o.degenerate);
    EXPECT_EQ(t.duplicate_triangles, o.duplicates);
    EXPECT_EQ(t.oriented, o.oriented);
  }
}

TEST(Topology, InvalidMeshIsRefused) {
  Mesh m = cube();
  m.triangles[5] = 100;
  try {
    topology(m);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::invalid_input);
    EXPECT_NE(std::string(e.what()).find("refers to vertex 100"), std::string::npos);
  }
  const TopologyReport empty = topology(Mesh{});
  EXPECT_EQ(empty.vertices, 0);
  EXPECT_FALSE(empty.closed);
  EXPECT_EQ(quality(Mesh{}).triangles, 0);
}

// --------------------------------------------------------------------- against a field

TEST(FieldError, IcosphereAgainstAnalyticSphere) {
  const double R = 2.0;
  const SphereField f(R);
  double prev_mean = 0, prev_eps_e = 0;
  for (int level = 2; level <= 5; ++level) {
    const Mesh m = icosphere(level, R);
    FieldErrorOptions o;
    o.inside_sign = -1;
    const FieldErrorReport r = field_error(m, f, 0.0, o);
    // Vertices lie on the sphere; the chord error of a triangle peaks at the foot of the
    // perpendicular from the centre: R − (distance from the centre to the plane).
    double worst = 0;
    for (std::size_t t = 0; t < m.num_triangles(); ++t) {
      const Vec3 a = m.vertex(m.triangles[3 * t]), b = m.vertex(m.triangles[3 * t + 1]),
                 c = m.vertex(m.triangles[3 * t + 2]);
      worst = std::max(worst, R - std::abs(dot(normalized(cross(b - a, c - a)), a)));
    }
    EXPECT_LE(r.distance.max, worst * (1 + 1e-6)) << "level " << level;
    EXPECT_GE(r.distance.max, 0.8 * worst) << "level " << level;
    EXPECT_GT(r.distance.mean, 0.2 * worst);
    EXPECT_LT(r.distance.mean, r.distance.rms);
    EXPECT_LE(r.distance.p99, r.distance.max);
    EXPECT_NEAR(r.distance_rel.max, r.distance.max / r.diagonal, 1e-15);
    EXPECT_NEAR(r.diagonal, 2 * R * std::sqrt(3.0), 0.2);
    EXPECT_EQ(r.unconverged, 0);
    EXPECT_GT(r.eps_n, 0);
    EXPECT_LT(r.eps_n, 0.02);
    EXPECT_GT(r.eps_e, 0);
    EXPECT_NEAR(r.eps_e_sqrt_rel, std::sqrt(r.eps_e) / r.diagonal, 1e-15);
    if (level > 2) {  // chord error ~ h²: about 4× smaller per subdivision
      EXPECT_GT(prev_mean / r.distance.mean, 3.0) << "level " << level;
      EXPECT_LT(prev_mean / r.distance.mean, 5.0) << "level " << level;
      EXPECT_GT(prev_eps_e / r.eps_e, 9.0) << "ε_e ~ h⁴";
    }
    prev_mean = r.distance.mean;
    prev_eps_e = r.eps_e;
  }
}

TEST(FieldError, EdgeDeviationOfASingleTriangleByHand) {
  // Plane field f = z, iso 0; triangle at height 0.5 with legs 1: every midpoint is at D = 0.5,
  // each edge is a border edge with weight A/2, so ε_e = 3·0.25·(A/2)/A = 0.375.
  class PlaneField : public ScalarField {
   public:
    double value(const Vec3& p) const override { return p.z; }
    Vec3 gradient(const Vec3&) const override { return {0, 0, 1}; }
    Box domain() const override { return {{-1, -1, -1}, {2, 2, 2}}; }
  } plane;
  const Mesh m = from({{0, 0, 0.5}, {1, 0, 0.5}, {0, 1, 0.5}}, {{0, 1, 2}});
  FieldErrorOptions o;
  o.samples = 1000;
  o.inside_sign = -1;  // inside below: outward normal +z, the triangle's normal is +z
  const FieldErrorReport r = field_error(m, plane, 0.0, o);
  EXPECT_NEAR(r.eps_e, 0.375, 1e-9);  // not analytic: gradients by differences
  EXPECT_NEAR(r.eps_n, 0, 1e-15);
  EXPECT_NEAR(r.distance.mean, 0.5, 1e-9);
  EXPECT_NEAR(r.distance.max, 0.5, 1e-9);
  o.inside_sign = 1;  // now the outward normal is −z: opposite
  EXPECT_NEAR(field_error(m, plane, 0.0, o).eps_n, 2, 1e-15);
  // Two triangles sharing an edge, same height: the shared edge has weight (A1 + A2)/2.
  const Mesh sq = from({{0, 0, 0.5}, {1, 0, 0.5}, {1, 1, 0.5}, {0, 1, 0.5}}, {{0, 1, 2}, {0, 2, 3}});
  // Σ_e U = 0.25·(4 border edges·A/2 + 1 shared edge·A) with A = 0.5: 0.25·(1 + 0.5) = 0.375,
  // total area 1.
  EXPECT_NEAR(field_error(sq, plane, 0.0, o).eps_e, 0.375, 1e-9);
}

TEST(FieldError, SampledFieldsAreMeasuredOnTheirValuesNotTheirGradient) {
  // A non-analytic field whose gradient() is misleading (as interpolated sample gradients can
  // be in thin structures): distances come from its values alone and match the exact ones.
  class MisleadingSphere : public ScalarField {
   public:
    double value(const Vec3& p) const override { return norm(p) - 1; }
    Vec3 gradient(const Vec3& p) const override { return cross(normalized(p), {0.3, 0.4, 0.5}) + normalized(p) * 0.1; }
    Box domain() const override { return {{-2, -2, -2}, {2, 2, 2}}; }
  } misleading;
  const SphereField exact(1.0);
  const Mesh m = icosphere(3);
  FieldErrorOptions o;
  o.inside_sign = -1;
  o.samples = 20000;
  const FieldErrorReport a = field_error(m, exact, 0.0, o), b = field_error(m, misleading, 0.0, o);
  EXPECT_NEAR(b.distance.mean, a.distance.mean, 1e-7 * a.distance.mean);
  EXPECT_NEAR(b.distance.max, a.distance.max, 1e-7 * a.distance.max);
  EXPECT_NEAR(b.eps_e, a.eps_e, 1e-6 * a.eps_e);
  EXPECT_EQ(b.unconverged, 0);
}

TEST(FieldError, NormalDeviationIsAboutTwoForInwardFacingMesh) {
  const SphereField f(1.0);
  FieldErrorOptions o;
  o.inside_sign = -1;
  const FieldErrorReport in = field_error(flipped(icosphere(4)), f, 0.0, o);
  EXPECT_GT(in.eps_n, 1.99);
  EXPECT_LE(in.eps_n, 2.0);
  const FieldErrorReport out = field_error(icosphere(4), f, 0.0, o);
  EXPECT_LT(out.eps_n, 0.001);
  EXPECT_NEAR(in.eps_e, out.eps_e, 1e-15);  // orientation does not matter to ε_e
}

// --------------------------------------------------------------------- against a mesh

TEST(Hausdorff, MeshAgainstItselfIsZero) {
  const Mesh m = icosphere(4, 1.5, {0.1, 0.2, 0.3});
  const HausdorffReport h = hausdorff(m, m);
  EXPECT_LT(h.symmetric, 1e-12);
  EXPECT_LT(h.a_to_b.mean, 1e-13);
  EXPECT_EQ(h.a_to_b.samples, default_sample_count(m));
}

TEST(Hausdorff, ConcentricSpheres) {
  const Mesh inner = icosphere(5, 1.0), outer = icosphere(5, 1.2);
  HausdorffOptions o;
  o.samples = 100000;
  const HausdorffReport h = hausdorff(inner, outer, o);
  // Both surfaces are within the level-5 chord error (~ 5e-4 R) of their spheres.
  EXPECT_NEAR(h.a_to_b.max, 0.2, 2e-3);
  EXPECT_NEAR(h.b_to_a.max, 0.2, 2e-3);
  EXPECT_NEAR(h.a_to_b.mean, 0.2, 2e-3);
  EXPECT_NEAR(h.symmetric, std::max(h.a_to_b.max, h.b_to_a.max), 0);
  EXPECT_EQ(h.a_to_b.samples, 100000);
  EXPECT_NEAR(h.symmetric_rel, h.symmetric / inner.bounds().diagonal(), 1e-15);
  // Shifted copy: the one-sided distances see the offset.
  const HausdorffReport s = hausdorff(icosphere(3), icosphere(3, 1.0, {0.25, 0, 0}));
  EXPECT_NEAR(s.symmetric, 0.25, 0.01);
  // Against nothing: infinite.
  EXPECT_TRUE(std::isinf(hausdorff(inner, Mesh{}).a_to_b.max));
}

TEST(Hausdorff, BvhClosestMatchesBruteForce) {
  // Exact point-triangle distance against dense sampling of the triangle (an upper bound that
  // converges to it), then BVH queries against a linear scan.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int k = 0; k < 200; ++k) {
    const Vec3 p{u(rng), u(rng), u(rng)}, a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)},
        c{u(rng), u(rng), u(rng)};
    double sampled = 1e300;
    for (int i = 0; i <= 60; ++i)
      for (int j = 0; i + j <= 60; ++j)
        sampled = std::min(sampled, distance(p, a + (i / 60.0) * (b - a) + (j / 60.0) * (c - a)));
    const double exact = std::sqrt(detail::point_triangle_distance2(p, a, b, c));
    EXPECT_LE(exact, sampled + 1e-12);
    EXPECT_GE(exact, sampled - 0.05 * norm(b - a) - 0.05 * norm(c - a));
  }
  // Degenerate triangles: distance to the segment.
  EXPECT_NEAR(detail::point_triangle_distance2({0.5, 1, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0}), 1, 1e-15);
  EXPECT_NEAR(detail::point_triangle_distance2({0, 0, 2}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}), 4, 1e-15);

  Mesh m = merged(torus(40, 20), icosphere(3, 0.4, {0.2, 0.1, 0.3}));
  m.add_triangle(0, 0, 1);  // a collapsed one too
  const detail::TriangleBvh bvh(m);
  for (int k = 0; k < 300; ++k) {
    const Vec3 p{u(rng), u(rng), u(rng) * 0.5};
    double best = 1e300;
    for (std::size_t t = 0; t < m.num_triangles(); ++t)
      best = std::min(best, detail::point_triangle_distance2(p, m.vertex(m.triangles[3 * t]),
                                                              m.vertex(m.triangles[3 * t + 1]),
                                                              m.vertex(m.triangles[3 * t + 2])));
    EXPECT_EQ(bvh.closest(p).distance2, best) << k;
  }
}

// make_mesh_distance_field: signed distance to a sphere mesh, at points around it (inside and
// out, near and far, on vertices, edges and faces), against the exact distance to the sphere it
// approximates; the gradient is the unit radial direction; a Newton step lands on the mesh.
TEST(MeshDistanceField, SignedDistanceToASphereMesh) {
  const Vec3 c{0.3, -0.2, 0.1};
  const double r = 1.2;
  const Mesh m = icosphere(5, r, c);  // chord error about 5e-4 r
  const Box domain{{-2, -2, -2}, {2, 2, 2}};
  const std::unique_ptr<ScalarField> f = make_mesh_distance_field(m, domain);
  EXPECT_EQ(f->domain().lo, domain.lo);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1), radius(0.2 * r, 1.8 * r);
  for (int k = 0; k < 500; ++k) {
    const Vec3 d = normalized(Vec3{u(rng), u(rng), u(rng)});
    const double rr = k < 100 ? r : radius(rng);  // the first ones on the sphere itself
    const Vec3 p = c + rr * d;
    EXPECT_NEAR(f->value(p), rr - r, 1e-3 * r) << k;
    const Vec3 g = f->gradient(p);
    EXPECT_NEAR(norm(g), 1, 1e-9) << k;
    if (std::abs(rr - r) > 0.05) EXPECT_GT(dot(g, d), 0.99) << k;
    // Newton: p − f ∇f lands on the mesh.
    const Vec3 q = p - f->value(p) * g;
    EXPECT_NEAR(f->value(q), 0, 1e-9) << k;
  }
  // On the mesh's own vertices and edge midpoints: zero, gradient along the outward normal.
  for (std::size_t t = 0; t < 50; ++t) {
    const Vec3 a = m.vertex(m.triangles[3 * t]), b = m.vertex(m.triangles[3 * t + 1]);
    for (const Vec3& p : {a, 0.5 * (a + b)}) {
      EXPECT_NEAR(f->value(p), 0, 1e-12);
      EXPECT_GT(dot(f->gradient(p), normalized(p - c)), 0.99);
    }
  }
  // Inward-facing triangles flip the sign: inside is then positive.
  const std::unique_ptr<ScalarField> g = make_mesh_distance_field(flipped(m), domain);
  EXPECT_NEAR(g->value(c), r, 1e-3 * r);
  // No triangles: zero, no gradient.
  const std::unique_ptr<ScalarField> none = make_mesh_distance_field(Mesh{}, domain);
  EXPECT_EQ(none->value(c), 0);
  EXPECT_EQ(norm(none->gradient(c)), 0);
}

// --------------------------------------------------------------------- determinism

TEST(Determinism, SameNumbersWithOneAndTwoThreads) {
  const Mesh m = merged(icosphere(6, 1.0), torus(200, 100, 3, 0.5));  // 122k triangles
  const SphereField f(1.0);
  ExecutionContext one{1}, two{2};
  const TopologyReport t1 = topology(m, one), t2 = topology(m, two);
  EXPECT_EQ(t1.edges, t2.edges);
  EXPECT_EQ(t1.boundary_loops, t2.boundary_loops);
  EXPECT_EQ(t1.component_list.size(), t2.component_list.size());
  const QualityReport q1 = quality(m, one), q2 = quality(m, two);
  EXPECT_EQ(q1.q_mean, q2.q_mean);
  EXPECT_EQ(q1.q_hist, q2.q_hist);
  EXPECT_EQ(q1.min_angle.p5, q2.min_angle.p5);
  EXPECT_EQ(surface_area(m, one), surface_area(m, two));
  EXPECT_EQ(signed_volume(m, one), signed_volume(m, two));
  FieldErrorOptions fo;
  fo.inside_sign = -1;
  fo.samples = 50000;
  const FieldErrorReport f1 = field_error(m, f, 0.0, fo, one);
  const FieldErrorReport f2 = field_error(m, f, 0.0, fo, two);
  EXPECT_EQ(f1.distance.mean, f2.distance.mean);
  EXPECT_EQ(f1.distance.rms, f2.distance.rms);
  EXPECT_EQ(f1.distance.p99, f2.distance.p99);
  EXPECT_EQ(f1.eps_e, f2.eps_e);
  EXPECT_EQ(f1.eps_n, f2.eps_n);
  HausdorffOptions ho;
  ho.samples = 50000;
  const HausdorffReport h1 = hausdorff(m, icosphere(5, 1.1), ho, one);
  const HausdorffReport h2 = hausdorff(m, icosphere(5, 1.1), ho, two);
  EXPECT_EQ(h1.a_to_b.mean, h2.a_to_b.mean);
  EXPECT_EQ(h1.b_to_a.rms, h2.b_to_a.rms);
  EXPECT_EQ(h1.symmetric, h2.symmetric);
  EXPECT_EQ(report_json(mesh_report(m, one)), report_json(mesh_report(m, two)));
}

// --------------------------------------------------------------------- reports and timing

TEST(Report, JsonHasEveryKey) {
  MeshReport r = mesh_report(cube());
  const std::string j = report_json(r);
  for (const char* key : {"vertices", "edges", "triangles", "euler", "components", "boundary_loops",
                          "genus", "genus_per_component", "nonmanifold_edges", "nonmanifold_vertices",
                          "degenerate_triangles", "duplicate_triangles", "oriented", "min_angle_deg",
                          "pct_min_angle_below", "max_angle_deg", "q_hist", "q_mean", "distance",
                          "eps_e", "eps_n", "hausdorff", "area", "volume"})
    EXPECT_NE(j.find(std::string("\"") + key + "\""), std::string::npos) << key;
  EXPECT_NE(j.find("\"distance\": null"), std::string::npos);
  EXPECT_NE(report_text(r).find("euler 2"), std::string::npos);
}

// Run with --gtest_also_run_disabled_tests: timings on a 4-million-triangle UV sphere
// (wall time and process CPU time, so results on a busy machine can still be compared).
TEST(MetricsPerf, DISABLED_BigSphere) {
  struct Clock {
    std::chrono::steady_clock::time_point wall = std::chrono::steady_clock::now();
    std::clock_t cpu = std::clock();
    std::string lap() {
      char buf[96];
      std::snprintf(buf, sizeof buf, "%6.3f s wall %6.3f s cpu", seconds_since(wall),
                    double(std::clock() - cpu) / CLOCKS_PER_SEC);
      wall = std::chrono::steady_clock::now();
      cpu = std::clock();
      return buf;
    }
  } clock;
  const Mesh m = uv_sphere(2000, 1001, 1.0);
  std::printf("UV sphere: %zu triangles, %zu vertices (built: %s)\n", m.num_triangles(),
              m.num_vertices(), clock.lap().c_str());
  const TopologyReport t = topology(m);
  std::printf("topology     %s (euler %lld, genus %lld)\n", clock.lap().c_str(),
              static_cast<long long>(t.euler), static_cast<long long>(t.genus));
  const QualityReport q = quality(m);
  std::printf("quality      %s (q mean %.4f)\n", clock.lap().c_str(), q.q_mean);
  const double a = surface_area(m), v = signed_volume(m);
  std::printf("area+volume  %s (%.6f, %.6f)\n", clock.lap().c_str(), a, v);
  const SphereField f(1.0);
  FieldErrorOptions fo;
  fo.inside_sign = -1;
  const FieldErrorReport fe = field_error(m, f, 0.0, fo);
  std::printf("field error  %s (%lld samples, rms %.3g, eps_e %.3g, eps_n %.3g)\n", clock.lap().c_str(),
              static_cast<long long>(fe.distance.samples), fe.distance.rms, fe.eps_e, fe.eps_n);
  const Mesh ref = icosphere(8, 1.0);  // 1.3M triangles
  clock.lap();
  const HausdorffReport h = hausdorff(m, ref);
  std::printf("hausdorff    %s vs %zu triangles (symmetric %.3g)\n", clock.lap().c_str(),
              ref.num_triangles(), h.symmetric);
  const HausdorffReport self = hausdorff(m, m);
  std::printf("hausdorff    %s mesh against itself (symmetric %.3g)\n", clock.lap().c_str(), self.symmetric);
  EXPECT_EQ(t.euler, 2);
}

// ----------------------------------------------------------------- self-intersections

TEST(SelfIntersections, CleanMeshesHaveNone) {
  EXPECT_EQ(self_intersections(cube()).pairs, 0);
  EXPECT_EQ(self_intersections(icosphere(3)).pairs, 0);
  EXPECT_EQ(self_intersections(torus(24, 12)).pairs, 0);
  // Two spheres apart, and a flat grid (coplanar neighbours everywhere).
  EXPECT_EQ(self_intersections(merged(icosphere(2), icosphere(2, 1, {3, 0, 0}))).pairs, 0);
  EXPECT_EQ(self_intersections(uv_sphere(16, 8)).pairs, 0);
}

TEST(SelfIntersections, CrossingTrianglesWithoutSharedVertices) {
  // A vertical triangle piercing a horizontal one.
  const Mesh m = from({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {1.5, 1.5, 1}},
                      {{0, 1, 2}, {3, 4, 5}});
  const IntersectionReport r = self_intersections(m, 10);
  EXPECT_EQ(r.pairs, 1);
  ASSERT_EQ(r.first_pairs.size(), 1u);
  EXPECT_EQ(r.first_pairs[0], (std::pair<std::uint32_t, std::uint32_t>{0, 1}));
  // Moved away: none.
  const Mesh far = from({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {5, 5, -1}, {5, 5, 1}, {6, 6, 1}},
                        {{0, 1, 2}, {3, 4, 5}});
  EXPECT_EQ(self_intersections(far).pairs, 0);
  // Two spheres overlapping: their surfaces cross along a circle.
  EXPECT_GT(self_intersections(merged(icosphere(2), icosphere(2, 1, {1, 0, 0}))).pairs, 10);
}

TEST(SelfIntersections, PairsInvolvingFlaggedTrianglesAreTheFullListsSubset) {
  // The incremental recount of the untangling: exactly the pairs of the full count that have a
  // flagged triangle, for sparse and dense flags, with a duplicate triangle in the mesh.
  Mesh m = merged(icosphere(2), icosphere(2, 1, {1, 0, 0}));
  m.triangles.insert(m.triangles.end(), m.triangles.begin(), m.triangles.begin() + 3);
  const std::size_t nt = m.num_triangles();
  const IntersectionReport all = self_intersections(m, nt * nt);
  ASSERT_GT(all.pairs, 10);
  for (const std::size_t every : {1, 3, 7, 50}) {
    std::vector<std::uint8_t> flag(nt, 0);
    for (std::size_t t = 0; t < nt; t += every) flag[t] = 1;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> want;
    for (const auto& p : all.first_pairs)
      if (flag[p.first] || flag[p.second]) want.push_back(p);
    const auto got = intersecting_pairs_involving(m, flag);
    ASSERT_TRUE(got.has_value());
    EXPECT_EQ(*got, want) << every;
  }
  EXPECT_TRUE(intersecting_pairs_involving(m, std::vector<std::uint8_t>(nt, 0))->empty());
  EXPECT_THROW(intersecting_pairs_involving(m, std::vector<std::uint8_t>(3, 1)), std::invalid_argument);
}

TEST(SelfIntersections, SharedVertexCountsOnlyContactsElsewhere) {
  // Fan of two triangles around vertex 0 that do not cross: none.
  const Mesh ok = from({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0.2}, {0, -1, 0.2}},
                       {{0, 1, 2}, {0, 3, 4}});
  EXPECT_EQ(self_intersections(ok).pairs, 0);
  // The second triangle's far edge passes through the first: one.
  const Mesh bad = from({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.6, 0.3, -1}, {0.3, 0.6, 1}},
                        {{0, 1, 2}, {0, 3, 4}});
  EXPECT_EQ(self_intersections(bad).pairs, 1);
}

TEST(SelfIntersections, SharedEdgeCountsOnlyFolds) {
  // A hinge at 90 degrees: fine; folded flat onto itself: one.
  const Mesh hinge = from({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0, 1}}, {{0, 1, 2}, {1, 0, 3}});
  EXPECT_EQ(self_intersections(hinge).pairs, 0);
  const Mesh fold = from({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.4, 0.6, 0}}, {{0, 1, 2}, {1, 0, 3}});
  EXPECT_EQ(self_intersections(fold).pairs, 1);
  const Mesh flat = from({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}}, {{0, 1, 2}, {1, 0, 3}});
  EXPECT_EQ(self_intersections(flat).pairs, 0);
}

TEST(SelfIntersections, InStatsJson) {
  const Mesh m = from({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {1.5, 1.5, 1}},
                      {{0, 1, 2}, {3, 4, 5}});
  EXPECT_EQ(mesh_report(m).self_intersecting_pairs, 1);
  EXPECT_NE(report_json(mesh_report(m)).find("\"self_intersecting_pairs\": 1"), std::string::npos);
}
