#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <nlohmann/json.hpp>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/graph.h"
#include "adamesh/input.h"
#include "adamesh/metrics.h"
#include "adamesh/simplify.h"
#include "adamesh/surfels.h"
#include "mesh_checks.h"
#include "testing.h"

using namespace adamesh;
using testutil::mesh_topo;

namespace {

/// Sorted (χ, boundary loops) of every component: compares per-component topology.
std::vector<std::pair<std::int64_t, std::int64_t>> component_signature(const Mesh& m) {
  std::vector<std::pair<std::int64_t, std::int64_t>> sig;
  for (const auto& c : topology(m).component_list) sig.push_back({c.euler, c.boundary_loops});
  std::sort(sig.begin(), sig.end());
  return sig;
}

/// Median radius ratio q = 2 r_in / r_circ of the triangles.
double median_q(const Mesh& m) {
  std::vector<double> q;
  for (std::size_t f = 0; f < m.num_triangles(); ++f) {
    const Vec3 a = m.vertex(m.triangles[3 * f]), b = m.vertex(m.triangles[3 * f + 1]),
               c = m.vertex(m.triangles[3 * f + 2]);
    const double la = distance(b, c), lb = distance(a, c), lc = distance(a, b);
    const double s = 0.5 * (la + lb + lc);
    const double area = 0.5 * norm(cross(b - a, c - a));
    const double rin = area / s, rcirc = la * lb * lc / (4 * area);
    q.push_back(area > 0 ? 2 * rin / rcirc : 0);
  }
  std::sort(q.begin(), q.end());
  return q.empty() ? 0 : q[q.size() / 2];
}

/// Checks the base mesh of a complex against its marching-cubes topology; returns the mesh.
/// Small inputs also run the covering validator and the independent topology oracle; large ones
/// (over 150k surfels) use the metrics module's topology only, to keep `make test` quick.
BaseMesh check_complex(const SurfelComplex& sc, const ScalarField* field, SimplifyOptions opt,
                       const std::string& label) {
  const bool small = sc.num_surfels() <= 150000;
  const Mesh mc = marching_cubes(sc);
  opt.validate = small;
  const auto t0 = std::chrono::steady_clock::now();
  BaseMesh bm = simplify(sc, field, opt);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  SCOPED_TRACE(label);
  const TopologyReport ref = topology(mc), got = topology(bm.mesh);
  EXPECT_EQ(got.euler, ref.euler);
  EXPECT_EQ(got.components, ref.components);
  EXPECT_EQ(got.boundary_loops, ref.boundary_loops);
  EXPECT_EQ(got.nonmanifold_edges, 0);
  EXPECT_EQ(got.nonmanifold_vertices, 0);
  EXPECT_EQ(got.degenerate_triangles, 0);
  EXPECT_EQ(got.duplicate_triangles, 0);
  EXPECT_TRUE(got.oriented);
  EXPECT_EQ(got.unreferenced_vertices, 0);
  EXPECT_EQ(component_signature(bm.mesh), component_signature(mc)) << "per-component χ/loops";
  if (small) {  // an independent oracle agrees
    const auto t = mesh_topo(bm.mesh);
    EXPECT_EQ(t.chi, ref.euler);
    EXPECT_EQ(t.boundary_loops, ref.boundary_loops);
    EXPECT_EQ(t.nonmanifold_vertices, 0);
    const auto& v = bm.stats.validation;
    EXPECT_TRUE(v.ok()) << "uncovered " << v.uncovered << " independence " << v.independence
                        << " grading " << v.grading << " non-disks " << v.non_disks
                        << " violated " << v.violated_cells;
  }
  std::printf("%-28s surfels %7zu -> V %6zu F %6zu chi %5ld comps %5ld loops %4ld | disks %zu "
              "events %zu split %zu fallback %zu | median q %.3f | %.2fs\n",
              label.c_str(), sc.num_surfels(), bm.mesh.num_vertices(), bm.mesh.num_triangles(),
              static_cast<long>(got.euler), static_cast<long>(got.components),
              static_cast<long>(got.boundary_loops), bm.stats.disks, bm.stats.events,
              bm.stats.split_cells, bm.stats.fallback_components, median_q(bm.mesh), secs);
  for (std::size_t i = 0; i < bm.stats.warnings.size() && i < 5; ++i)
    std::printf("    warning: %s\n", bm.stats.warnings[i].c_str());
  return bm;
}

BaseMesh check_shape(const std::string& shape, int res, SimplifyOptions opt = {}) {
  InputOptions io;
  io.resolution = res;
  const Input in = load_input("shape:" + shape, io);
  const SurfelComplex sc = build_surfels(*in.volume, 0.0, in.inside_sign);
  BaseMesh bm = check_complex(sc, in.field.get(), opt, shape + " @" + std::to_string(res));
  EXPECT_GE(median_q(bm.mesh), 0.6) << shape;
  EXPECT_EQ(self_intersections(bm.mesh).pairs, 0) << shape;
  EXPECT_EQ(bm.stats.fallback_components, 0u) << shape;
  return bm;
}

}  // namespace

