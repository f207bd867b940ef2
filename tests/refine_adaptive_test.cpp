// Adaptive refinement drivers (ALGORITHM.md 2.10): threshold, maximum error, triangle budget;
// determinism across runs and thread counts.
#include <gtest/gtest.h>

#include <cstdio>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/metrics.h"
#include "adamesh/refine.h"
#include "refine_checks.h"
#include "testing.h"

using namespace adamesh;
using namespace adamesh::testutil;

namespace {

/// Independent evaluation of the criterion: 15 barycentric samples (i, j, k)/4.
struct Sampled {
  double sqrt_var = 0, max_abs = 0;
};
Sampled sample_triangle(const ScalarField& f, double iso, const Vec3& a, const Vec3& b,
                        const Vec3& c) {
  double s = 0, s2 = 0, mx = 0;
  int n = 0;
  for (int i = 0; i <= 4; ++i)
    for (int j = 0; i + j <= 4; ++j) {
      const Vec3 p = (i * a + j * b + (4 - i - j) * c) / 4.0;
      const double d = signed_distance(f, iso, p);
      s += d, s2 += d * d, mx = std::max(mx, std::abs(d)), ++n;
    }
  return {std::sqrt(std::max(0.0, s2 / n - (s / n) * (s / n))), mx};
}

Sampled leaf_error(const CutMesh& cut, const Hierarchy& h, const ScalarField& f, std::size_t t) {
  const auto* v = &cut.mesh.triangles[3 * t];
  return sample_triangle(f, h.iso, h.vertex(cut.vertex_id[v[0]]), h.vertex(cut.vertex_id[v[1]]),
                         h.vertex(cut.vertex_id[v[2]]));
}

RefineResult run(const Fixture& f, const ScalarField& field, RefineOptions o,
                 const std::string& label) {
  const RefineResult r = refine(f.sc, f.base, field, o);
  const CutMesh cut = extract_all(r.hierarchy);
  const ShapeFigures q = shape_figures(cut.mesh);
  std::printf("%s: F %zu -> %zu, splits %zu (forced %zu), depth %d, at limit %zu, %.2fs | "
              "median q %.3f, <20deg %.2f%%\n",
              label.c_str(), f.base.mesh.num_triangles(), cut.mesh.num_triangles(),
              r.stats.splits, r.stats.forced_splits, r.stats.max_level, r.stats.at_limit_leaves,
              r.stats.time_refine_s, q.median_q, q.pct_below_20);
  expect_valid_cut(cut, r.hierarchy, f.base_topo, label);
  expect_semi_regular(cut, r.hierarchy.base_positions.size(), false, label);
  return r;
}

SimplifyOptions coarse(double r_max) {
  SimplifyOptions so;
  so.r_max = r_max;
  return so;
}

}  // namespace

TEST(RefineAdaptive, EveryLeafMeetsTheThreshold) {
  // Smooth shapes only: along a crease (genus2, gyroid ∩ ball, cube_minus_sphere) the variance
  // does not converge and leaves stop at the limits.
  for (const char* shape : {"sphere", "torus", "linked_tori"}) {
    const Fixture f = make_fixture(std::string("shape:") + shape, 64, 0, coarse(0.3));
    RefineOptions o;
    o.mode = RefineMode::threshold;
    o.delta = 0.05 * f.h;
    const RefineResult r = run(f, *f.in.field, o, std::string(shape) + " threshold 0.05h");
    const CutMesh cut = extract_all(r.hierarchy);
    EXPECT_GT(cut.mesh.num_triangles(), 2 * f.base.mesh.num_triangles());
    long failing = 0;
    for (std::size_t t = 0; t < cut.mesh.num_triangles(); ++t) {
      const Sampled e = leaf_error(cut, r.hierarchy, *f.in.field, t);
      failing += e.sqrt_var > o.delta * (1 + 1e-6) || e.max_abs > 4 * o.delta * (1 + 1e-6);
    }
    // Smooth shapes: nothing stops at a limit, so every leaf meets the threshold.
    EXPECT_EQ(r.stats.at_limit_leaves, 0u) << shape;
    EXPECT_EQ(failing, 0) << shape;
  }
}

TEST(RefineAdaptive, LargerThresholdGivesFewerTriangles) {
  const Fixture f = make_fixture("shape:genus2", 64, 0, coarse(0.3));
  std::size_t previous = SIZE_MAX;
  for (double d : {0.025, 0.05, 0.1, 0.2, 0.4}) {
    RefineOptions o;
    o.mode = RefineMode::threshold;
    o.delta = d * f.h;
    const RefineResult r = run(f, *f.in.field, o, "genus2 threshold " + std::to_string(d) + "h");
    const std::size_t n = extract_all(r.hierarchy).mesh.num_triangles();
    EXPECT_LT(n, previous) << d;
    previous = n;
  }
}

