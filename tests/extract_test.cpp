// extract(): the library pipeline — the same bytes as `adamesh extract`, budgets, options
// checked, progress reported in stage order, cancellation, thread-count independence.
#include "adamesh/extract.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "adamesh/error.h"
#include "adamesh/io.h"
#include "adamesh/metrics.h"
#include "error_status.h"
#include "testing.h"

using namespace adamesh;
using namespace adamesh::testutil;

namespace {

std::string head_path() { return source_dir() + "/data/ct_headsq/quarter.nhdr"; }


}  // namespace

TEST(Extract, SameBytesAsTheCli) {
  TempDir tmp;
  ASSERT_EQ(run_cli("extract '" + head_path() + "' --iso 500.5 --triangles 20000 --quiet -o " +
                    tmp.file("cli.ply") + " --base " + tmp.file("cli_base.ply") +
                    " --hierarchy " + tmp.file("cli.amh"))
                .exit_code,
            0);
  ExtractOptions o;
  o.iso = 500.5;
  o.budget = Budget::triangles;
  o.triangles = 20000;
  const ExtractResult r = extract(head_path(), o);
  write_mesh(r.mesh, tmp.file("lib.ply"));
  write_mesh(r.base.mesh, tmp.file("lib_base.ply"));
  ASSERT_TRUE(r.hierarchy);
  write_hierarchy(*r.hierarchy, tmp.file("lib.amh"));
  EXPECT_EQ(read_bytes(tmp.file("cli.ply")), read_bytes(tmp.file("lib.ply")));
  EXPECT_EQ(read_bytes(tmp.file("cli_base.ply")), read_bytes(tmp.file("lib_base.ply")));
  EXPECT_EQ(read_bytes(tmp.file("cli.amh")), read_bytes(tmp.file("lib.amh")));
  EXPECT_LE(r.mesh.num_triangles(), 20000u);
  EXPECT_EQ(r.report.triangles, r.mesh.num_triangles());
}

TEST(Extract, DefaultBudgetIsCappedByMarchingCubes) {
  ExtractOptions o;
  const ExtractResult r = extract("shape:torus", o, {});
  ASSERT_TRUE(r.report.refined);
  EXPECT_GT(r.report.triangle_cap, 0u);
  EXPECT_LE(r.mesh.num_triangles(), r.report.triangle_cap);
  EXPECT_NE(r.report.chosen.find("the default"), std::string::npos) << r.report.chosen;
  EXPECT_EQ(r.report.base_topology.euler, 0);  // a torus
  // The output is the hierarchy's finest cut.
  EXPECT_EQ(extract_all(*r.hierarchy).mesh.num_triangles(), r.mesh.num_triangles());
}

TEST(Extract, BaseOnlyAndUniformLevels) {
  ExtractOptions o;
  o.budget = Budget::none;
  const ExtractResult base = extract("shape:sphere", o);
  EXPECT_FALSE(base.hierarchy);
  EXPECT_EQ(base.mesh.num_triangles(), 0u);
  EXPECT_FALSE(base.report.refined);
  EXPECT_GT(base.base.mesh.num_triangles(), 0u);
  EXPECT_EQ(base.report.base_topology.euler, 2);

  o.budget = Budget::levels;
  o.levels = 2;
  o.measure_levels = true;
  const ExtractResult lv = extract("shape:sphere", o);
  ASSERT_TRUE(lv.hierarchy);
  // Each uniform level doubles the triangles: M2 has 4 × M0.
  EXPECT_EQ(lv.mesh.num_triangles(), 4 * lv.base.mesh.num_triangles());
  ASSERT_EQ(lv.report.levels.size(), 3u);
  for (int j = 0; j < 3; ++j) EXPECT_EQ(lv.report.levels[j].level, j);
  // The same sphere and the same base mesh with and without refinement.
  EXPECT_EQ(lv.base.mesh.positions, base.base.mesh.positions);
}

TEST(Extract, RejectsBadOptionsAndEmptySurfaces) {
  ExtractOptions o;
  o.budget = Budget::levels;
  o.levels = 31;
  EXPECT_EQ(status_of([&] { extract("shape:sphere", o); }), Status::usage);
  o = {};
  o.budget = Budget::max_error;
  EXPECT_EQ(status_of([&] { extract("shape:sphere", o); }), Status::usage);
  o = {};
  o.r_max = -1;
  EXPECT_EQ(status_of([&] { extract("shape:sphere", o); }), Status::usage);
  o = {};
  EXPECT_EQ(status_of([&] { extract(head_path(), o); }), Status::usage);  // no iso
  o.iso = 1e9;
  try {
    extract(head_path(), o);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::invalid_input);
    EXPECT_NE(std::string(e.what()).find("quarter.nhdr: iso-value"), std::string::npos) << e.what();
  }
}