TEST(Simplify, Sphere) { check_shape("sphere", 64); }
TEST(Simplify, SphereCoarse) {
  SimplifyOptions o;
  o.r_max = 0.3;
  check_shape("sphere", 64, o);
}
TEST(Simplify, Torus) { check_shape("torus", 64); }
TEST(Simplify, TwoTori) { check_shape("two_tori", 64); }
TEST(Simplify, LinkedTori) { check_shape("linked_tori", 64); }
TEST(Simplify, Genus2) { check_shape("genus2", 64); }
TEST(Simplify, CubeMinusSphere) { check_shape("cube_minus_sphere", 64); }
TEST(Simplify, WavySheet) { check_shape("wavy_sheet", 64); }
TEST(Simplify, Gyroid) { check_shape("gyroid", 64); }

TEST(Simplify, LargerRadiusGivesFewerVertices) {
  InputOptions io;
  io.resolution = 64;
  const Input in = load_input("shape:torus", io);
  const SurfelComplex sc = build_surfels(*in.volume, 0.0, in.inside_sign);
  std::size_t previous = SIZE_MAX;
  for (double r : {0.07, 0.1, 0.14, 0.2, 0.28}) {
    SimplifyOptions o;
    o.r_max = r;
    const BaseMesh bm = simplify(sc, in.field.get(), o);
    EXPECT_LT(bm.mesh.num_vertices(), previous) << "r_max " << r;
    previous = bm.mesh.num_vertices();
    EXPECT_EQ(mesh_topo(bm.mesh).chi, 0);
  }
}

TEST(Simplify, RadiiInVoxels) {
  InputOptions io;
  io.resolution = 48;
  const Input in = load_input("shape:sphere", io);
  const SurfelComplex sc = build_surfels(*in.volume, 0.0, in.inside_sign);
  SimplifyOptions a, b;
  a.r_max = 4 * sc.grid.min_spacing();
  b.r_max = 4;
  b.unit = LengthUnit::voxels;
  EXPECT_EQ(simplify(sc, nullptr, a).mesh.positions, simplify(sc, nullptr, b).mesh.positions);
}

TEST(Simplify, DeterministicAcrossRunsAndThreads) {
  InputOptions io;
  io.resolution = 64;
  const Input in = load_input("shape:genus2", io);
  ExecutionContext one, two;
  one.threads = 1;
  two.threads = 2;
  const SurfelComplex a = build_surfels(*in.volume, 0.0, in.inside_sign, one);
  const SurfelComplex b = build_surfels(*in.volume, 0.0, in.inside_sign, two);
  const BaseMesh ma = simplify(a, in.field.get(), {}, one), mb = simplify(b, in.field.get(), {}, two),
                 mc = simplify(b, in.field.get(), {}, two);
  EXPECT_EQ(ma.mesh.positions, mb.mesh.positions);
  EXPECT_EQ(ma.mesh.triangles, mb.mesh.triangles);
  EXPECT_EQ(mb.mesh.positions, mc.mesh.positions);
  EXPECT_EQ(mb.mesh.triangles, mc.mesh.triangles);
  EXPECT_EQ(ma.anchor, mb.anchor);
}

TEST(Simplify, BorderVerticesLieOnVolumeFaces) {
  InputOptions io;
  io.resolution = 48;
  const Input in = load_input("shape:wavy_sheet", io);
  const SurfelComplex sc = build_surfels(*in.volume, 0.0, in.inside_sign);
  const BaseMesh bm = simplify(sc, in.field.get(), {});
  const Box box = sc.grid.world_bounds();
  const double h = sc.grid.min_spacing();
  std::size_t border = 0;
  for (std::size_t v = 0; v < bm.mesh.num_vertices(); ++v) {
    if (!bm.border[v]) continue;
    ++border;
    const Vec3 p = bm.mesh.vertex(v);
    double gap = 1e30;
    for (int a = 0; a < 3; ++a)
      gap = std::min({gap, std::abs(p[a] - box.lo[a]), std::abs(p[a] - box.hi[a])});
    EXPECT_LT(gap, 1e-6 * h + 1e-6) << "vertex " << v;
  }
  EXPECT_GT(border, 8u);
}

// Every dataset of ../shared/data at each suggested iso-value (skipped when absent).
TEST(Simplify, SharedDatasets) {
  ADAMESH_REQUIRE_SHARED_DATA(dir);
  std::ifstream f(dir + "/manifest.json");
  const auto manifest = nlohmann::json::parse(f);
  for (const auto& ds : manifest["datasets"]) {
    const std::string path = dir + "/" + ds["primary_file"].get<std::string>();
    const std::string id = ds["id"];
    Input in;
    try {
      in = load_input(path);
    } catch (const Error& e) {
      if (e.status() == Status::unsupported) {
        std::printf("%s: skipped (%s)\n", id.c_str(), e.what());
        continue;
      }
      throw;
    }
    for (const auto& iso : ds["iso_values"]) {
      const double v = iso["value"];
      const SurfelComplex sc = build_surfels(*in.volume, v, in.inside_sign);
      SimplifyOptions o;
      check_complex(sc, in.field.get(), o, id + " @" + std::to_string(v));
    }
  }
}
