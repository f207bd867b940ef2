#include <gtest/gtest.h>

#include "adamesh/graph.h"
#include "adamesh/input.h"
#include "adamesh/simplify.h"
#include "adamesh/surfels.h"
#include "mesh_checks.h"
#include "testing.h"

using namespace adamesh;
using testutil::mesh_topo;

namespace {

struct Case {
  const char* shape;
  int res;
};

void check_shape(const std::string& shape, int res, SimplifyOptions opt = {}) {
  InputOptions io;
  io.resolution = res;
  const Input in = load_input("shape:" + shape, io);
  const SurfelComplex sc = build_surfels(*in.volume, 0.0, in.inside_sign);
  const Mesh mc = marching_cubes(sc);
  const auto ref = mesh_topo(mc);
  opt.validate = true;
  const BaseMesh bm = simplify(sc, in.field.get(), opt);
  const auto got = mesh_topo(bm.mesh);
  SCOPED_TRACE(shape);
  EXPECT_EQ(got.chi, ref.chi);
  EXPECT_EQ(got.components, ref.components);
  EXPECT_EQ(got.boundary_loops, ref.boundary_loops);
  EXPECT_EQ(got.nonmanifold_edges, 0);
  EXPECT_EQ(got.nonmanifold_vertices, 0);
  EXPECT_EQ(got.degenerate, 0);
  EXPECT_EQ(got.duplicates, 0);
  EXPECT_TRUE(got.oriented);
  const auto& v = bm.stats.validation;
  EXPECT_TRUE(v.ok()) << "uncovered " << v.uncovered << " independence " << v.independence
                      << " grading " << v.grading << " non-disks " << v.non_disks << " violated "
                      << v.violated_cells;
  std::printf("%-18s res %3d: surfels %zu -> base V %zu F %zu (chi %ld comps %ld loops %ld) "
              "disks %zu events %zu halvings %zu floor %zu rounds %zu repaired %zu fallback %zu\n",
              shape.c_str(), res, sc.num_surfels(), bm.mesh.num_vertices(),
              bm.mesh.num_triangles(), got.chi, got.components, got.boundary_loops,
              bm.stats.disks, bm.stats.events, bm.stats.halvings, bm.stats.floor_conflicts,
              bm.stats.repair_rounds, bm.stats.violated_cells_repaired,
              bm.stats.fallback_components);
  std::printf("  kinds:");
  for (auto k : bm.stats.violations_by_kind) std::printf(" %zu", k);
  std::printf("  r_max %.4f r_min %.4f\n", bm.stats.r_max, bm.stats.r_min);
  if (!bm.stats.warnings.empty()) std::printf("  warning: %s\n", bm.stats.warnings[0].c_str());
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
