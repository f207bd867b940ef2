#include <filesystem>
#include <fstream>

#include "adamesh/atomic_file.h"
#include "adamesh/error.h"
#include "adamesh/volume.h"
#include "testing.h"

using namespace adamesh;

TEST(Grid, WorldMappingWithSpacingOriginAndDirection) {
  Grid g;
  g.dims = {4, 5, 6};
  g.spacing = {2, 3, 4};
  g.origin = {10, 20, 30};
  // Index axes rotated: i -> +y, j -> -x, k -> +z.
  g.direction = Mat3::from_columns({0, 1, 0}, {-1, 0, 0}, {0, 0, 1});
  const Vec3 w = g.to_world({1, 1, 1});
  EXPECT_DOUBLE_EQ(w.x, 10 - 3);
  EXPECT_DOUBLE_EQ(w.y, 20 + 2);
  EXPECT_DOUBLE_EQ(w.z, 30 + 4);
  const Vec3 back = g.to_index(w);
  EXPECT_NEAR(back.x, 1, 1e-12);
  EXPECT_NEAR(back.y, 1, 1e-12);
  EXPECT_NEAR(back.z, 1, 1e-12);
  EXPECT_DOUBLE_EQ(g.min_spacing(), 2);
  const Box b = g.world_bounds();
  EXPECT_DOUBLE_EQ(b.lo.x, 10 - 3 * 4);
  EXPECT_DOUBLE_EQ(b.hi.y, 20 + 2 * 3);
  EXPECT_FALSE(g.axis_aligned());
}

TEST(Volume, CheckedBytesRejectsBadDims) {
  EXPECT_EQ(checked_volume_bytes({2, 3, 4}, ScalarType::i16, "x"), 48u);
  auto expect_fail = [](std::array<std::int64_t, 3> d, const char* needle) {
    try {
      checked_volume_bytes(d, ScalarType::f64, "vol.raw");
      ADD_FAILURE() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::invalid_input);
      EXPECT_NE(std::string(e.what()).find("vol.raw: "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  expect_fail({0, 3, 4}, "at least 1");
  expect_fail({-1, 3, 4}, "at least 1");
  expect_fail({1ll << 40, 1ll << 40, 1ll << 40}, "overflow");
  expect_fail({100000, 100000, 100000}, "memory");
}

TEST(Volume, ScalarTypeNames) {
  EXPECT_EQ(parse_scalar_type("short"), ScalarType::i16);
  EXPECT_EQ(parse_scalar_type("unsigned char"), ScalarType::u8);
  EXPECT_EQ(parse_scalar_type("Float"), ScalarType::f32);
  EXPECT_EQ(parse_scalar_type("uint16_t"), ScalarType::u16);
  EXPECT_FALSE(parse_scalar_type("complex"));
  EXPECT_EQ(scalar_size(ScalarType::f64), 8u);
  Volume v = allocate_volume(Grid{{2, 2, 2}}, ScalarType::i16, "t");
  for (int i = 0; i < 8; ++i) v.samples<std::int16_t>()[i] = static_cast<std::int16_t>(i - 4);
  EXPECT_EQ(v.at(1, 1, 1), 3.0);
  EXPECT_EQ(v.at(0), -4.0);
}

TEST(AtomicFile, WritesAndReplaces) {
  testutil::TempDir tmp;
  const std::string p = tmp.file("a.txt");
  write_file_atomically(p, [](std::ostream& o) { o << "hello"; });
  EXPECT_EQ(testutil::read_bytes(p), "hello");
  write_file_atomically(p, [](std::ostream& o) { o << "bye"; });
  EXPECT_EQ(testutil::read_bytes(p), "bye");
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(tmp.path()), {}), 1);
}

TEST(AtomicFile, FailureLeavesNothingBehind) {
  testutil::TempDir tmp;
  const std::string p = tmp.file("b.txt");
  EXPECT_THROW(write_file_atomically(p,
                                     [](std::ostream& o) {
                                       o << "partial";
                                       throw Error(Status::internal, "writer failed");
                                     }),
               Error);
  EXPECT_FALSE(std::filesystem::exists(p));
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(tmp.path()), {}), 0);
  try {
    write_file_atomically(tmp.file("no/such/dir/c.txt"), [](std::ostream& o) { o << "x"; });
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::output_failed);
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos);
  }
}

TEST(Cli, UnknownCommandFails) {
  auto r = testutil::run_cli("frobnicate");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("unknown command"), std::string::npos);
  auto v = testutil::run_cli("--version");
  EXPECT_EQ(v.exit_code, 0);
  EXPECT_NE(v.out.find("adamesh"), std::string::npos);
}
