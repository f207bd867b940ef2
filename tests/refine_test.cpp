// Refinement: blocks, 4-8 bisection, adaptation and uniform levels (ALGORITHM.md 2.7–2.9 and
// section 4). Adaptive drivers: refine_adaptive_test.cpp; hierarchy files: hierarchy_test.cpp.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "adamesh/error.h"
#include "adamesh/metrics.h"
#include "adamesh/refine.h"
#include "refine/forest.h"
#include "refine_checks.h"
#include "testing.h"

using namespace adamesh;
using namespace adamesh::testutil;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double mean_edge(const Mesh& m) {
  double s = 0;
  for (std::size_t f = 0; f < m.num_triangles(); ++f)
    for (int e = 0; e < 3; ++e)
      s += distance(m.vertex(m.triangles[3 * f + e]), m.vertex(m.triangles[3 * f + (e + 1) % 3]));
  return s / std::max<std::size_t>(1, 3 * m.num_triangles());
}

/// Uniform levels 0..J: validity, nesting, doubling, semi-regularity; prints figures per level.
Hierarchy check_uniform(const Fixture& f, int levels, const std::string& label,
                        RefineOptions o = {}) {
  o.mode = RefineMode::uniform;
  o.levels = levels;
  const auto t0 = std::chrono::steady_clock::now();
  const RefineResult r = refine(f.sc, f.base, *f.in.field, o);
  const double secs = seconds_since(t0);
  const Hierarchy& h = r.hierarchy;
  EXPECT_EQ(r.stats.forced_splits, 0u) << label;
  std::printf("%s: base F %zu, blocks %zu (half %zu, greedy %zu, augmentations %zu)%s, %zu splits, "
              "%.2fs (placements line %zu geodesic %zu euclidean %zu border %zu, unconverged %zu)\n",
              label.c_str(), r.stats.base_triangles, r.stats.blocks, r.stats.border_half_blocks,
              r.stats.greedy_pairs, r.stats.augmentations, r.stats.quad_fallback ? " quads" : "",
              r.stats.splits, secs, r.stats.line_placements, r.stats.geodesic_placements,
              r.stats.euclidean_placements, r.stats.border_placements,
              r.stats.unconverged_projections);
  CutMesh prev;
  for (int j = 0; j <= levels; ++j) {
    const CutMesh cut = extract_level(h, j);
    const std::string l = label + " level " + std::to_string(j);
    expect_valid_cut(cut, h, f.base_topo, l);
    expect_semi_regular(cut, h.base_positions.size(), true, l);
    const ShapeFigures q = shape_figures(cut.mesh);
    std::printf("  level %d: F %7zu V %7zu  median q %.3f  min angle %5.1f  <20deg %5.2f%%\n", j,
                cut.mesh.num_triangles(), cut.mesh.num_vertices(), q.median_q, q.min_angle,
                q.pct_below_20);
    EXPECT_GE(q.median_q, 0.6) << l;
    if (j > 0) {
      EXPECT_EQ(cut.mesh.num_triangles(), 2 * prev.mesh.num_triangles()) << l;
      expect_nested(prev, cut, l);
    }
    prev = cut;
  }
  return h;
}

/// ε_e and ε_n over uniform levels, on `field`: ε_e non-increasing (1% tolerance) while edges are
/// longer than h, ε_n from level 1 on. M0 → M1 may raise ε_n: the near-equilateral base triangles
/// become right triangles, whose planes are parallel to the tangent plane at their circumcentre
/// (the hypotenuse midpoint), not at the centroid where ε_n compares with ∇f.
void check_convergence(const Fixture& f, const ScalarField& field, double iso, int levels,
                       const std::string& label) {
  RefineOptions o;
  o.mode = RefineMode::uniform;
  o.levels = levels;
  const RefineResult r = refine(f.sc, f.base, field, o);
  FieldErrorOptions fo;
  fo.inside_sign = f.in.inside_sign;
  fo.samples = 100000;
  double prev_e = 0, prev_n = 0;
  for (int j = 0; j <= levels; ++j) {
    const CutMesh cut = extract_level(r.hierarchy, j);
    const FieldErrorReport e = field_error(cut.mesh, field, iso, fo);
    const double edge = mean_edge(cut.mesh) / f.h;
    std::printf("%s level %d: F %7zu edge %.2fh  eps_e %.3e  eps_n %.3e  rms %.3e  max %.3e\n",
                label.c_str(), j, cut.mesh.num_triangles(), edge, e.eps_e, e.eps_n,
                e.distance.rms, e.distance.max);
    if (j > 0 && edge > 1.0) {
      EXPECT_LE(e.eps_e, 1.01 * prev_e) << label << " level " << j;
      if (j > 1) {
        EXPECT_LE(e.eps_n, 1.01 * prev_n) << label << " level " << j;
      }
    }
    prev_e = e.eps_e;
    prev_n = e.eps_n;
  }
}

}  // namespace

