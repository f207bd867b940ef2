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
  const std::vector<std::string> want = {"read",   "surfels",    "graph",  "disk cover", "voronoi",
                                         "dual",   "improve M0", "refine", "improve"};
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
