// `adamesh stats`: JSON keys and values on known meshes, --field with an analytic shape and with a
// raw volume (input options passed through), --reference, text output and usage errors.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "adamesh/io.h"
#include "metrics_test_meshes.h"
#include "testing.h"

using namespace adamesh;
using adamesh::testutil::run_cli;
using adamesh::testutil::TempDir;
using nlohmann::json;

namespace {

json parse(const std::string& text) {
  try {
    return json::parse(text);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not JSON: " << e.what() << "\n" << text.substr(0, 400);
    return json::object();
  }
}

}  // namespace

TEST(StatsCli, JsonHasEveryKeyWithTheCubesNumbers) {
  TempDir tmp;
  write_mesh(testmesh::cube(), tmp.file("cube.ply"));
  const auto r = run_cli("stats '" + tmp.file("cube.ply") + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = parse(r.out);
  for (const char* key :
       {"vertices", "edges", "triangles", "euler", "components", "boundary_loops", "genus",
        "genus_per_component", "nonmanifold_edges", "nonmanifold_vertices", "degenerate_triangles",
        "duplicate_triangles", "oriented", "min_angle_deg", "pct_min_angle_below", "max_angle_deg",
        "q_hist", "q_mean", "distance", "eps_e", "eps_n", "hausdorff", "area", "volume"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["vertices"], 8);
  EXPECT_EQ(j["edges"], 18);
  EXPECT_EQ(j["triangles"], 12);
  EXPECT_EQ(j["euler"], 2);
  EXPECT_EQ(j["components"], 1);
  EXPECT_EQ(j["boundary_loops"], 0);
  EXPECT_EQ(j["genus"], 0);
  EXPECT_EQ(j["genus_per_component"], json::array({0}));
  EXPECT_EQ(j["oriented"], true);
  EXPECT_NEAR(j["area"].get<double>(), 6, 1e-12);
  EXPECT_NEAR(j["volume"].get<double>(), 1, 1e-12);
  for (const char* k : {"min", "p1", "p5", "median"}) EXPECT_NEAR(j["min_angle_deg"][k].get<double>(), 45, 1e-9);
  EXPECT_NEAR(j["max_angle_deg"].get<double>(), 90, 1e-9);
  for (const char* k : {"10", "20", "30"}) EXPECT_EQ(j["pct_min_angle_below"][k], 0.0);
  ASSERT_EQ(j["q_hist"].size(), 20u);
  EXPECT_EQ(j["q_hist"][16], 12);
  EXPECT_TRUE(j["distance"].is_null());
  EXPECT_TRUE(j["eps_e"].is_null());
  EXPECT_TRUE(j["hausdorff"].is_null());
}

TEST(StatsCli, OpenMeshHasNullVolumeAndTextOutput) {
  TempDir tmp;
  write_mesh(testmesh::from({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}}),
             tmp.file("sq.obj"));
  const auto r = run_cli("stats '" + tmp.file("sq.obj") + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = parse(r.out);
  EXPECT_TRUE(j["volume"].is_null());
  EXPECT_EQ(j["boundary_loops"], 1);
  EXPECT_EQ(j["genus_per_component"], json::array({0}));  // a disk
  const auto t = run_cli("stats '" + tmp.file("sq.obj") + "'");
  ASSERT_EQ(t.exit_code, 0) << t.err;
  EXPECT_NE(t.out.find("euler 1"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("boundary loops 1"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("not closed"), std::string::npos) << t.out;
}

TEST(StatsCli, FieldAndReference) {
  TempDir tmp;
  write_mesh(testmesh::icosphere(4, 0.8), tmp.file("ico.ply"));
  write_mesh(testmesh::icosphere(4, 0.9), tmp.file("ico2.ply"));
  // shape:sphere is the sphere of radius 0.8 (PEERS.md); its default iso is 0.
  const auto r = run_cli("stats '" + tmp.file("ico.ply") + "' --field shape:sphere --reference '" +
                         tmp.file("ico2.ply") + "' --samples 20000 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = parse(r.out);
  ASSERT_TRUE(j["distance"].is_object()) << r.out;
  for (const char* k : {"mean", "rms", "max", "p99", "mean_rel", "rms_rel", "max_rel", "p99_rel"})
    EXPECT_TRUE(j["distance"][k].is_number()) << k;
  EXPECT_EQ(j["distance"]["samples"], 20000);
  EXPECT_GT(j["distance"]["max"].get<double>(), 0);
  EXPECT_LT(j["distance"]["max"].get<double>(), 0.01);  // level-4 chord error of r = 0.8
  EXPECT_GT(j["eps_n"].get<double>(), 0);
  EXPECT_LT(j["eps_n"].get<double>(), 0.01);  // outward mesh, outward field normal
  EXPECT_GT(j["eps_e"].get<double>(), 0);
  ASSERT_TRUE(j["hausdorff"].is_object());
  EXPECT_NEAR(j["hausdorff"]["symmetric"].get<double>(), 0.1, 0.005);
  EXPECT_NEAR(j["hausdorff"]["a_to_b"].get<double>(), 0.1, 0.005);
  EXPECT_NEAR(j["hausdorff"]["b_to_a"].get<double>(), 0.1, 0.005);
  EXPECT_TRUE(j["hausdorff"]["a_to_b_mean"].is_number());
}

TEST(StatsCli, RawVolumeFieldWithInputOptions) {
  // A ball in a 24³ uint8 volume (bright inside): `mc` then `stats --field` on the same input.
  TempDir tmp;
  const int n = 24;
  std::string bytes(n * n * n, '\0');
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double d = std::sqrt((i - 11.3) * (i - 11.3) + (j - 11.6) * (j - 11.6) + (k - 11.1) * (k - 11.1));
        bytes[i + n * (j + n * k)] = static_cast<char>(std::clamp(200.0 - 20.0 * d, 0.0, 255.0));
      }
  testutil::write_bytes(tmp.file("ball.raw"), bytes);
  std::string in = "'";  // built by appending: GCC 12 warns (-Wrestrict) on "'" + std::string
  in += tmp.file("ball.raw");
  in += "' --dims 24,24,24 --type uint8 --spacing 0.5,0.5,0.5";
  const auto mc = run_cli("mc " + in + " --iso 100.5 -o '" + tmp.file("ball.ply") + "' --quiet");
  ASSERT_EQ(mc.exit_code, 0) << mc.err;
  const auto r = run_cli("stats '" + tmp.file("ball.ply") + "' --field " + in + " --iso 100.5 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = parse(r.out);
  EXPECT_EQ(j["genus"], 0);
  EXPECT_EQ(j["nonmanifold_edges"], 0);
  ASSERT_TRUE(j["distance"].is_object()) << r.out;
  // Marching cubes vertices lie on the trilinear surface; triangle interiors stay well within
  // a voxel (0.5) of it, and the mesh faces out of the bright inside.
  EXPECT_LT(j["distance"]["max"].get<double>(), 0.1);
  EXPECT_LT(j["eps_n"].get<double>(), 0.05);
  EXPECT_EQ(j["vertices_outside_volume"], 0);  // marching cubes stays inside
  EXPECT_EQ(j["outside_volume_max_voxels"], 0.0);
  // A vertex 0.3 (0.6 voxel) beyond the x = 0 face: counted, and how far.
  testutil::write_bytes(tmp.file("out.off"), "OFF\n3 1 0\n-0.3 5 5\n5 5 5\n5 6 5\n3 0 1 2\n");
  const auto o = run_cli("stats '" + tmp.file("out.off") + "' --field " + in + " --iso 100.5 --json");
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const json k = parse(o.out);
  EXPECT_EQ(k["vertices_outside_volume"], 1);
  EXPECT_NEAR(k["outside_volume_max_voxels"].get<double>(), 0.6, 1e-5);
  const auto t = run_cli("stats '" + tmp.file("out.off") + "' --field " + in + " --iso 100.5");
  EXPECT_NE(t.out.find("1 vertex outside the volume's grid, the farthest 0.6 voxel"),
            std::string::npos) << t.out;
  // Without --iso a volume file has no default: usage error naming the input.
  const auto u = run_cli("stats '" + tmp.file("ball.ply") + "' --field " + in);
  EXPECT_EQ(u.exit_code, 1);
  EXPECT_NE(u.err.find("no default iso-value"), std::string::npos) << u.err;
}

TEST(StatsCli, Errors) {
  TempDir tmp;
  auto r = run_cli("stats '" + tmp.file("missing.ply") + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(tmp.file("missing.ply") + ": no such file"), std::string::npos) << r.err;
  write_mesh(testmesh::cube(), tmp.file("cube.off"));
  r = run_cli("stats '" + tmp.file("cube.off") + "' --iso 3");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--iso needs --field"), std::string::npos) << r.err;
  r = run_cli("stats");
  EXPECT_EQ(r.exit_code, 1);
  r = run_cli("stats '" + tmp.file("cube.off") + "' --samples -5");
  EXPECT_EQ(r.exit_code, 1);
  r = run_cli("stats '" + tmp.file("cube.off") + "' --field shape:nonexistent");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  r = run_cli("stats --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("--reference"), std::string::npos);
}
