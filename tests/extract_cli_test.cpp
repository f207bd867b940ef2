// `adamesh extract` end to end: outputs, report keys, determinism across runs and thread counts,
// bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "testing.h"

using namespace adamesh::testutil;

TEST(ExtractCli, WritesBaseMeshAndReport) {
  TempDir tmp;
  const auto r = run_cli("extract shape:torus --res 48 --base " + tmp.file("b.ply") + " --report " +
                         tmp.file("r.json") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(read_bytes(tmp.file("r.json")));
  for (const char* k : {"input", "iso", "graph", "base", "fallback_components", "timings_s",
                        "peak_rss_mb"})
    EXPECT_TRUE(j.contains(k)) << k;
  for (const char* k : {"cvertices", "edges"}) EXPECT_TRUE(j["graph"].contains(k)) << k;
  for (const char* k : {"vertices", "triangles", "euler", "components", "boundary_loops"})
    EXPECT_TRUE(j["base"].contains(k)) << k;
  for (const char* k : {"read", "surfels", "graph", "disk_cover", "voronoi", "dual", "write"})
    EXPECT_TRUE(j["timings_s"].contains(k)) << k;
  EXPECT_EQ(j["base"]["euler"], 0);
  EXPECT_EQ(j["base"]["components"], 1);
  EXPECT_EQ(j["base"]["boundary_loops"], 0);
  EXPECT_GT(j["peak_rss_mb"].get<double>(), 0.0);
  EXPECT_TRUE(std::filesystem::file_size(tmp.file("b.ply")) > 100);
}

TEST(ExtractCli, IdenticalBytesAcrossRunsAndThreads) {
  TempDir tmp;
  const std::string base = "extract shape:genus2 --res 64 --quiet --base ";
  ASSERT_EQ(run_cli(base + tmp.file("a.ply") + " --threads 1").exit_code, 0);
  ASSERT_EQ(run_cli(base + tmp.file("b.ply") + " --threads 2").exit_code, 0);
  ASSERT_EQ(run_cli(base + tmp.file("c.ply") + " --threads 2").exit_code, 0);
  EXPECT_EQ(read_bytes(tmp.file("a.ply")), read_bytes(tmp.file("b.ply")));
  EXPECT_EQ(read_bytes(tmp.file("b.ply")), read_bytes(tmp.file("c.ply")));
  const std::string head = source_dir() + "/data/ct_headsq/quarter.nhdr";
  const std::string h = "extract '" + head + "' --iso 500.5 --quiet --base ";
  ASSERT_EQ(run_cli(h + tmp.file("h1.ply") + " --threads 1").exit_code, 0);
  ASSERT_EQ(run_cli(h + tmp.file("h2.ply") + " --threads 2").exit_code, 0);
  EXPECT_EQ(read_bytes(tmp.file("h1.ply")), read_bytes(tmp.file("h2.ply")));
}

TEST(ExtractCli, BadInputGivesOneLineAndNoFile) {
  TempDir tmp;
  const std::string head = source_dir() + "/data/ct_headsq/quarter.nhdr";
  auto r = run_cli("extract '" + head + "' --iso 99999 --base " + tmp.file("x.ply"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("outside the value range"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("quarter.nhdr"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp.file("x.ply")));

  r = run_cli("extract '" + head + "' --base " + tmp.file("x.ply") + " --quiet");
  EXPECT_EQ(r.exit_code, 1);  // volume files need --iso
  EXPECT_NE(r.err.find("--iso"), std::string::npos) << r.err;

  r = run_cli("extract shape:sphere --res 32 --quiet --base " + tmp.file("no/such/dir/x.ply"));
  EXPECT_EQ(r.exit_code, 4);
  EXPECT_NE(r.err.find("x.ply"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;

  r = run_cli("extract " + tmp.file("missing.nrrd") + " --iso 1 --quiet --base " + tmp.file("x.ply"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing.nrrd"), std::string::npos) << r.err;
}
