// Refinement: blocks, 4-8 bisection, adaptation, drivers (ALGORITHM.md 2.7–2.10 and section 4).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <set>

#include "adamesh/error.h"
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

/// Uniform levels 0..J: validity, nesting, doubling, semi-regularity; prints figures per level.
void check_uniform(const Fixture& f, int levels, const std::string& label) {
  RefineOptions o;
  o.mode = RefineMode::uniform;
  o.levels = levels;
  const auto t0 = std::chrono::steady_clock::now();
  const RefineResult r = refine(f.sc, f.base, *f.in.field, o);
  const double secs = seconds_since(t0);
  const Hierarchy& h = r.hierarchy;
  EXPECT_FALSE(r.stats.quad_fallback) << label;
  EXPECT_EQ(r.stats.forced_splits, 0u) << label;
  std::printf("%s: base F %zu, blocks %zu (half %zu, greedy %zu, augmentations %zu), %zu splits, "
              "%.2fs (placements geodesic %zu euclidean %zu border %zu, unconverged %zu)\n",
              label.c_str(), r.stats.base_triangles, r.stats.blocks, r.stats.border_half_blocks,
              r.stats.greedy_pairs, r.stats.augmentations, r.stats.splits, secs,
              r.stats.geodesic_placements, r.stats.euclidean_placements,
              r.stats.border_placements, r.stats.unconverged_projections);
  CutMesh prev;
  for (int j = 0; j <= levels; ++j) {
    const CutMesh cut = extract_level(h, j);
    const std::string l = label + " level " + std::to_string(j);
    expect_valid_cut(cut, h, f.base_topo, l);
    expect_semi_regular(cut, h.base_positions.size(), true, l);
    const ShapeFigures q = shape_figures(cut.mesh);
    std::printf("  level %d: F %7zu V %7zu  median q %.3f  min angle %.1f  <20deg %.2f%%\n", j,
                cut.mesh.num_triangles(), cut.mesh.num_vertices(), q.median_q, q.min_angle,
                q.pct_below_20);
    if (j > 0) {
      EXPECT_EQ(cut.mesh.num_triangles(), 2 * prev.mesh.num_triangles()) << l;
      // Nesting: every vertex of M_{j-1} is in M_j with identical coordinates.
      std::size_t k = 0;
      for (std::size_t i = 0; i < prev.vertex_id.size(); ++i) {
        while (k < cut.vertex_id.size() && cut.vertex_id[k] < prev.vertex_id[i]) ++k;
        ASSERT_LT(k, cut.vertex_id.size()) << l;
        ASSERT_EQ(cut.vertex_id[k], prev.vertex_id[i]) << l;
        for (int c = 0; c < 3; ++c)
          ASSERT_EQ(cut.mesh.positions[3 * k + c], prev.mesh.positions[3 * i + c]) << l;
      }
    } else {
      EXPECT_EQ(cut.mesh.num_triangles(), f.base.mesh.num_triangles()) << l;
    }
    prev = cut;
  }
}

}  // namespace

TEST(Refine, UniformSphere) { check_uniform(make_fixture("shape:sphere", 48), 4, "sphere@48"); }
TEST(Refine, UniformTorus) { check_uniform(make_fixture("shape:torus", 48), 4, "torus@48"); }
TEST(Refine, UniformGenus2) { check_uniform(make_fixture("shape:genus2", 48), 3, "genus2@48"); }
TEST(Refine, UniformTwoTori) { check_uniform(make_fixture("shape:two_tori", 48), 3, "two_tori@48"); }
TEST(Refine, UniformWavySheet) {
  check_uniform(make_fixture("shape:wavy_sheet", 48), 4, "wavy_sheet@48");
}
TEST(Refine, UniformCubeMinusSphere) {
  check_uniform(make_fixture("shape:cube_minus_sphere", 48), 3, "cube_minus_sphere@48");
}
TEST(Refine, UniformGyroid) { check_uniform(make_fixture("shape:gyroid", 48), 3, "gyroid@48"); }
TEST(Refine, UniformLinkedTori) {
  check_uniform(make_fixture("shape:linked_tori", 48), 3, "linked_tori@48");
}
