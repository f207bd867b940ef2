// Helpers for the volume reader tests: byte builders, compression, error expectations.
#pragma once

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "adamesh/error.h"
#include "adamesh/io.h"
#include "adamesh/volume.h"
#include "testing.h"

namespace adamesh::testutil {

/// Bytes of the values in little- or big-endian order.
template <class T>
std::string to_bytes(const std::vector<T>& values, bool big_endian = false) {
  std::string out(values.size() * sizeof(T), '\0');
  for (std::size_t i = 0; i < values.size(); ++i) {
    char b[sizeof(T)];
    std::memcpy(b, &values[i], sizeof(T));
    for (std::size_t k = 0; k < sizeof(T); ++k)
      out[i * sizeof(T) + k] = big_endian ? b[sizeof(T) - 1 - k] : b[k];
  }
  return out;
}

template <class T>
std::string pod_bytes(const T& v, bool big_endian = false) {
  return to_bytes(std::vector<T>{v}, big_endian);
}

/// zlib (wrap = 15) or gzip (wrap = 31) compression of `data`.
inline std::string compress(const std::string& data, int wrap = 15) {
  z_stream s{};
  EXPECT_EQ(deflateInit2(&s, 6, Z_DEFLATED, wrap, 8, Z_DEFAULT_STRATEGY), Z_OK);
  std::string out(deflateBound(&s, data.size()) + 64, '\0');
  s.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  s.avail_in = static_cast<uInt>(data.size());
  s.next_out = reinterpret_cast<Bytef*>(out.data());
  s.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(deflate(&s, Z_FINISH), Z_STREAM_END);
  out.resize(s.total_out);
  deflateEnd(&s);
  return out;
}
inline std::string gzip(const std::string& data) { return compress(data, 31); }

/// A ramp of n values v[i] = a + b*i (cast to T).
template <class T>
std::vector<T> ramp(std::size_t n, double a = 0, double b = 1) {
  std::vector<T> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<T>(a + b * double(i));
  return v;
}

/// Every sample equals `expected` (converted to double).
template <class T>
void expect_samples(const Volume& v, const std::vector<T>& expected) {
  ASSERT_EQ(v.grid.num_samples(), static_cast<std::int64_t>(expected.size()));
  for (std::size_t i = 0; i < expected.size(); ++i)
    ASSERT_EQ(v.at(static_cast<std::int64_t>(i)), static_cast<double>(expected[i])) << "sample " << i;
}

inline void expect_vec(const Vec3& a, const Vec3& b, double tol = 1e-9) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

inline void expect_mat(const Mat3& a, const Mat3& b, double tol = 1e-9) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a.m[r][c], b.m[r][c], tol) << "entry " << r << "," << c;
}

/// Runs f, expects an adamesh::Error with `status` whose one-line message starts with `path`
/// and contains every string in `parts`.
inline void expect_error(const std::function<void()>& f, Status status, const std::string& path,
                         const std::vector<std::string>& parts) {
  try {
    f();
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_EQ(e.status(), status) << msg;
    EXPECT_EQ(msg.rfind(path + ": ", 0), 0u) << "message does not start with the path: " << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message is not one line: " << msg;
    for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
    return;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "unexpected exception type: " << e.what();
    return;
  }
  ADD_FAILURE() << "no error thrown (expected " << to_string(status) << ")";
}

inline void expect_read_error(const std::string& path, Status status,
                              const std::vector<std::string>& parts, const RawOptions& raw = {}) {
  expect_error([&] { (void)read_volume(path, raw); }, status, path, parts);
}

}  // namespace adamesh::testutil
