// Tests for load_input() (implicit sampling, files, inside conventions, NaN/Inf policy) and for
// the `adamesh info` command (text and JSON output, errors), run through the real CLI.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <vector>

#include "adamesh/error.h"
#include "adamesh/input.h"
#include "adamesh/stats.h"
#include "testing.h"

using namespace adamesh;
using testutil::run_cli;

namespace {

/// Shell-quoted path (built with += : GCC 12 warns falsely (-Wrestrict) on "'" + std::string).
std::string quoted(const std::string& path) {
  std::string q = "'";
  q += path;
  q += "'";
  return q;
}

std::string ct_head() { return testutil::source_dir() + "/data/ct_headsq/quarter.nhdr"; }

/// A little-endian float32 raw file of dims d with the given values.
std::string write_float_raw(const testutil::TempDir& dir, const std::string& name,
                            const std::vector<float>& values) {
  std::string bytes(values.size() * 4, '\0');
  std::memcpy(bytes.data(), values.data(), bytes.size());
  const std::string path = dir.file(name);
  testutil::write_bytes(path, bytes);
  return path;
}

InputOptions raw_float(std::int64_t x, std::int64_t y, std::int64_t z) {
  InputOptions o;
  o.raw.dims = std::array<std::int64_t, 3>{x, y, z};
  o.raw.type = ScalarType::f32;
  return o;
}

std::string error_of(const std::function<void()>& f, Status* status = nullptr) {
  try {
    f();
  } catch (const Error& e) {
    if (status) *status = e.status();
    return e.what();
  }
  return "(no error)";
}

nlohmann::json info_json(const std::string& args) {
  const auto r = run_cli("info " + args + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// load_input: implicit inputs

TEST(LoadInput, ShapeDefaults) {
  const Input in = load_input("shape:sphere");
  const Grid& g = in.volume->grid;
  EXPECT_EQ(g.dims, (std::array<std::int64_t, 3>{64, 64, 64}));
  EXPECT_DOUBLE_EQ(g.spacing.x, 2.0 / 63);
  EXPECT_NEAR(g.origin.x, -1, 1e-15);
  EXPECT_NEAR(g.world_bounds().hi.z, 1, 1e-12);
  EXPECT_EQ(in.inside_sign, -1);
  EXPECT_EQ(in.default_iso, 0.0);
  EXPECT_EQ(in.volume->type, ScalarType::f32);
  EXPECT_EQ(in.volume->format, "implicit");
  EXPECT_EQ(in.spec, "shape:sphere");
  ASSERT_TRUE(in.field);
  EXPECT_TRUE(in.field->is_analytic());
  // The samples are the exact field at the grid points.
  for (std::int64_t k : {0, 17, 63})
    for (std::int64_t i : {0, 31, 50}) {
      const Vec3 p = g.to_world({double(i), 20.0, double(k)});
      EXPECT_EQ(in.volume->at(i, 20, k), static_cast<float>(in.field->value(p)));
    }
}

TEST(LoadInput, ResolutionAndBoundsGiveDimsAndSpacing) {
  InputOptions o;
  o.resolution = 33;
  o.bounds = Box{{-1, -1, -0.5}, {1, 1, 0.5}};
  const Input a = load_input("shape:torus", o);
  EXPECT_EQ(a.volume->grid.dims, (std::array<std::int64_t, 3>{33, 33, 17}));
  EXPECT_DOUBLE_EQ(a.volume->grid.spacing.z, 0.0625);
  // Extent 0.73 along y with h = 0.1: round(7.3) + 1 = 8 samples, centred in the box.
  o.resolution = 11;
  o.bounds = Box{{0, 0, 0}, {1, 0.73, 0.5}};
  const Input b = load_input("expr:x+y+z", o);
  const Grid& g = b.volume->grid;
  EXPECT_EQ(g.dims, (std::array<std::int64_t, 3>{11, 8, 6}));
  EXPECT_NEAR(g.spacing.y, 0.1, 1e-15);
  EXPECT_NEAR(g.origin.y, 0.015, 1e-12);
  EXPECT_NEAR(g.origin.x, 0, 1e-15);
  const Box d = b.field->domain();
  EXPECT_NEAR(d.lo.y, 0.015, 1e-12);
  EXPECT_NEAR(d.hi.y, 0.715, 1e-12);
  EXPECT_NEAR(b.volume->at(10, 7, 5), 1 + 0.715 + 0.5, 1e-6);
}

TEST(LoadInput, ExpressionsAndFlip) {
  const Input e = load_input("expr:'x^2 + y^2 + z^2 - 0.25'");  // quotes kept by a non-shell caller
  EXPECT_EQ(e.inside_sign, -1);
  EXPECT_EQ(e.default_iso, 0.0);
  EXPECT_EQ(e.volume->grid.dims[0], 64);
  EXPECT_NEAR(e.field->value({0.5, 0, 0}), 0, 1e-15);
  InputOptions flip;
  flip.flip_inside = true;
  EXPECT_EQ(load_input("shape:gyroid", flip).inside_sign, +1);
  EXPECT_EQ(load_input(ct_head(), flip).inside_sign, -1);
}

TEST(LoadInput, BadImplicitInputs) {
  Status st{};
  std::string m = error_of([] { load_input("shape:cylinder"); }, &st);
  EXPECT_EQ(st, Status::invalid_input);
  EXPECT_EQ(m.rfind("shape:cylinder: unknown shape (valid: sphere, torus", 0), 0u) << m;
  m = error_of([] { load_input("expr:x+"); }, &st);
  EXPECT_EQ(st, Status::invalid_input);
  EXPECT_EQ(m.rfind("expr:'x+': ", 0), 0u) << m;
  InputOptions o;
  o.resolution = 1;
  m = error_of([&] { load_input("shape:sphere", o); }, &st);
  EXPECT_EQ(st, Status::usage);
  EXPECT_NE(m.find("resolution"), std::string::npos) << m;
  o.resolution = 0;
  o.bounds = Box{{0, 0, 0}, {1, 0, 1}};
  m = error_of([&] { load_input("shape:sphere", o); }, &st);
  EXPECT_NE(m.find("bounds"), std::string::npos) << m;
}

// ---------------------------------------------------------------------------------------------
// load_input: files

TEST(LoadInput, VolumeFileAndMovedInputs) {
  Input in = load_input(ct_head());
  EXPECT_EQ(in.inside_sign, +1);
  EXPECT_FALSE(in.default_iso);
  EXPECT_EQ(in.volume->grid.dims, (std::array<std::int64_t, 3>{64, 64, 93}));
  ASSERT_TRUE(in.field);
  EXPECT_FALSE(in.field->is_analytic());
  const Vec3 p = in.volume->grid.to_world({30, 31, 40});
  const double expected = in.volume->at(30, 31, 40);
  EXPECT_EQ(in.field->value(p), expected);
  // Moving (or copying) the Input never leaves the field reading freed memory.
  std::vector<Input> many;
  many.push_back(std::move(in));
  for (int i = 0; i < 8; ++i) many.push_back(many.back());
  many.erase(many.begin(), many.end() - 1);
  EXPECT_EQ(many.back().field->value(p), expected);
  auto field = many.back().field;
  many.clear();
  EXPECT_EQ(field->value(p), expected);
}

TEST(LoadInput, NonFiniteSamplesPolicy) {
  testutil::TempDir dir;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  // 3x2x2 volume with NaN at (1,0,0) and +Inf at (2,1,1).
  std::vector<float> v(12, 1.0f);
  v[1] = nan;
  v[11] = inf;
  const std::string path = write_float_raw(dir, "holes.raw", v);

  Status st{};
  const std::string m = error_of([&] { load_input(path, raw_float(3, 2, 2)); }, &st);
  EXPECT_EQ(st, Status::invalid_input);
  EXPECT_EQ(m, path + ": 2 NaN/Inf samples (first at voxel 1,0,0); use --nan-value V to replace them");

  InputOptions o = raw_float(3, 2, 2);
  o.nan_value = -5;
  const Input fixed = load_input(path, o);
  EXPECT_EQ(fixed.nonfinite_samples, 2);
  EXPECT_EQ(fixed.volume->at(1, 0, 0), -5);
  EXPECT_EQ(fixed.volume->at(2, 1, 1), -5);
  EXPECT_EQ(fixed.volume->at(0, 0, 0), 1);

  o = raw_float(3, 2, 2);
  o.keep_nonfinite = true;
  const Input kept = load_input(path, o);
  EXPECT_EQ(kept.nonfinite_samples, 2);
  EXPECT_TRUE(std::isnan(kept.volume->at(1, 0, 0)));
  EXPECT_EQ(compute_stats(*kept.volume).nonfinite, 2);

  o.nan_value = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(error_of([&] { load_input(path, o); }).find("--nan-value"), std::string::npos);

  // Implicit inputs are checked the same way.
  const std::string me = error_of([] { load_input("expr:sqrt(x)"); });
  EXPECT_EQ(me.rfind("expr:sqrt(x): ", 0), 0u) << me;
  EXPECT_NE(me.find("NaN/Inf samples (first at voxel 0,0,0)"), std::string::npos) << me;
}

TEST(LoadInput, MissingFileNamesIt) {
  Status st{};
  const std::string m = error_of([] { load_input("/nonexistent/dir/head.nrrd"); }, &st);
  EXPECT_EQ(st, Status::invalid_input);
  EXPECT_NE(m.find("/nonexistent/dir/head.nrrd"), std::string::npos) << m;
}

// ---------------------------------------------------------------------------------------------
// adamesh info

TEST(InfoCli, JsonForCtHead) {
  const nlohmann::json j = info_json(quoted(ct_head()));
  for (const char* key : {"format", "dims", "type", "spacing", "origin", "direction", "range",
                          "percentiles", "suggested_iso", "nonfinite", "bounds", "inside"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["format"], "NRRD");
  EXPECT_EQ(j["dims"], nlohmann::json({64, 64, 93}));
  EXPECT_EQ(j["type"], "int16");
  EXPECT_EQ(j["spacing"], nlohmann::json({3.2, 3.2, 1.5}));
  EXPECT_EQ(j["origin"], nlohmann::json({0.0, 0.0, 0.0}));
  EXPECT_EQ(j["direction"], nlohmann::json({{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}}));
  EXPECT_EQ(j["range"], nlohmann::json({0.0, 3926.0}));
  EXPECT_EQ(j["nonfinite"], 0);
  EXPECT_EQ(j["inside"], "f >= iso");
  EXPECT_TRUE(j["default_iso"].is_null());
  EXPECT_NEAR(j["bounds"][1][0].get<double>(), 63 * 3.2, 1e-9);
  EXPECT_NEAR(j["bounds"][1][2].get<double>(), 92 * 1.5, 1e-9);

  // Percentiles: exact nearest-rank values, checked against a sort of the samples.
  const Input in = load_input(ct_head());
  std::vector<double> all(in.volume->grid.num_samples());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = in.volume->at(std::int64_t(i));
  std::sort(all.begin(), all.end());
  for (int level : {1, 5, 25, 50, 75, 95, 99}) {
    const std::size_t rank = std::max<std::size_t>(1, (level * all.size() + 99) / 100);
    EXPECT_EQ(j["percentiles"][std::to_string(level)].get<double>(), all[rank - 1]) << level;
  }
  const double iso = j["suggested_iso"].get<double>();
  EXPECT_EQ(iso - std::floor(iso), 0.5);
  // Otsu separates air/background from tissue: between the median and the 99th percentile.
  EXPECT_GT(iso, j["percentiles"]["50"].get<double>());
  EXPECT_LT(iso, j["percentiles"]["99"].get<double>());
}

TEST(InfoCli, JsonForShape) {
  const nlohmann::json j = info_json("shape:torus");
  EXPECT_EQ(j["format"], "implicit");
  EXPECT_EQ(j["dims"], nlohmann::json({64, 64, 64}));
  EXPECT_EQ(j["type"], "float32");
  EXPECT_EQ(j["default_iso"], 0.0);
  EXPECT_EQ(j["inside"], "f <= iso");
  EXPECT_EQ(j["analytic"], true);
  // min: −r on the ring (within a sample spacing); max: at the box corners.
  const double h = 2.0 / 63;
  EXPECT_NEAR(j["range"][0].get<double>(), -0.25, h);
  EXPECT_GE(j["range"][0].get<double>(), -0.25);
  EXPECT_NEAR(j["range"][1].get<double>(), std::hypot(std::sqrt(2.0) - 0.6, 1.0) - 0.25, 1e-6);
  EXPECT_NEAR(j["bounds"][0][0].get<double>(), -1, 1e-12);
  const nlohmann::json f = info_json("shape:torus --flip --res 20 --bounds -1,-1,-0.5,1,1,0.5");
  EXPECT_EQ(f["inside"], "f >= iso");
  EXPECT_EQ(f["dims"], nlohmann::json({20, 20, 11}));
  const nlohmann::json e = info_json("expr:'x - 0.25'");
  EXPECT_NEAR(e["range"][0].get<double>(), -1.25, 1e-6);
  EXPECT_NEAR(e["range"][1].get<double>(), 0.75, 1e-6);
  EXPECT_NEAR(e["percentiles"]["50"].get<double>(), -0.25, 2.0 / 63);
}

TEST(InfoCli, TextOutput) {
  const auto r = run_cli("info " + quoted(ct_head()));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  for (const char* s : {"format         NRRD", "dims           64 x 64 x 93", "type           int16",
                        "spacing        3.2 3.2 1.5", "range          0 .. 3926", "suggested iso",
                        "(Otsu)", "inside         f >= iso", "NaN/Inf        0", "percentiles    1%: "})
    EXPECT_NE(r.out.find(s), std::string::npos) << s << "\n" << r.out;
  const auto s = run_cli("info shape:wavy_sheet");
  ASSERT_EQ(s.exit_code, 0) << s.err;
  EXPECT_NE(s.out.find("default iso    0"), std::string::npos) << s.out;
  EXPECT_NE(s.out.find("inside         f <= iso"), std::string::npos) << s.out;
  const auto h = run_cli("info --help");
  EXPECT_EQ(h.exit_code, 0);
  EXPECT_NE(h.out.find("--json"), std::string::npos);
  EXPECT_NE(h.out.find("--nan-value"), std::string::npos);
}

TEST(InfoCli, NonFiniteSamplesAreReported) {
  testutil::TempDir dir;
  std::vector<float> v(8, 2.0f);
  v[3] = std::numeric_limits<float>::quiet_NaN();
  v[0] = 1.0f;
  const std::string path = write_float_raw(dir, "nan.raw", v);
  const nlohmann::json j = info_json(quoted(path) + " --dims 2,2,2 --type float32");
  EXPECT_EQ(j["nonfinite"], 1);
  EXPECT_EQ(j["range"], nlohmann::json({1.0, 2.0}));
  const nlohmann::json r = info_json(quoted(path) + " --dims 2,2,2 --type float32 --nan-value 0");
  EXPECT_EQ(r["nonfinite"], 1);
  EXPECT_EQ(r["range"], nlohmann::json({0.0, 2.0}));
}

TEST(InfoCli, ErrorsAreOneLineWithExitCodes) {
  const auto missing = run_cli("info /nonexistent/skull.nrrd");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_TRUE(missing.out.empty());
  EXPECT_EQ(std::count(missing.err.begin(), missing.err.end(), '\n'), 1) << missing.err;
  EXPECT_EQ(missing.err.rfind("adamesh: /nonexistent/skull.nrrd: ", 0), 0u) << missing.err;

  const auto shape = run_cli("info shape:blob --json");
  EXPECT_EQ(shape.exit_code, 2);
  EXPECT_NE(shape.err.find("shape:blob: unknown shape (valid: "), std::string::npos) << shape.err;
  EXPECT_EQ(std::count(shape.err.begin(), shape.err.end(), '\n'), 1) << shape.err;

  const auto expr = run_cli("info 'expr:sin(x'");
  EXPECT_EQ(expr.exit_code, 2);
  EXPECT_EQ(expr.err.rfind("adamesh: expr:'sin(x': ", 0), 0u) << expr.err;

  EXPECT_EQ(run_cli("info").exit_code, 1);
  EXPECT_EQ(run_cli("info shape:sphere --bogus").exit_code, 1);
  EXPECT_EQ(run_cli("info shape:sphere shape:torus").exit_code, 1);
}
