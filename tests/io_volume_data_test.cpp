// Real data: every dataset of ../shared/data/manifest.json loads with the manifest's
// dimensions, voxel type, spacing, origin, value range and 1/50/99 percentiles; the MC33
// NRRD headers and the bundled CT head load too. Skips when ../shared/data is absent.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "io_volume_test_util.h"

namespace adamesh {
namespace {

using namespace testutil;

// Value of rank k (0-based) in sorted order.
class Ranks {
 public:
  explicit Ranks(const Volume& v) : n_(static_cast<std::size_t>(v.grid.num_samples())) {
    if (scalar_size(v.type) <= 2 && !is_floating(v.type)) {
      hist_.assign(65536, 0);
      for (std::size_t i = 0; i < n_; ++i) ++hist_[static_cast<std::size_t>(v.at(static_cast<std::int64_t>(i)) + 32768)];
    } else {
      sorted_.resize(n_);
      for (std::size_t i = 0; i < n_; ++i) sorted_[i] = v.at(static_cast<std::int64_t>(i));
      std::sort(sorted_.begin(), sorted_.end());
    }
  }
  double kth(std::size_t k) const {
    if (!sorted_.empty()) return sorted_[k];
    std::size_t seen = 0;
    for (std::size_t b = 0; b < hist_.size(); ++b) {
      seen += hist_[b];
      if (seen > k) return double(b) - 32768;
    }
    return NAN;
  }
  /// numpy.percentile with linear interpolation.
  double percentile(double p) const {
    const double idx = p / 100.0 * double(n_ - 1);
    const auto lo = static_cast<std::size_t>(std::floor(idx));
    const double frac = idx - double(lo);
    const double a = kth(lo);
    return frac == 0 ? a : a + (kth(std::min(lo + 1, n_ - 1)) - a) * frac;
  }

 private:
  std::size_t n_;
  std::vector<std::size_t> hist_;
  std::vector<double> sorted_;
};

TEST(ManifestData, EveryDatasetLoadsAsDescribed) {
  ADAMESH_REQUIRE_SHARED_DATA(dir);
  std::ifstream in(dir + "/manifest.json");
  const nlohmann::json manifest = nlohmann::json::parse(in);
  int loaded = 0;
  for (const auto& d : manifest.at("datasets")) {
    const std::string id = d.at("id");
    const std::string path = dir + "/" + d.at("primary_file").get<std::string>();
    SCOPED_TRACE(id + " (" + path + ")");
    const auto t0 = std::chrono::steady_clock::now();
    Volume v;
    try {
      v = read_volume(path);
    } catch (const Error& e) {
      ADD_FAILURE() << "load failed: " << e.what();
      continue;
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::printf("  %-20s %-18s %5lldx%lldx%lld %-8s %8.1f ms\n", id.c_str(), v.format.c_str(),
                (long long)v.grid.dims[0], (long long)v.grid.dims[1], (long long)v.grid.dims[2],
                to_string(v.type), ms);
    ++loaded;
    EXPECT_EQ(v.source, path);
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(v.grid.dims[a], d.at("dims_xyz")[a].get<std::int64_t>()) << "axis " << a;
      EXPECT_NEAR(v.grid.spacing[a], d.at("spacing_xyz")[a].get<double>(), 1e-6) << "axis " << a;
      if (d.contains("origin_xyz") && !d.at("origin_xyz").is_null()) {
        EXPECT_NEAR(v.grid.origin[a], d.at("origin_xyz")[a].get<double>(), 1e-6) << "axis " << a;
      }
    }
    EXPECT_TRUE(v.grid.axis_aligned());
    EXPECT_EQ(std::string(to_string(v.type)), d.at("voxel_type").get<std::string>());
    double lo = INFINITY, hi = -INFINITY;
    for (std::int64_t i = 0; i < v.grid.num_samples(); ++i) {
      lo = std::min(lo, v.at(i));
      hi = std::max(hi, v.at(i));
    }
    EXPECT_DOUBLE_EQ(lo, d.at("value_range")[0].get<double>());
    EXPECT_DOUBLE_EQ(hi, d.at("value_range")[1].get<double>());
    if (d.contains("percentiles_1_50_99")) {
      const Ranks ranks(v);
      const double ps[3] = {1, 50, 99};
      for (int k = 0; k < 3; ++k) {
        const double want = d.at("percentiles_1_50_99")[k].get<double>();
        EXPECT_NEAR(ranks.percentile(ps[k]), want, 1e-4 * std::max(1.0, std::abs(want))) << "percentile " << ps[k];
      }
    }
  }
  EXPECT_EQ(loaded, static_cast<int>(manifest.at("datasets").size()));
  EXPECT_EQ(loaded, 12);
}

TEST(ManifestData, Mc33CustodioNrrdHeadersLoad) {
  ADAMESH_REQUIRE_SHARED_DATA(dir);
  const std::string base = dir + "/mc33/custodio2013/";
  const Volume alg = read_volume(base + "algorithm1/algorithm.nhdr");
  EXPECT_EQ(alg.grid.dims, (std::array<std::int64_t, 3>{2, 2, 2}));
  EXPECT_EQ(alg.type, ScalarType::f32);
  const Volume f7 = read_volume(base + "figure7/figure7.nhdr");
  EXPECT_EQ(f7.grid.dims, (std::array<std::int64_t, 3>{2, 2, 2}));
  const Volume f6 = read_volume(base + "figure6/figure6.nhdr");  // big-endian float32
  EXPECT_EQ(f6.grid.dims, (std::array<std::int64_t, 3>{5, 5, 5}));
  expect_vec(f6.grid.spacing, {0.5, 0.5, 0.5});
  for (const Volume* v : {&alg, &f7, &f6})
    for (std::int64_t i = 0; i < v->grid.num_samples(); ++i) {
      ASSERT_TRUE(std::isfinite(v->at(i))) << v->source;
      ASSERT_LE(std::abs(v->at(i)), 10.0) << v->source << " sample " << i << " (byte order?)";
    }
}

TEST(ManifestData, BundledCtHeadMatchesSharedCopy) {
  ADAMESH_REQUIRE_SHARED_DATA(dir);
  const Volume bundled = read_volume(source_dir() + "/data/ct_headsq/quarter.nhdr");
  const Volume shared = read_volume(dir + "/ct_headsq/quarter.nhdr");
  ASSERT_EQ(bundled.data.size(), shared.data.size());
  EXPECT_EQ(std::memcmp(bundled.data.data(), shared.data.data(), shared.data.size()), 0);
}

}  // namespace
}  // namespace adamesh