// A flat disk on a hemisphere: the flat part stays at the base resolution, the curved part is
// refined.
TEST(RefineAdaptive, DenserWhereCurved) {
  const Fixture f = make_fixture("expr:max(z, x*x + y*y + z*z - 0.64)", 64, 0, coarse(0.2));
  RefineOptions o;
  o.mode = RefineMode::threshold;
  o.delta = 0.1 * f.h;
  const RefineResult r = run(f, *f.in.field, o, "hemisphere threshold 0.1h");
  const CutMesh cut = extract_all(r.hierarchy);
  double flat_area = 0, curved_area = 0;
  long flat = 0, curved = 0;
  for (std::size_t t = 0; t < cut.mesh.num_triangles(); ++t) {
    const Vec3 a = cut.mesh.vertex(cut.mesh.triangles[3 * t]),
               b = cut.mesh.vertex(cut.mesh.triangles[3 * t + 1]),
               c = cut.mesh.vertex(cut.mesh.triangles[3 * t + 2]);
    const Vec3 g = (a + b + c) / 3.0;
    const double area = 0.5 * norm(cross(b - a, c - a));
    if (g.z > -0.01 && g.x * g.x + g.y * g.y < 0.25) flat_area += area, ++flat;
    if (g.z < -0.3) curved_area += area, ++curved;
  }
  ASSERT_GT(flat, 10);
  ASSERT_GT(curved, 10);
  const double flat_density = flat / flat_area, curved_density = curved / curved_area;
  std::printf("triangles per unit area: flat %.1f, curved %.1f\n", flat_density, curved_density);
  EXPECT_GT(curved_density, 1.5 * flat_density);
}

TEST(RefineAdaptive, MaxErrorIsMetByTheMetrics) {
  struct Case {
    const char* shape;
    bool sampled;
  };
  for (const Case c : {Case{"sphere", false}, Case{"torus", false}, Case{"linked_tori", false},
                       Case{"torus", true}}) {
    const Fixture f = make_fixture(std::string("shape:") + c.shape, 64, 0, coarse(0.3));
    const auto field = c.sampled ? make_volume_field(f.in.volume) : f.in.field;
    for (double e : {0.5, 0.2}) {
      RefineOptions o;
      o.mode = RefineMode::max_error;
      o.max_error = e * f.h;
      const std::string label = std::string(c.shape) + (c.sampled ? " trilinear" : "") +
                                " max error " + std::to_string(e) + "h";
      const RefineResult r = run(f, *field, o, label);
      const CutMesh cut = extract_all(r.hierarchy);
      FieldErrorOptions fo;
      fo.inside_sign = f.in.inside_sign;
      const FieldErrorReport m = field_error(cut.mesh, *field, 0, fo);
      std::printf("  measured: max %.3fh rms %.3fh (unconverged %ld)\n", m.distance.max / f.h,
                  m.distance.rms / f.h, static_cast<long>(m.unconverged));
      EXPECT_LE(m.distance.max, o.max_error) << label;
      EXPECT_EQ(r.stats.at_limit_leaves, 0u) << label;
      // The stored errors cut the same hierarchy at a coarser E, still within it.
      const CutMesh coarser = extract_max_error(r.hierarchy, 2 * o.max_error);
      EXPECT_LT(coarser.mesh.num_triangles(), cut.mesh.num_triangles());
      EXPECT_LE(field_error(coarser.mesh, *field, 0, fo).distance.max, 2 * o.max_error) << label;
    }
  }
}

TEST(RefineAdaptive, BudgetSplitsTheWorstFirst) {
  for (const char* shape : {"torus", "genus2"}) {
    const Fixture f = make_fixture(std::string("shape:") + shape, 64, 0, coarse(0.3));
    FieldErrorOptions fo;
    fo.inside_sign = f.in.inside_sign;
    RefineOptions u;
    u.mode = RefineMode::uniform;
    u.levels = 8;
    const RefineResult ru = refine(f.sc, f.base, *f.in.field, u);
    for (std::size_t n : {2000u, 8000u}) {
      RefineOptions o;
      o.mode = RefineMode::budget;
      o.max_triangles = n;
      const std::string label = std::string(shape) + " budget " + std::to_string(n);
      const RefineResult r = run(f, *f.in.field, o, label);
      const CutMesh cut = extract_all(r.hierarchy);
      EXPECT_LE(cut.mesh.num_triangles(), n) << label;
      EXPECT_GE(cut.mesh.num_triangles(), n - 16) << label;  // stops when the next split won't fit
      // The same size cut from the uniform hierarchy's progressive order: the budget mesh is as
      // accurate (5 % tolerance).
      const CutMesh same = extract_triangles(ru.hierarchy, n);
      const double rms_budget = field_error(cut.mesh, *f.in.field, 0, fo).distance.rms;
      const double rms_prefix = field_error(same.mesh, *f.in.field, 0, fo).distance.rms;
      std::printf("  rms at %zu triangles: budget %.3e, uniform hierarchy prefix (%zu) %.3e\n", n,
                  rms_budget, same.mesh.num_triangles(), rms_prefix);
      EXPECT_LE(rms_budget, 1.05 * rms_prefix) << label;
    }
  }
}

