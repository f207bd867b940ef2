// Real scans (issue 12, docs/QUALITY.md): on the shared volumes the adaptive meshes keep their
// triangle budget, keep marching cubes' topology, stay inside the volume's box and are well
// shaped. Uses ../shared/data (skips without it); about a minute.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "adamesh/io.h"
#include "mesh_checks.h"
#include "testing.h"

namespace adamesh {
namespace {

using testutil::mesh_topo;
using testutil::run_cli;
using testutil::TempDir;

struct Scan {
  const char* file;
  double iso;
  double max_pct_below_20;  ///< measured at 20k (docs/QUALITY.md) plus a margin
  double min_angle_deg;     ///< the smallest angle at 20k must stay above this (measured less a margin)
  double max_pairs_pct;     ///< self-intersecting pairs, % of the budget (measured plus a margin)
};

// Every shared scan small enough for ctest; the large ones (lidc2, frog, embryo) are in the
// benchmark's scans table. Measured at 20k on 2026-12-03, with the rescue (below 20° / smallest
// angle / pairs; docs/QUALITY.md "Rescue"): CT head 0.06 % / 12.4° / 20, skull 0.12 % / 8.4° / 38,
// MRI head 0.35 % / 9.6° / 219, ironprot 0 % / 20.1° / 0, neghip 0.01 % / 18.6° / 53, hydrogen
// 0 % / 23.7° / 0, carotid 0 % / 20.0° / 37, bolt and vase 0 % / 23.3° / 0. The share under 20°
// is asserted at issue 12's target (< 1 %) everywhere, the smallest angle at its 10° target
// where it is met and at the measured value less a margin on the skull (docs/QUALITY.md). The MRI
// head's two back-to-back 9.6° needles on a 0.50 edge held by the link condition are gone since
// the graded needle splits (2026-12-04): 0.15 % / 11.7° / 145.
const Scan kScans[] = {
    {"ct_headsq/quarter.nhdr", 500.5, 1.0, 10.0, 1.0},
    {"ct_headsq/quarter.nhdr", 1150.5, 1.0, 6.0, 1.0},
    {"mri_headmr/HeadMRVolume.mhd", 20.5, 1.0, 10.0, 2.0},
    {"ironprot/ironProt.vtk", 128.5, 1.0, 10.0, 1.0},
    {"neghip/neghip.slc", 100.5, 1.0, 10.0, 1.0},
    {"hydrogen/hydrogen.vti", 0.1, 1.0, 10.0, 1.0},
    {"carotid/carotid.vtk", 200.5, 1.0, 10.0, 1.0},
    {"bolt/bolt.slc", 128.5, 1.0, 10.0, 1.0},
    {"vase/vase.vti", 128.5, 1.0, 10.0, 1.0},
};

/// Vertices of `m` outside the world box `adamesh info` gives for `file` (by more than 1e-5 of
/// the box's side).
std::size_t vertices_outside_box(const Mesh& m, const std::string& file) {
  const auto info = run_cli("info " + file + " --json");
  EXPECT_EQ(info.exit_code, 0) << info.err;
  const auto j = nlohmann::json::parse(info.out);
  const auto lo = j["bounds"][0], hi = j["bounds"][1];
  std::size_t outside = 0;
  for (std::size_t v = 0; v < m.num_vertices(); ++v) {
    const Vec3 p = m.vertex(v);
    bool out = false;
    for (int k = 0; k < 3; ++k) {
      const double l = lo[k].get<double>(), h = hi[k].get<double>(), e = 1e-5 * (h - l);
      out |= p[k] < l - e || p[k] > h + e;
    }
    outside += out;
  }
  return outside;
}

class ScanTest : public ::testing::TestWithParam<Scan> {};

TEST_P(ScanTest, BudgetTopologyBoxAndShape) {
  ADAMESH_REQUIRE_SHARED_DATA(data);
  const Scan& s = GetParam();
  TempDir tmp;
  const std::string in = data + "/" + s.file + " --iso " + std::to_string(s.iso);
  ASSERT_EQ(run_cli("mc " + in + " -o " + tmp.file("mc.ply") + " --quiet").exit_code, 0);
  const Mesh mc = read_mesh(tmp.file("mc.ply"));
  const std::size_t n = 20000;
  const auto r = run_cli("extract " + in + " --triangles " + std::to_string(n) + " -o " +
                         tmp.file("a.ply") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Mesh a = read_mesh(tmp.file("a.ply"));
  // The budget holds within 1 % (smaller when the surface is too small for it: the size limit).
  EXPECT_LE(a.num_triangles(), n);
  if (mc.num_triangles() > 2 * n) {
    EXPECT_GE(a.num_triangles(), n - n / 100);
  }
  // Marching cubes' topology.
  const auto ta = mesh_topo(a), tm = mesh_topo(mc);
  EXPECT_EQ(ta.chi, tm.chi);
  EXPECT_EQ(ta.components, tm.components);
  EXPECT_EQ(ta.boundary_loops, tm.boundary_loops);
  EXPECT_EQ(ta.nonmanifold_edges, 0);
  EXPECT_TRUE(ta.oriented);
  // Inside the volume's box (marching cubes' vertices span it on open surfaces).
  EXPECT_EQ(vertices_outside_box(a, data + "/" + s.file), 0u);
  // Shape.
  const auto st = run_cli("stats " + tmp.file("a.ply") + " --json");
  ASSERT_EQ(st.exit_code, 0);
  const auto q = nlohmann::json::parse(st.out);
  EXPECT_LE(q["pct_min_angle_below"]["20"].get<double>(), s.max_pct_below_20) << s.file;
  EXPECT_GE(q["min_angle_deg"]["min"].get<double>(), s.min_angle_deg) << s.file;
  // Self-intersections: the refinement folds noisy surfaces (CT head 20k: 943 pairs, MRI head
  // 1,800), the untangling removes most; a regression guard, not the zero.
  EXPECT_LE(q["self_intersecting_pairs"].get<double>(), 0.01 * s.max_pairs_pct * static_cast<double>(n))
      << s.file;
}

// A border vertex placed by the refinement is projected in its face's plane, which can carry it
// past the face's edge where the surface leaves the box along that face: carotid at 100.5 (an
// iso-value no other test uses) had one default-mesh vertex 0.08 voxel beyond y max on the
// x min face until the placement clamped it into the face (2026-12-04).
TEST(ScanBounds, BorderVerticesStayInsideTheirFace) {
  ADAMESH_REQUIRE_SHARED_DATA(data);
  TempDir tmp;
  const std::string file = data + "/carotid/carotid.vtk";
  for (const char* mode : {"", " --no-improve --fit surface"}) {
    const auto r = run_cli("extract " + file + " --iso 100.5 -o " + tmp.file("a.ply") + " --quiet" +
                           mode);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(vertices_outside_box(read_mesh(tmp.file("a.ply")), file), 0u) << mode;
  }
}

// A noisy synthetic scan, 110×90×70 uint8 (a CT-like texture: white noise blurred by three
// box passes of radius 2, plus white noise), the same at every call.
std::string noisy_scan_bytes() {
  const int nx = 110, ny = 90, nz = 70, r = 2;
  const std::size_t n = static_cast<std::size_t>(nx) * ny * nz;
  std::vector<double> w(n), f(n), acc(n);
  std::uint64_t state = 2026;
  for (auto& x : w) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    x = static_cast<double>(state >> 11) / 9007199254740992.0 - 0.5;
  }
  f = w;
  const int dims[3] = {nx, ny, nz};
  auto at = [&](int x, int y, int z) { return (static_cast<std::size_t>(z) * ny + y) * nx + x; };
  for (int pass = 0; pass < 3; ++pass)
    for (int axis = 0; axis < 3; ++axis) {
      for (int z = 0; z < nz; ++z)
        for (int y = 0; y < ny; ++y)
          for (int x = 0; x < nx; ++x) {
            double sum = 0;
            for (int d = -r; d <= r; ++d) {
              int c[3] = {x, y, z};
              c[axis] = (c[axis] + d + dims[axis]) % dims[axis];  // periodic
              sum += f[at(c[0], c[1], c[2])];
            }
            acc[at(x, y, z)] = sum / (2 * r + 1);
          }
      f.swap(acc);
    }
  double mean = 0, var = 0;
  for (double x : f) mean += x;
  mean /= static_cast<double>(n);
  for (double x : f) var += (x - mean) * (x - mean);
  const double sd = std::sqrt(var / static_cast<double>(n));
  std::string bytes(n, '\0');
  for (std::size_t i = 0; i < n; ++i)
    bytes[i] = static_cast<char>(static_cast<unsigned char>(
        std::clamp(std::round(128 + 40 * (f[i] - mean) / sd + 8 * w[i]), 0.0, 255.0)));
  return bytes;
}

// Voxel spacings whose box is not a float (0.8: the top faces at 87.2, 71.2, 110.4): the mesh's
// float vertices lie up to half a float step off those faces, which the improvement took for
// "not on the face" (border vertices frozen) or "outside the box" (no move allowed); the slivers
// along the faces stayed: smallest angle 0.00° and 0.39 % under 20° at 20k against 1.13° and
// 0.06 % for the same scan at spacing 0.75 (before 2026-12-04). Both are now the same within
// noise, with the 10° minimum held.
TEST(ScanBounds, SpacingThatIsNotAFloatMeshesAsWell) {
  TempDir tmp;
  testutil::write_bytes(tmp.file("s.raw"), noisy_scan_bytes());
  double pct[2] = {0, 0};
  int i = 0;
  for (const char* spacing : {"0.8,0.8,1.6", "0.75,0.75,1.5"}) {
    const std::string in =
        tmp.file("s.raw") + " --dims 110,90,70 --type uint8 --spacing " + spacing;
    const auto r = run_cli("extract " + in + " --iso 140.5 --triangles 20000 -o " +
                           tmp.file("a.ply") + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const Mesh a = read_mesh(tmp.file("a.ply"));
    EXPECT_NEAR(static_cast<double>(a.num_triangles()), 20000.0, 200.0) << spacing;
    EXPECT_EQ(vertices_outside_box(a, in), 0u) << spacing;
    const auto st = run_cli("stats " + tmp.file("a.ply") + " --json");
    ASSERT_EQ(st.exit_code, 0) << st.err;
    const auto q = nlohmann::json::parse(st.out);
    pct[i++] = q["pct_min_angle_below"]["20"].get<double>();
    EXPECT_GE(q["min_angle_deg"]["min"].get<double>(), 10.0) << spacing;  // 13.99° at both
    EXPECT_LT(pct[i - 1], 0.2) << spacing;                               // 0.05 % and 0.04 %
  }
  EXPECT_LT(std::abs(pct[0] - pct[1]), 0.1);
}

// An oblique grid (NRRD space directions rotated 20° about z, spacing 0.8, 0.8, 1.6): its world
// box holds more than the grid, and the improvement and the fit took the box for the volume.
// Before 2026-12-04 the 20k mesh had vertices 1.28 voxel outside the grid, border vertices never
// moved (their faces are not axis planes) and a 0.00° triangle (0.50 % under 20°). Now every
// vertex is inside the grid (to float rounding), 11.9° and 0.05 %.
TEST(ScanBounds, ObliqueGridStaysInsideAndWellShaped) {
  TempDir tmp;
  testutil::write_bytes(tmp.file("s.raw"), noisy_scan_bytes());
  const double c = std::cos(20 * std::numbers::pi / 180), s = std::sin(20 * std::numbers::pi / 180);
  const Vec3 origin{-40.3, -20.7, 10.1}, spacing{0.8, 0.8, 1.6};
  std::ostringstream h;
  h.precision(17);
  h << "NRRD0004\ntype: uint8\ndimension: 3\nspace: left-posterior-superior\nsizes: 110 90 70\n"
    << "space directions: (" << c * spacing.x << "," << s * spacing.x << ",0) ("
    << -s * spacing.y << "," << c * spacing.y << ",0) (0,0," << spacing.z << ")\n"
    << "space origin: (" << origin.x << "," << origin.y << "," << origin.z << ")\n"
    << "encoding: raw\ndata file: s.raw\n";
  testutil::write_bytes(tmp.file("s.nhdr"), h.str());
  const auto r = run_cli("extract " + tmp.file("s.nhdr") + " --iso 140.5 --triangles 20000 -o " +
                         tmp.file("a.ply") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Mesh a = read_mesh(tmp.file("a.ply"));
  EXPECT_NEAR(static_cast<double>(a.num_triangles()), 20000.0, 200.0);
  const double top[3] = {109, 89, 69};
  double worst = 0;  // farthest outside the grid, in voxels
  for (std::size_t v = 0; v < a.num_vertices(); ++v) {
    const Vec3 d = a.vertex(v) - origin;
    const double u[3] = {(c * d.x + s * d.y) / spacing.x, (-s * d.x + c * d.y) / spacing.y,
                         d.z / spacing.z};
    for (int k = 0; k < 3; ++k) worst = std::max({worst, -u[k], u[k] - top[k]});
  }
  EXPECT_LT(worst, 1e-4);  // float rounding of the stored coordinates: 8e-6
  // `stats --field` says the same (it was 8 vertices, 1.283 voxel, before).
  const auto sf = run_cli("stats " + tmp.file("a.ply") + " --field " + tmp.file("s.nhdr") +
                          " --iso 140.5 --json");
  ASSERT_EQ(sf.exit_code, 0) << sf.err;
  EXPECT_EQ(nlohmann::json::parse(sf.out)["vertices_outside_volume"], 0);
  const auto st = run_cli("stats " + tmp.file("a.ply") + " --json");
  ASSERT_EQ(st.exit_code, 0) << st.err;
  const auto q = nlohmann::json::parse(st.out);
  EXPECT_GE(q["min_angle_deg"]["min"].get<double>(), 10.0);
  EXPECT_LT(q["pct_min_angle_below"]["20"].get<double>(), 0.2);
}

// A budget far below the base mesh (MRI head at 5,000 triangles: M0 has 23,288, decimated to
// 3,750 first): the decimation's collapses choose the best of the projected midpoint and the two
// ends (8.9 % under 20° with the midpoint only, 5.5 % now) and the topology stays.
TEST(ScanBounds, DecimatedBudgetIsWellShaped) {
  ADAMESH_REQUIRE_SHARED_DATA(data);
  TempDir tmp;
  const std::string in = data + "/mri_headmr/HeadMRVolume.mhd --iso 20.5";
  ASSERT_EQ(run_cli("mc " + in + " -o " + tmp.file("mc.ply") + " --quiet").exit_code, 0);
  const auto r = run_cli("extract " + in + " --triangles 5000 -o " + tmp.file("a.ply") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Mesh a = read_mesh(tmp.file("a.ply"));
  EXPECT_LE(a.num_triangles(), 5000u);
  EXPECT_GE(a.num_triangles(), 4950u);
  const auto ta = mesh_topo(a), tm = mesh_topo(read_mesh(tmp.file("mc.ply")));
  EXPECT_EQ(ta.chi, tm.chi);
  EXPECT_EQ(ta.components, tm.components);
  EXPECT_EQ(ta.boundary_loops, tm.boundary_loops);
  const auto st = run_cli("stats " + tmp.file("a.ply") + " --json");
  ASSERT_EQ(st.exit_code, 0);
  const auto q = nlohmann::json::parse(st.out);
  EXPECT_LE(q["pct_min_angle_below"]["20"].get<double>(), 2.0);  // 1.26 % on 2026-12-03
  EXPECT_EQ(q["degenerate_triangles"].get<int>(), 0);
}

// The improvement's last collapses (docs/QUALITY.md "Rescue"): the MRI head's default mesh had
// a 1.0° triangle at a fold whose needle edge cannot collapse; another edge of it can, and the
// smallest angle is 11.1° since (2026-12-03). The topology stays marching cubes'.
TEST(ScanBounds, DefaultMriHeadHasNoTriangleUnderTenDegrees) {
  ADAMESH_REQUIRE_SHARED_DATA(data);
  TempDir tmp;
  const std::string in = data + "/mri_headmr/HeadMRVolume.mhd --iso 20.5";
  ASSERT_EQ(run_cli("mc " + in + " -o " + tmp.file("mc.ply") + " --quiet").exit_code, 0);
  const auto r = run_cli("extract " + in + " -o " + tmp.file("a.ply") + " --report " +
                         tmp.file("r.json") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto ta = mesh_topo(read_mesh(tmp.file("a.ply"))), tm = mesh_topo(read_mesh(tmp.file("mc.ply")));
  EXPECT_EQ(ta.chi, tm.chi);
  EXPECT_EQ(ta.components, tm.components);
  EXPECT_EQ(ta.boundary_loops, tm.boundary_loops);
  const auto st = run_cli("stats " + tmp.file("a.ply") + " --json");
  ASSERT_EQ(st.exit_code, 0) << st.err;
  const auto q = nlohmann::json::parse(st.out);
  EXPECT_GE(q["min_angle_deg"]["min"].get<double>(), 10.0);
  EXPECT_LT(q["pct_min_angle_below"]["20"].get<double>(), 1.0);
  const auto rep = nlohmann::json::parse(testutil::read_bytes(tmp.file("r.json")));
  EXPECT_GE(rep["refine"]["improve"]["min_angle_after"].get<double>(), 10.0);
}

INSTANTIATE_TEST_SUITE_P(Shared, ScanTest, ::testing::ValuesIn(kScans),
                         [](const auto& info) { return "scan" + std::to_string(info.index); });

// --max-error E on a noisy CT: the written mesh meets E at the 99th percentile of the dense
// measurement, or the report says where it could not, and is as well shaped as the default's.
TEST(ScanBounds, MaxErrorP99HoldsOrIsReported) {
  TempDir tmp;
  const std::string head = testutil::source_dir() + "/data/ct_headsq/quarter.nhdr";
  const double e = 0.5;
  const auto r = run_cli("extract " + head + " --iso 500.5 --max-error " + std::to_string(e) +
                         " -o " + tmp.file("a.ply") + " --report " + tmp.file("r.json") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto s = run_cli("stats " + tmp.file("a.ply") + " --field " + head + " --iso 500.5 --json");
  ASSERT_EQ(s.exit_code, 0) << s.err;
  const auto j = nlohmann::json::parse(s.out);
  EXPECT_LE(j["distance"]["p99"].get<double>(), e);
  // As well shaped and untangled as the default mesh: the improvement keeps the surface within
  // min(E, ¼ voxel) but no seven-point bound per triangle, which left 1.55 % of the triangles
  // under 20°, a 0.35° triangle and 7,910 crossing pairs (12 %) here (docs/QUALITY.md).
  EXPECT_LT(j["pct_min_angle_below"]["20"].get<double>(), 1.0);
  EXPECT_GE(j["min_angle_deg"]["min"].get<double>(), 5.0);
  EXPECT_LT(j["self_intersecting_pairs"].get<double>(), 0.02 * j["triangles"].get<double>());
  const auto rep = nlohmann::json::parse(testutil::read_bytes(tmp.file("r.json")));
  const auto& fin = rep["levels"].back();
  // The report's own measurement is the one a user checks against.
  EXPECT_NEAR(fin["p99"].get<double>(), j["distance"]["p99"].get<double>(), 0.05 * e);
}

// --max-error on shared scans of other kinds (an angiography CT, an averaged MRI): the bound at
// the 99th percentile, and the mesh untangled and well shaped. Before the improvement dropped
// its seven-point bound (docs/QUALITY.md "An explicit --max-error"): carotid 2.3° and 916
// crossing pairs (3 %), avg152T1 1.7°, 1.54 % under 20° and 2,817 pairs (6.7 %).
TEST(ScanBounds, MaxErrorOnSharedScansIsUntangledAndWellShaped) {
  ADAMESH_REQUIRE_SHARED_DATA(data);
  struct Case {
    const char* file;
    double iso, e;
  };
  for (const Case c : {Case{"carotid/carotid.vtk", 200.5, 0.1},
                       Case{"mri_avg152T1/avg152T1_RL_nifti.nii.gz", 60.5, 1.0}}) {
    TempDir tmp;
    const std::string in = data + "/" + c.file + " --iso " + std::to_string(c.iso);
    const auto r = run_cli("extract " + in + " --max-error " + std::to_string(c.e) + " -o " +
                           tmp.file("a.ply") + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << c.file << r.err;
    const auto s = run_cli("stats " + tmp.file("a.ply") + " --field " + in + " --json");
    ASSERT_EQ(s.exit_code, 0) << c.file << s.err;
    const auto j = nlohmann::json::parse(s.out);
    EXPECT_LE(j["distance"]["p99"].get<double>(), c.e) << c.file;
    EXPECT_LT(j["pct_min_angle_below"]["20"].get<double>(), 1.0) << c.file;
    EXPECT_GE(j["min_angle_deg"]["min"].get<double>(), 5.0) << c.file;
    EXPECT_LT(j["self_intersecting_pairs"].get<double>(), 0.01 * j["triangles"].get<double>())
        << c.file;
    EXPECT_EQ(j["vertices_outside_volume"].get<int>(), 0) << c.file;
  }
}

// A triangle budget below the base mesh of the topology: the smallest mesh plus a warning that
// says what would reach it.
TEST(ScanBounds, UnreachableBudgetSaysWhy) {
  TempDir tmp;
  const std::string head = testutil::source_dir() + "/data/ct_headsq/quarter.nhdr";
  const auto r = run_cli("extract " + head + " --iso 1150.5 --triangles 300 -o " + tmp.file("a.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("--triangles 300 is out of reach"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--min-component"), std::string::npos) << r.err;
}

// A budget the base mesh reaches only below the decimation's shape floor (frog label 13: 231
// components and 64 handles at 5,000 triangles, 12.4 % under 20° on 2026-12-03): the budget is
// met and one warning says the shape gave way and from which budget the floor holds; that budget
// decimates without going below it, and the output is better shaped (1.8 %).
TEST(ScanBounds, BudgetBelowTheShapeFloorSaysSo) {
  ADAMESH_REQUIRE_SHARED_DATA(data);
  TempDir tmp;
  const std::string in = data + "/frog/frogtissue.mhd --label 13";
  auto pct20 = [&](const std::string& mesh) {
    const auto st = run_cli("stats " + mesh + " --json");
    EXPECT_EQ(st.exit_code, 0) << st.err;
    return nlohmann::json::parse(st.out)["pct_min_angle_below"]["20"].get<double>();
  };
  const auto r = run_cli("extract " + in + " --triangles 5000 -o " + tmp.file("a.ply") +
                         " --report " + tmp.file("a.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto at = r.err.find("--triangles 5000 is met by collapsing the base mesh's edges below the 15.0° shape floor");
  ASSERT_NE(at, std::string::npos) << r.err;
  const auto more = r.err.find("; --triangles ", at);
  ASSERT_NE(more, std::string::npos) << r.err;
  const std::size_t n = std::stoul(r.err.substr(more + 14));
  const auto ra = nlohmann::json::parse(testutil::read_bytes(tmp.file("a.json")));
  const std::size_t stuck = ra["base"]["improve"]["decimation_stuck_at"].get<std::size_t>();
  EXPECT_LT(ra["base"]["improve"]["decimation_floor_deg"].get<double>(), 15.0);
  EXPECT_EQ(n, (4 * stuck + 2) / 3);
  const Mesh a = read_mesh(tmp.file("a.ply"));
  EXPECT_LE(a.num_triangles(), 5000u);
  EXPECT_GE(a.num_triangles(), 4950u);
  const double bad_a = pct20(tmp.file("a.ply"));
  EXPECT_GT(bad_a, 1.0);  // why the warning is there

  const auto r2 = run_cli("extract " + in + " --triangles " + std::to_string(n) + " -o " +
                          tmp.file("b.ply") + " --report " + tmp.file("b.json"));
  ASSERT_EQ(r2.exit_code, 0) << r2.err;
  EXPECT_EQ(r2.err.find("shape floor"), std::string::npos) << r2.err;
  const auto rb = nlohmann::json::parse(testutil::read_bytes(tmp.file("b.json")));
  EXPECT_EQ(rb["base"]["improve"]["decimation_stuck_at"].get<std::size_t>(), 0u);
  EXPECT_EQ(rb["base"]["improve"]["decimation_floor_deg"].get<double>(), 15.0);
  const Mesh b = read_mesh(tmp.file("b.ply"));
  EXPECT_NEAR(static_cast<double>(b.num_triangles()), static_cast<double>(n), 0.01 * n);
  EXPECT_LT(pct20(tmp.file("b.ply")), 0.5 * bad_a);
}

}  // namespace
}  // namespace adamesh

namespace adamesh {
namespace {

// Label maps: `info` lists the labels with their voxel counts, --label meshes one label,
// --labels all writes one mesh per label and a summary.
TEST(Labels, FrogInfoAndOneLabel) {
  ADAMESH_REQUIRE_SHARED_DATA(data);
  TempDir tmp;
  const std::string frog = data + "/frog/frogtissue.mhd";
  const auto info = run_cli("info " + frog + " --json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const auto j = nlohmann::json::parse(info.out);
  EXPECT_TRUE(j["label_map"].get<bool>());
  EXPECT_TRUE(j["suggested_iso"].is_null());
  ASSERT_EQ(j["labels"].size(), 26u);  // manifest: values 0..29, 26 of them present
  std::int64_t total = 0;
  for (const auto& l : j["labels"]) total += l["voxels"].get<std::int64_t>();
  EXPECT_EQ(total, 500LL * 470 * 136);
  EXPECT_EQ(j["labels"][13]["label"], 13);
  EXPECT_EQ(j["labels"][13]["voxels"], 440722);
  // Label 17 (38 voxels): its mesh has the topology of marching cubes on its mask.
  ASSERT_EQ(run_cli("mc " + frog + " --label 17 -o " + tmp.file("mc.ply") + " --quiet").exit_code, 0);
  const auto r = run_cli("extract " + frog + " --label 17 -o " + tmp.file("a.ply") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto ta = mesh_topo(read_mesh(tmp.file("a.ply"))), tm = mesh_topo(read_mesh(tmp.file("mc.ply")));
  EXPECT_EQ(ta.chi, tm.chi);
  EXPECT_EQ(ta.components, tm.components);
  EXPECT_GT(ta.triangles, 0);
  // A label no voxel has is one clear line.
  const auto bad = run_cli("extract " + frog + " --label 18 -o " + tmp.file("b.ply"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("no voxel has label 18"), std::string::npos) << bad.err;
}

TEST(Labels, AllLabelsIntoAFolder) {
  TempDir tmp;
  // 24³ uint8 volume: background 0, a 10³ cube of label 3, a 6³ cube of label 7 inside it.
  std::string v(24 * 24 * 24, '\0');
  for (int z = 0; z < 24; ++z)
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 24; ++x) {
        char c = 0;
        if (x >= 4 && x < 14 && y >= 4 && y < 14 && z >= 4 && z < 14) c = 3;
        if (x >= 16 && x < 22 && y >= 16 && y < 22 && z >= 16 && z < 22) c = 7;
        v[(z * 24 + y) * 24 + x] = c;
      }
  testutil::write_bytes(tmp.file("labels.raw"), v);
  const std::string in = tmp.file("labels.raw") + " --dims 24,24,24 --type uint8";
  const auto info = run_cli("info " + in + " --json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["labels"].size(), 3u);
  std::filesystem::create_directory(tmp.file("out"));
  const auto r = run_cli("extract " + in + " --labels all -o " + tmp.file("out") + "/");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp.file("out/label_0.ply")));  // the background
  for (const char* l : {"3", "7"}) {
    const Mesh m = read_mesh(tmp.file(std::string("out/label_") + l + ".ply"));
    const auto t = mesh_topo(m);
    EXPECT_EQ(t.chi, 2) << l;  // one closed sphere each
    EXPECT_EQ(t.components, 1) << l;
    EXPECT_NE(r.out.find(std::string("label_") + l + ".ply"), std::string::npos) << r.out;
  }
  const auto summary = nlohmann::json::parse(testutil::read_bytes(tmp.file("out/labels.json")));
  ASSERT_EQ(summary["labels"].size(), 2u);
  EXPECT_EQ(summary["labels"][0]["voxels"], 1000);
  EXPECT_EQ(summary["labels"][1]["voxels"], 216);
  // A folder that does not exist is refused before any work.
  const auto bad = run_cli("extract " + in + " --labels all -o " + tmp.file("nope") + "/");
  EXPECT_EQ(bad.exit_code, 4);
}

// A set of labels is one surface (their union's 0/1 mask), and an iso-value on a label map with
// several labels on one side says that its surface follows the label numbers and which set to
// mesh instead.
TEST(Labels, ASetIsOneSurfaceAndAnIsoValueSaysWhichSet) {
  TempDir tmp;
  // 24³ uint8: label 3 in x 4..11, label 7 in x 12..17 (touching: one box), label 9 apart.
  std::string v(24 * 24 * 24, '\0');
  for (int z = 4; z < 14; ++z)
    for (int y = 4; y < 14; ++y)
      for (int x = 4; x < 22; ++x) v[(z * 24 + y) * 24 + x] = x < 12 ? 3 : x < 18 ? 7 : 0;
  for (int z = 17; z < 21; ++z)
    for (int y = 17; y < 21; ++y)
      for (int x = 17; x < 21; ++x) v[(z * 24 + y) * 24 + x] = 9;
  testutil::write_bytes(tmp.file("l.raw"), v);
  const std::string in = tmp.file("l.raw") + " --dims 24,24,24 --type uint8";
  auto topo = [&](const std::string& opts, std::string* err = nullptr) {
    const auto r = run_cli("extract " + in + " " + opts + " -o " + tmp.file("a.ply"));
    EXPECT_EQ(r.exit_code, 0) << opts << ": " << r.err;
    if (err) *err = r.err;
    return mesh_topo(read_mesh(tmp.file("a.ply")));
  };
  const auto info = run_cli("info " + in);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("all but 0 as one surface with `extract --label 3-9`"), std::string::npos)
      << info.out;
  EXPECT_EQ(topo("--label 3,7").components, 1);  // one box, no wall between the labels
  EXPECT_EQ(topo("--label 3-7").components, 1);  // 3 to 7: the same voxels
  EXPECT_EQ(topo("--label 7,3").chi, 2);
  EXPECT_EQ(topo("--label 3,7,9").components, 2);
  EXPECT_EQ(topo("--label 9").components, 1);
  // The raw values at 0.5: the note names the three labels above it as one set.
  std::string err;
  topo("--iso 0.5", &err);
  EXPECT_NE(err.find("looks like a label map (4 integer values, 3 of them above the iso-value 0.5)"),
            std::string::npos) << err;
  EXPECT_NE(err.find("`--label 3-9` meshes the union of those 3 labels"), std::string::npos) << err;
  // One label against the background (a 0/1-like map) or its own mask: no note.
  topo("--label 3", &err);
  EXPECT_EQ(err.find("label map"), std::string::npos) << err;
  // Bad sets: one line each, usage exit code; a set no voxel is in: invalid input.
  for (const char* bad : {"3,", "7-3", "x", "3-7-9", "99999999999999999999"}) {
    const auto r = run_cli("extract " + in + " --label " + bad + " -o " + tmp.file("b.ply"));
    EXPECT_EQ(r.exit_code, 1) << bad;
    EXPECT_NE(r.err.find("--label: label set '" + std::string(bad) + "'"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  const auto none = run_cli("extract " + in + " --label 10-20 -o " + tmp.file("b.ply"));
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_NE(none.err.find("no voxel has a label in 10-20"), std::string::npos) << none.err;
  EXPECT_FALSE(std::filesystem::exists(tmp.file("b.ply")));
}

// The frog's tissues as one surface (docs/QUALITY.md "Label maps"): at iso 0.5 of the raw
// label numbers the surface hugs the background wherever a label above 1 meets it (4.3 % of
// the 100k mesh under 20° on 2026-12-03, 98 % of them in such cells); the union's mask at
// 100k: 0.07 %, topology of marching cubes on the same mask, inside the box.
TEST(Labels, FrogUnionOfTissuesIsWellShaped) {
  ADAMESH_REQUIRE_SHARED_DATA(data);
  TempDir tmp;
  const std::string in = data + "/frog/frogtissue.mhd --label 1-29";
  ASSERT_EQ(run_cli("mc " + in + " -o " + tmp.file("mc.ply") + " --quiet").exit_code, 0);
  const auto r = run_cli("extract " + in + " --triangles 100000 -o " + tmp.file("a.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
  const Mesh a = read_mesh(tmp.file("a.ply"));
  EXPECT_NEAR(static_cast<double>(a.num_triangles()), 100000.0, 1000.0);
  const auto ta = mesh_topo(a), tm = mesh_topo(read_mesh(tmp.file("mc.ply")));
  EXPECT_EQ(ta.chi, tm.chi);
  EXPECT_EQ(ta.components, tm.components);
  EXPECT_EQ(ta.boundary_loops, tm.boundary_loops);
  const auto st = run_cli("stats " + tmp.file("a.ply") + " --json");
  ASSERT_EQ(st.exit_code, 0) << st.err;
  const auto j = nlohmann::json::parse(st.out);
  EXPECT_LT(j["pct_min_angle_below"]["20"].get<double>(), 0.5);
  EXPECT_GT(j["min_angle_deg"]["min"].get<double>(), 2.0);
  const auto& b = j["bounds"];
  const std::array<double, 3> hi{499, 469, 202.5};  // (500, 470, 136) samples, spacing (1, 1, 1.5)
  for (int k = 0; k < 3; ++k) {
    EXPECT_GE(b["min"][k].get<double>(), 0.0);
    EXPECT_LE(b["max"][k].get<double>(), hi[k]);
  }
}

// Topology control: --min-cavity fills enclosed pockets below the size and says so.
TEST(TopologyControl, MinCavityFillsSmallCavities) {
  TempDir tmp;
  // A 16³ solid cube of 1 in a 24³ volume of 0, with a 2³ cavity and a 5³ cavity inside.
  std::string v(24 * 24 * 24, '\0');
  for (int z = 4; z < 20; ++z)
    for (int y = 4; y < 20; ++y)
      for (int x = 4; x < 20; ++x) {
        const bool small = x >= 7 && x < 9 && y >= 7 && y < 9 && z >= 7 && z < 9;
        const bool big = x >= 12 && x < 17 && y >= 12 && y < 17 && z >= 12 && z < 17;
        v[(z * 24 + y) * 24 + x] = small || big ? 0 : 100;
      }
  testutil::write_bytes(tmp.file("c.raw"), v);
  const std::string in = tmp.file("c.raw") + " --dims 24,24,24 --type uint8 --iso 50";
  auto topo_of = [&](const std::string& extra) {
    const auto r = run_cli("extract " + in + " " + extra + " -o " + tmp.file("a.ply") +
                           " --report " + tmp.file("r.json") + " --quiet");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return mesh_topo(read_mesh(tmp.file("a.ply")));
  };
  EXPECT_EQ(topo_of("").components, 3);  // outer surface + two cavity surfaces
  EXPECT_EQ(topo_of("--min-cavity 10").components, 2);  // the 8-voxel cavity is filled
  auto rep = nlohmann::json::parse(testutil::read_bytes(tmp.file("r.json")));
  EXPECT_EQ(rep["topology_control"]["cavities_filled"], 1);
  EXPECT_EQ(rep["topology_control"]["cavity_voxels_filled"], 8);
  EXPECT_EQ(topo_of("--min-cavity 200").components, 1);  // both
  rep = nlohmann::json::parse(testutil::read_bytes(tmp.file("r.json")));
  EXPECT_EQ(rep["topology_control"]["cavities_filled"], 2);
  EXPECT_EQ(rep["topology_control"]["largest_cavity_filled"], 125);
}

// --max-handle on the MRI scalp (avg152T1 at iso 10.5, issue 12's example): ~770 handles of
// noise around one head. With the small components and cavities gone and the handles shorter
// than 12 voxels cut, one surface is left, with a handful of handles, and --triangles 5000 is
// reached (without --max-handle it is out of reach: 14,307 triangles at χ −1534).
TEST(TopologyControl, MaxHandleCleansTheMriScalp) {
  ADAMESH_REQUIRE_SHARED_DATA(data);
  TempDir tmp;
  const std::string in = data + "/mri_avg152T1/avg152T1_RL_nifti.nii.gz --iso 10.5 --triangles 5000 " +
                         "--min-component 400 --min-cavity 1000 -o " + tmp.file("a.ply") +
                         " --report " + tmp.file("r.json");
  const auto plain = run_cli("extract " + in);
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const auto t0 = mesh_topo(read_mesh(tmp.file("a.ply")));
  const long genus0 = (2 * t0.components - t0.boundary_loops - t0.chi) / 2;
  EXPECT_GT(genus0, 500);
  EXPECT_NE(plain.err.find("--max-handle L cuts handles"), std::string::npos) << plain.err;
  const auto r = run_cli("extract " + in + " --max-handle 12");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE((r.out + r.err).find("handles ("), std::string::npos) << r.out;
  const Mesh a = read_mesh(tmp.file("a.ply"));
  const auto t = mesh_topo(a);
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.nonmanifold_edges, 0);
  const long genus = (2 * t.components - t.boundary_loops - t.chi) / 2;
  EXPECT_LE(genus, 4);
  EXPECT_LE(a.num_triangles(), 5000u);
  EXPECT_GE(a.num_triangles(), 4950u);
  const auto rep = nlohmann::json::parse(testutil::read_bytes(tmp.file("r.json")));
  const auto& tc = rep["topology_control"];
  EXPECT_GT(tc["handles_cut"].get<long>(), 100);
  EXPECT_GT(tc["tunnels_filled"].get<long>(), 50);
  EXPECT_NEAR(tc["max_handle_radius"].get<double>(), 12 / (2 * 3.141592653589793), 1e-9);
  EXPECT_EQ(run_cli("extract " + in + " --max-handle -2").exit_code, 1);
}

}  // namespace
}  // namespace adamesh

namespace adamesh {
namespace {

// `level --improve`: a cut of the stored hierarchy improved without the volume keeps its count
// (± 1) and topology and has fewer slivers than the plain cut.
TEST(LevelImprove, KeepsCountAndTopologyAndRemovesSlivers) {
  TempDir tmp;
  const std::string head = testutil::source_dir() + "/data/ct_headsq/quarter.nhdr --iso 500.5";
  ASSERT_EQ(run_cli("extract " + head + " --hierarchy " + tmp.file("h.amh") + " --quiet").exit_code, 0);
  ASSERT_EQ(run_cli("level " + tmp.file("h.amh") + " --triangles 30000 -o " + tmp.file("a.ply") +
                    " --quiet").exit_code, 0);
  ASSERT_EQ(run_cli("level " + tmp.file("h.amh") + " --triangles 30000 --improve -o " +
                    tmp.file("b.ply") + " --quiet").exit_code, 0);
  const Mesh a = read_mesh(tmp.file("a.ply")), b = read_mesh(tmp.file("b.ply"));
  EXPECT_LE(b.num_triangles(), a.num_triangles());
  EXPECT_GE(b.num_triangles() + 1, a.num_triangles());
  const auto ta = mesh_topo(a), tb = mesh_topo(b);
  EXPECT_EQ(ta.chi, tb.chi);
  EXPECT_EQ(ta.components, tb.components);
  EXPECT_EQ(ta.boundary_loops, tb.boundary_loops);
  auto pct = [&](const std::string& f) {
    const auto s = run_cli("stats " + f + " --json");
    return nlohmann::json::parse(s.out)["pct_min_angle_below"]["20"].get<double>();
  };
  const double before = pct(tmp.file("a.ply")), after = pct(tmp.file("b.ply"));
  EXPECT_GT(before, 3.0);
  EXPECT_LT(after, 1.0);
  // The separation ran last and says how many intersecting pairs it left: the mesh's count.
  const auto said = run_cli("level " + tmp.file("h.amh") + " --triangles 30000 --improve -o " +
                            tmp.file("c.ply"));
  const auto at = said.out.find("intersecting triangle pairs ");
  ASSERT_NE(at, std::string::npos) << said.out;
  const std::size_t arrow = said.out.find(" -> ", at);
  ASSERT_NE(arrow, std::string::npos);
  const long from = std::stol(said.out.substr(at + 28)), left = std::stol(said.out.substr(arrow + 4));
  EXPECT_LT(left, from);
  const auto st = run_cli("stats " + tmp.file("c.ply") + " --json");
  EXPECT_EQ(left, nlohmann::json::parse(st.out)["self_intersecting_pairs"].get<long>());
}

}  // namespace
}  // namespace adamesh