TEST(Extract, ReportsProgressInStageOrder) {
  std::vector<std::string> stages;
  ExtractOptions o;
  o.budget = Budget::triangles;
  o.triangles = 2000;
  o.context.progress = [&](const char* s, double f) {
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
    if (stages.empty() || stages.back() != s) stages.push_back(s);
  };
  extract("shape:genus2", o);
  const std::vector<std::string> want = {"read",       "surfels", "graph",   "disk cover",
                                         "voronoi",    "dual",    "improve M0", "refine",
                                         "improve",    "fit",     "separate"};
  EXPECT_EQ(stages, want);
}

TEST(Extract, CancellationStopsTheCall) {
  std::atomic<bool> cancel{false};
  ExtractOptions o;
  o.context.cancel = &cancel;
  int calls = 0;
  o.context.progress = [&](const char* s, double) {
    if (std::string(s) == "graph") cancel = true;
    ++calls;
  };
  EXPECT_EQ(status_of([&] { extract("shape:torus", o); }), Status::cancelled);
  EXPECT_GT(calls, 0);
  cancel = true;  // already set: not even the input is read
  calls = 0;
  EXPECT_EQ(status_of([&] { extract("shape:torus", o); }), Status::cancelled);
  EXPECT_EQ(calls, 0);
}

TEST(Extract, SameMeshForAnyThreadCount) {
  ExtractOptions o;
  o.budget = Budget::triangles;
  o.triangles = 5000;
  o.context.threads = 1;
  const ExtractResult a = extract("shape:genus2", o);
  o.context.threads = 2;
  const ExtractResult b = extract("shape:genus2", o);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  o.context.threads = -1;
  EXPECT_EQ(status_of([&] { extract("shape:genus2", o); }), Status::usage);
}

TEST(Extract, SameScanMeshForAnyThreadCount) {
  // The CT head exercises what genus2 does not: M0's decimation (3000 < M0), flips, moves,
  // collapses and the untangling of crossings on a noisy surface, whose tests run in parallel
  // and are applied in order (issue 14).
  for (const std::size_t triangles : {3000, 20000}) {
    ExtractOptions o;
    o.iso = 500.5;
    o.budget = Budget::triangles;
    o.triangles = triangles;
    o.context.threads = 1;
    const ExtractResult a = extract(head_path(), o);
    o.context.threads = 2;
    const ExtractResult b = extract(head_path(), o);
    EXPECT_EQ(a.mesh.positions, b.mesh.positions) << triangles;
    EXPECT_EQ(a.mesh.triangles, b.mesh.triangles) << triangles;
    EXPECT_GT(a.report.improve.flips + a.report.improve.moves, 0u) << triangles;
    if (triangles == 3000) EXPECT_GT(a.report.base_improve.decimated, 0u);
    else EXPECT_GT(a.report.improve.intersections_before, 0u);
    // The separation ran last: its count is the written mesh's, and it never adds a pair.
    ASSERT_TRUE(a.report.separate.has_value());
    EXPECT_LE(a.report.separate->intersections_after, a.report.separate->intersections_before);
    EXPECT_EQ(static_cast<std::int64_t>(a.report.separate->intersections_after),
              self_intersections(a.mesh).pairs);
  }
}

TEST(Extract, FromALoadedInput) {
  const Input in = load_input("shape:torus");
  ExtractOptions o;
  o.budget = Budget::triangles;
  o.triangles = 3000;
  const ExtractResult a = extract(in, o);
  const ExtractResult b = extract("shape:torus", o);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.report.input, "shape:torus");
  EXPECT_NE(report_json(a.report).find("\"chosen\": \"--triangles 3000\""), std::string::npos);
}

TEST(Extract, FromBorrowedSamples) {
  // The Python module's path: samples owned elsewhere (a numpy array), borrowed without a copy.
  const Input ref = load_input("shape:genus2");
  const Volume& v = *ref.volume;
  const std::size_t bytes = v.data.size();
  auto owner = std::make_shared<std::vector<std::byte>>(v.data.data(), v.data.data() + bytes);
  Volume borrowed;
  borrowed.grid = v.grid;
  borrowed.type = v.type;
  borrowed.data = SampleBuffer(owner->data(), bytes, owner);
  EXPECT_TRUE(borrowed.data.borrowed());
  EXPECT_EQ(borrowed.data.data(), owner->data());
  const Input in = make_input(std::move(borrowed), "<array>", -1);
  EXPECT_EQ(in.volume->data.data(), owner->data());  // still not copied
  EXPECT_FALSE(in.default_iso);
  // The same samples in an owned buffer (a sampled field, not the analytic shape).
  Volume owned;
  owned.grid = v.grid;
  owned.type = v.type;
  owned.data = SampleBuffer(bytes);
  std::copy(v.data.data(), v.data.data() + bytes, owned.data.data());
  EXPECT_FALSE(owned.data.borrowed());
  const Input copy = make_input(std::move(owned), "<copy>", -1);
  ExtractOptions o;
  o.iso = 0.0;
  o.budget = Budget::triangles;
  o.triangles = 3000;
  const ExtractResult a = extract(in, o), b = extract(copy, o);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
  EXPECT_EQ(a.report.input, "<array>");
  // NaN samples: rejected with the input's name, or replaced (in the buffer given).
  std::vector<float> nan(8, 1.0f);
  nan[5] = std::numeric_limits<float>::quiet_NaN();
  Volume tiny;
  tiny.grid.dims = {2, 2, 2};
  tiny.type = ScalarType::f32;
  tiny.data = SampleBuffer(reinterpret_cast<std::byte*>(nan.data()), 32, nullptr);
  EXPECT_EQ(status_of([&] { make_input(std::move(tiny), "<array>"); }), Status::invalid_input);
}