TEST(Refine, UniformSphere) { check_uniform(make_fixture("shape:sphere", 48), 4, "sphere@48"); }
TEST(Refine, UniformTorus) { check_uniform(make_fixture("shape:torus", 48), 4, "torus@48"); }
TEST(Refine, UniformGenus2) { check_uniform(make_fixture("shape:genus2", 48), 3, "genus2@48"); }
TEST(Refine, UniformTwoTori) { check_uniform(make_fixture("shape:two_tori", 48), 3, "two_tori@48"); }
TEST(Refine, UniformLinkedTori) {
  check_uniform(make_fixture("shape:linked_tori", 48), 3, "linked_tori@48");
}
TEST(Refine, UniformCubeMinusSphere) {
  check_uniform(make_fixture("shape:cube_minus_sphere", 48), 3, "cube_minus_sphere@48");
}
TEST(Refine, UniformGyroid) { check_uniform(make_fixture("shape:gyroid", 48), 3, "gyroid@48"); }
TEST(Refine, UniformCoarseBase) {
  SimplifyOptions so;
  so.r_max = 0.3;  // long base edges: geodesic midpoints
  check_uniform(make_fixture("shape:torus", 64, 0, so), 5, "torus@64 r_max 0.3");
}

/// Large bases pair their blocks by local augmenting paths (refine.h local_matching_from); forced
/// here on small ones: a perfect matching (no quad fallback), found mostly inside the balls, and
/// uniform levels as valid as with the global search. wavy_sheet has border half-blocks, two_tori
/// two closed components.
TEST(Refine, LocalMatchingGivesValidBlocks) {
  for (const char* shape : {"shape:gyroid", "shape:wavy_sheet", "shape:two_tori"}) {
    const Fixture f = make_fixture(shape, 48);
    RefineOptions o;
    o.local_matching_from = 0;
    o.mode = RefineMode::uniform;
    o.levels = 0;
    const RefineResult r = refine(f.sc, f.base, *f.in.field, o);
    EXPECT_FALSE(r.stats.quad_fallback) << shape;
    EXPECT_GT(r.stats.local_augmentations, 0u) << shape;
    EXPECT_LE(r.stats.local_augmentations, r.stats.augmentations) << shape;
    EXPECT_EQ(2 * r.stats.blocks - r.stats.border_half_blocks, r.stats.base_triangles) << shape;
    if (std::string(shape) == "shape:wavy_sheet") {
      EXPECT_GT(r.stats.border_half_blocks, 0u);
    }
    check_uniform(f, 3, std::string(shape) + "@48 local matching", o);
  }
}

TEST(Refine, UniformWavySheetBorderOnVolumeFaces) {
  const Fixture f = make_fixture("shape:wavy_sheet", 48);
  const Hierarchy h = check_uniform(f, 4, "wavy_sheet@48");
  const CutMesh cut = extract_all(h);
  const Grid& grid = f.sc.grid;
  std::size_t border = 0, created = 0;
  for (std::size_t i = 0; i < cut.vertex_id.size(); ++i) {
    if (!cut.vertex_border[i]) continue;
    ++border;
    created += cut.vertex_id[i] >= h.base_positions.size();
    const Vec3 q = grid.to_index(h.vertex(cut.vertex_id[i]));
    double gap = 1e30;
    for (int a = 0; a < 3; ++a)
      gap = std::min({gap, std::abs(q[a]), std::abs(q[a] - static_cast<double>(grid.dims[a] - 1))});
    EXPECT_LT(gap, 1e-6) << "vertex " << cut.vertex_id[i] << " is " << gap << " h from a face";
  }
  EXPECT_GT(created, 100u);
  std::printf("border vertices %zu (created by refinement %zu)\n", border, created);
}

TEST(Refine, QuadFallbackBlocks) {
  const Fixture f = make_fixture("shape:torus", 48);
  RefineOptions o;
  o.force_quad_blocks = true;
  const Hierarchy h = check_uniform(f, 2, "torus@48 quad blocks", o);
  EXPECT_EQ(h.base_triangles.size(), 6 * f.base.mesh.num_triangles());
  const Fixture s = make_fixture("shape:wavy_sheet", 48);
  check_uniform(s, 2, "wavy_sheet@48 quad blocks", o);
}

TEST(Refine, ConvergenceAnalytic) {
  SimplifyOptions so;
  so.r_max = 0.3;
  for (const char* shape : {"sphere", "torus"}) {
    const Fixture f = make_fixture(std::string("shape:") + shape, 64, 0, so);
    check_convergence(f, *f.in.field, 0, 6, std::string(shape) + " analytic");
  }
}