TEST(RefineAdaptive, CtHead) {
  const Fixture f = make_fixture(source_dir() + "/data/ct_headsq/quarter.nhdr", 0, 500.5);
  RefineOptions o;
  o.mode = RefineMode::threshold;
  run(f, *f.in.field, o, "ct_headsq threshold 0.1h");
  o.mode = RefineMode::budget;
  o.max_triangles = 30000;
  run(f, *f.in.field, o, "ct_headsq budget 30000");
}

TEST(RefineAdaptive, DeterministicAcrossRunsAndThreads) {
  const Fixture f = make_fixture("shape:genus2", 64, 0, coarse(0.3));
  for (const RefineMode mode : {RefineMode::uniform, RefineMode::threshold, RefineMode::budget}) {
    std::vector<Hierarchy> hs;
    for (int threads : {1, 2, 2}) {
      RefineOptions o;
      o.mode = mode;
      o.levels = mode == RefineMode::uniform ? 4 : 20;
      o.max_triangles = 6000;
      o.delta = 0.05 * f.h;
      ExecutionContext ctx;
      ctx.threads = threads;
      hs.push_back(refine(f.sc, f.base, *f.in.field, o, nullptr, ctx).hierarchy);
    }
    for (std::size_t i = 1; i < hs.size(); ++i) {
      EXPECT_EQ(hs[i].base_triangles, hs[0].base_triangles);
      ASSERT_EQ(hs[i].splits.size(), hs[0].splits.size());
      for (std::size_t s = 0; s < hs[0].splits.size(); ++s) {
        ASSERT_EQ(hs[i].splits[s].triangle, hs[0].splits[s].triangle) << s;
        ASSERT_EQ(hs[i].splits[s].position, hs[0].splits[s].position) << s;
        ASSERT_EQ(hs[i].splits[s].error, hs[0].splits[s].error) << s;
      }
      EXPECT_EQ(extract_all(hs[i]).mesh.positions, extract_all(hs[0]).mesh.positions);
    }
  }
}

// Triangle shapes of budget meshes (docs/HIERARCHY.md, "Vertex placement"): the new vertex of an
// interior edge goes on the line along the block normal, where its four triangles are best
// shaped. Measured (% of triangles with a minimum angle below 20°, RMS distance):
//   gyroid@64  5000: 4.78 % 4.80e-3 with the projection along ∇f, 2.58 % 3.71e-3 now
//   gyroid@64 20000: 14.1 % 1.92e-3                                3.04 % 9.45e-4
//   torus@64   5000: 2.78 % 1.074e-3                               1.68 % 1.095e-3
//   torus@64  20000: 2.00 % 2.587e-4                               1.24 % 2.628e-4
// The bounds sit between the two (shapes) or 5 % above the old error.
TEST(RefineAdaptive, BudgetMeshesAreWellShaped) {
  struct Case {
    const char* shape;
    std::size_t triangles;
    double max_pct_below_20, max_rms;
  };
  for (const Case c : {Case{"gyroid", 5000, 3.6, 4.1e-3}, Case{"gyroid", 20000, 5.0, 1.1e-3},
                       Case{"torus", 5000, 2.3, 1.128e-3}, Case{"torus", 20000, 1.7, 2.72e-4}}) {
    const Fixture f = make_fixture(std::string("shape:") + c.shape, 64);
    RefineOptions o;
    o.mode = RefineMode::budget;
    o.max_triangles = c.triangles;
    const std::string label = std::string(c.shape) + "@64 budget " + std::to_string(c.triangles);
    const RefineResult r = run(f, *f.in.field, o, label);
    const CutMesh cut = extract_all(r.hierarchy);
    const ShapeFigures q = shape_figures(cut.mesh);
    FieldErrorOptions fo;
    fo.inside_sign = f.in.inside_sign;
    const double rms = field_error(cut.mesh, *f.in.field, 0, fo).distance.rms;
    std::printf("  %s: %.2f%% below 20deg, rms %.3e, normal-line placements %zu of %zu\n",
                label.c_str(), q.pct_below_20, rms, r.stats.line_placements, r.stats.splits);
    EXPECT_LT(q.pct_below_20, c.max_pct_below_20) << label;
    EXPECT_LT(rms, c.max_rms) << label;
  }
}