// The least-squares fit (the default for adaptive meshes): against the same mesh with its
// vertices on the surface, a lower RMS distance, no triangle sharper than min(its angle before,
// 20°), no more intersecting pairs, every vertex in the volume's box, identical for 1 and 2
// threads; --levels and --no-improve keep the hierarchy's placements.
TEST(Extract, FitLowersTheErrorAndKeepsShapeCrossingsAndBox) {
  struct Case {
    std::string spec;
    double iso;
    std::size_t triangles;
    double max_ratio;  // RMS with the fit / RMS on the surface
  };
  for (const Case& c : {Case{"shape:torus", 0.0, 3000, 0.6}, Case{head_path(), 500.5, 5000, 0.9}}) {
    SCOPED_TRACE(c.spec);
    InputOptions io;
    io.resolution = 48;
    const Input in = load_input(c.spec, io);
    ExtractOptions o;
    o.iso = c.iso;
    o.budget = Budget::triangles;
    o.triangles = c.triangles;
    o.fit = ExtractOptions::Fit::surface;
    const ExtractResult on = extract(in, o);
    EXPECT_FALSE(on.report.fit.has_value());
    o.fit = ExtractOptions::Fit::automatic;
    o.context.threads = 1;
    const ExtractResult fit = extract(in, o);
    o.context.threads = 2;
    EXPECT_EQ(extract(in, o).mesh.positions, fit.mesh.positions);
    ASSERT_TRUE(fit.report.fit.has_value());
    EXPECT_LT(fit.report.fit->rms_after, fit.report.fit->rms_before);
    ASSERT_EQ(fit.mesh.triangles, on.mesh.triangles);  // the same connectivity, moved vertices
    const double e_on = field_error(on.mesh, *in.field, c.iso).distance.rms;
    const double e_fit = field_error(fit.mesh, *in.field, c.iso).distance.rms;
    EXPECT_LT(e_fit, c.max_ratio * e_on) << e_on << " -> " << e_fit;
    // Angles, triangle by triangle.
    auto smallest = [](const Mesh& m, std::size_t t) {
      double best = 180;
      for (int k = 0; k < 3; ++k) {
        const Vec3 a = m.vertex(m.triangles[3 * t + k]), b = m.vertex(m.triangles[3 * t + (k + 1) % 3]),
                   d = m.vertex(m.triangles[3 * t + (k + 2) % 3]);
        const Vec3 u = b - a, w = d - a;
        best = std::min(best, std::atan2(norm(cross(u, w)), dot(u, w)) * 180 / 3.141592653589793);
      }
      return best;
    };
    std::size_t sharper = 0;
    for (std::size_t t = 0; t < fit.mesh.num_triangles(); ++t) {
      const double before = smallest(on.mesh, t), after = smallest(fit.mesh, t);
      sharper += after < std::min(before, 20.0) - 1e-3;
    }
    EXPECT_EQ(sharper, 0u);
    EXPECT_LE(quality(fit.mesh).pct_min_angle_below[1], quality(on.mesh).pct_min_angle_below[1]);
    EXPECT_LE(self_intersections(fit.mesh).pairs, self_intersections(on.mesh).pairs);
    const Box box = in.field->domain();
    for (std::size_t v = 0; v < fit.mesh.num_vertices(); ++v)
      for (int k = 0; k < 3; ++k) {
        EXPECT_GE(fit.mesh.vertex(v)[k], box.lo[k]);
        EXPECT_LE(fit.mesh.vertex(v)[k], box.hi[k]);
      }
  }
  // Uniform levels and --no-improve: the hierarchy's placements, not fitted.
  ExtractOptions o;
  o.budget = Budget::levels;
  o.levels = 1;
  InputOptions io;
  io.resolution = 32;
  EXPECT_FALSE(extract("shape:torus", o, io).report.fit.has_value());
  o.budget = Budget::triangles;
  o.triangles = 2000;
  o.improve = false;
  EXPECT_FALSE(extract("shape:torus", o, io).report.fit.has_value());
  o.fit = ExtractOptions::Fit::l2;  // unless asked for
  EXPECT_TRUE(extract("shape:torus", o, io).report.fit.has_value());
}