TEST(Refine, ConvergenceSampled) {
  SimplifyOptions so;
  so.r_max = 0.3;
  const Fixture f = make_fixture("shape:torus", 64, 0, so);
  const auto trilinear = make_volume_field(f.in.volume);
  check_convergence(f, *trilinear, 0, 6, "torus trilinear");
  const Fixture head = make_fixture(source_dir() + "/data/ct_headsq/quarter.nhdr", 0, 500.5);
  check_convergence(head, *head.in.field, 500.5, 3, "ct_headsq");
}

TEST(Refine, CtHeadLevels) {
  const Fixture f = make_fixture(source_dir() + "/data/ct_headsq/quarter.nhdr", 0, 500.5);
  check_uniform(f, 3, "ct_headsq@500.5");
}

// Every dataset of ../shared/data up to 2M samples, at its first suggested iso-value (skipped when
// the directory is absent).
TEST(Refine, SharedDatasets) {
  ADAMESH_REQUIRE_SHARED_DATA(dir);
  std::ifstream in(dir + "/manifest.json");
  const auto manifest = nlohmann::json::parse(in);
  for (const auto& ds : manifest["datasets"]) {
    const std::string path = dir + "/" + ds["primary_file"].get<std::string>();
    Fixture f;
    try {
      f.in = load_input(path);
    } catch (const Error& e) {
      std::printf("%s: skipped (%s)\n", path.c_str(), e.what());
      continue;
    }
    if (f.in.volume->grid.num_samples() > 2'000'000) {  // the large ones: simplify_test covers them
      std::printf("%s: skipped here (%lld samples)\n", path.c_str(),
                  static_cast<long long>(f.in.volume->grid.num_samples()));
      continue;
    }
    const double iso = ds["iso_values"][0]["value"];
    f.sc = build_surfels(*f.in.volume, iso, f.in.inside_sign);
    f.base = simplify(f.sc, f.in.field.get());
    f.base_topo = mesh_topo(f.base.mesh);
    f.h = f.sc.grid.min_spacing();
    if (f.base.mesh.num_triangles() == 0) continue;
    check_uniform(f, 2, ds["id"].get<std::string>());
  }
}

TEST(Refine, ForestSplitsAndForcedSplits) {
  // A 2×2 grid of squares, each cut by the diagonal through the centre vertex 4; each triangle is
  // (v0, v1, v2), counter-clockwise, with the diagonal (v1, v2) as refinement edge.
  //   6 7 8
  //   3 4 5
  //   0 1 2
  using detail::Forest;
  const std::vector<std::array<std::uint32_t, 3>> lab = {
      {1, 4, 0}, {3, 0, 4}, {1, 2, 4}, {5, 4, 2}, {3, 4, 6}, {7, 6, 4}, {5, 8, 4}, {7, 4, 8}};
  Forest f(lab, 9);
  EXPECT_EQ(f.nonmanifold_edges(), 0u);
  for (std::uint32_t t = 0; t < 8; ++t) EXPECT_TRUE(f.compatible(t)) << t;
  // Split the block of triangle 0: 0 and 1 share (0, 4).
  ASSERT_TRUE(f.split(0, 0));
  EXPECT_FALSE(f.is_leaf(0));
  EXPECT_FALSE(f.is_leaf(1));
  EXPECT_EQ(f.num_leaves(), 10u);
  EXPECT_EQ(f.tri(f.child(0, 0)).v[0], 9u);  // the new vertex is V0 + 0
  EXPECT_FALSE(f.split(0, 1));               // not a leaf any more
  // A child of the split block has a refinement edge that is an outer edge of the block; its
  // neighbour (a coarser triangle) must be split first: not compatible yet.
  const std::uint32_t c = f.child(0, 0);
  EXPECT_FALSE(f.compatible(c));
  EXPECT_FALSE(f.split(c, 1));
  const std::uint32_t n = f.partner(c);
  ASSERT_TRUE(f.split(n, 1));  // the forced split
  EXPECT_TRUE(f.compatible(c));
  ASSERT_TRUE(f.split(c, 2));
  f.check();
  EXPECT_EQ(f.tri(f.child(c, 0)).level, 2);
}

TEST(Refine, RejectsBadInput) {
  const Fixture f = make_fixture("shape:sphere", 32);
  RefineOptions o;
  o.mode = RefineMode::max_error;
  o.max_error = 0;
  EXPECT_THROW(refine(f.sc, f.base, *f.in.field, o), Error);
  o.mode = RefineMode::budget;
  o.max_triangles = 0;
  EXPECT_THROW(refine(f.sc, f.base, *f.in.field, o), Error);
  BaseMesh empty;
  EXPECT_THROW(refine(f.sc, empty, *f.in.field, {}), Error);
}
