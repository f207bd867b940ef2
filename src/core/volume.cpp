#include "adamesh/volume.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cctype>
#include <fstream>
#include <limits>
#include <new>
#include <sstream>

#include "adamesh/error.h"

namespace {
std::string format_double(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}
}  // namespace

namespace adamesh {

std::size_t scalar_size(ScalarType t) noexcept {
  return dispatch_scalar(t, [](auto v) { return sizeof(v); });
}

const char* to_string(ScalarType t) noexcept {
  switch (t) {
    case ScalarType::u8: return "uint8";
    case ScalarType::i8: return "int8";
    case ScalarType::u16: return "uint16";
    case ScalarType::i16: return "int16";
    case ScalarType::u32: return "uint32";
    case ScalarType::i32: return "int32";
    case ScalarType::f32: return "float32";
    case ScalarType::f64: return "float64";
  }
  return "?";
}

bool is_floating(ScalarType t) noexcept { return t == ScalarType::f32 || t == ScalarType::f64; }

std::optional<ScalarType> parse_scalar_type(std::string_view name) {
  std::string s;
  for (char c : name) {
    if (c == '_' || c == '-') c = ' ';
    s.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  }
  struct Alias {
    const char* name;
    ScalarType type;
  };
  static const Alias aliases[] = {
      {"uint8", ScalarType::u8},   {"u8", ScalarType::u8},     {"uchar", ScalarType::u8},
      {"unsigned char", ScalarType::u8}, {"uint8 t", ScalarType::u8},
      {"int8", ScalarType::i8},    {"i8", ScalarType::i8},     {"char", ScalarType::i8},
      {"signed char", ScalarType::i8}, {"int8 t", ScalarType::i8},
      {"uint16", ScalarType::u16}, {"u16", ScalarType::u16},   {"ushort", ScalarType::u16},
      {"unsigned short", ScalarType::u16}, {"unsigned short int", ScalarType::u16},
      {"uint16 t", ScalarType::u16},
      {"int16", ScalarType::i16},  {"i16", ScalarType::i16},   {"short", ScalarType::i16},
      {"short int", ScalarType::i16}, {"signed short", ScalarType::i16},
      {"signed short int", ScalarType::i16}, {"int16 t", ScalarType::i16},
      {"uint32", ScalarType::u32}, {"u32", ScalarType::u32},   {"uint", ScalarType::u32},
      {"unsigned int", ScalarType::u32}, {"uint32 t", ScalarType::u32},
      {"int32", ScalarType::i32},  {"i32", ScalarType::i32},   {"int", ScalarType::i32},
      {"signed int", ScalarType::i32}, {"int32 t", ScalarType::i32},
      {"float32", ScalarType::f32}, {"f32", ScalarType::f32},  {"float", ScalarType::f32},
      {"float64", ScalarType::f64}, {"f64", ScalarType::f64},  {"double", ScalarType::f64},
  };
  for (const auto& a : aliases)
    if (s == a.name) return a.type;
  return std::nullopt;
}

Mat3 Grid::index_to_world_matrix() const noexcept {
  Mat3 r = direction;
  for (int row = 0; row < 3; ++row)
    for (int c = 0; c < 3; ++c) r.m[row][c] *= spacing[c];
  return r;
}

Vec3 Grid::to_index(const Vec3& p) const noexcept {
  return index_to_world_matrix().inverse() * (p - origin);
}

Box Grid::world_bounds() const noexcept {
  Box b{to_world({0, 0, 0}), to_world({0, 0, 0})};
  for (int c = 1; c < 8; ++c) {
    const Vec3 ijk{(c & 1) ? double(dims[0] - 1) : 0.0, (c & 2) ? double(dims[1] - 1) : 0.0,
                   (c & 4) ? double(dims[2] - 1) : 0.0};
    const Vec3 w = to_world(ijk);
    b.lo = vmin(b.lo, w);
    b.hi = vmax(b.hi, w);
  }
  return b;
}

double Grid::min_spacing() const noexcept {
  const Mat3 a = index_to_world_matrix();
  return std::min({norm(a.column(0)), norm(a.column(1)), norm(a.column(2))});
}

void check_world_range(const Grid& g, const std::string& where) {
  const Mat3 a = g.index_to_world_matrix();
  for (int c = 0; c < 3; ++c) {
    const double len = norm(a.column(c));
    if (!(len >= kMinVoxelEdge && len <= kMaxWorldCoordinate))
      fail_input(where, "voxel edge " + std::to_string(c) + " is " + format_double(len) +
                            " world units long (adamesh needs " + format_double(kMinVoxelEdge) +
                            " to " + format_double(kMaxWorldCoordinate) + ")");
  }
  const Box b = g.world_bounds();
  for (int c = 0; c < 3; ++c)
    if (!(std::abs(b.lo[c]) <= kMaxWorldCoordinate && std::abs(b.hi[c]) <= kMaxWorldCoordinate))
      fail_input(where, "world coordinates reach " +
                            format_double(std::max(std::abs(b.lo[c]), std::abs(b.hi[c]))) +
                            ", beyond the supported ±" + format_double(kMaxWorldCoordinate) +
                            " (check the origin and spacing)");
}

bool Grid::axis_aligned() const noexcept { return direction == Mat3::identity(); }

Vec3 Grid::float_rounding_in_index() const noexcept {
  const Box b = world_bounds();
  double big = 0;
  for (int k = 0; k < 3; ++k) big = std::max({big, std::abs(b.lo[k]), std::abs(b.hi[k])});
  const Mat3 to_index = index_to_world_matrix().inverse();
  Vec3 r;
  for (int a = 0; a < 3; ++a) {
    const Vec3 row = to_index.row(a);
    r[a] = (std::abs(row.x) + std::abs(row.y) + std::abs(row.z)) * 0x1p-23 * big;
  }
  return r;
}

SampleBuffer::SampleBuffer(std::size_t bytes)
    : data_(new (std::nothrow) std::byte[bytes == 0 ? 1 : bytes]), size_(bytes) {
  if (!data_) throw std::bad_alloc();
  ptr_ = data_.get();
}

double Volume::at(std::int64_t linear) const noexcept {
  return dispatch_scalar(type, [&](auto v) {
    using T = decltype(v);
    return static_cast<double>(samples<T>()[linear]);
  });
}

std::uint64_t available_memory_bytes() noexcept {
  std::ifstream in("/proc/meminfo");
  std::string key;
  std::uint64_t value = 0;
  std::string unit;
  while (in >> key >> value >> unit) {
    if (key == "MemAvailable:") return value * 1024ull;
  }
  const long pages = sysconf(_SC_PHYS_PAGES);
  const long page = sysconf(_SC_PAGE_SIZE);
  if (pages > 0 && page > 0) return std::uint64_t(pages) * std::uint64_t(page);
  return std::numeric_limits<std::uint64_t>::max();
}

std::size_t checked_volume_bytes(const std::array<std::int64_t, 3>& dims, ScalarType type,
                                 const std::string& where) {
  for (int a = 0; a < 3; ++a) {
    if (dims[a] < 1) {
      std::ostringstream os;
      os << "invalid dimensions " << dims[0] << "x" << dims[1] << "x" << dims[2]
         << " (each must be at least 1)";
      fail_input(where, os.str());
    }
  }
  // Product with overflow checks; 2^62 is far beyond any real volume.
  const std::uint64_t limit = std::uint64_t(1) << 62;
  std::uint64_t n = 1;
  for (int a = 0; a < 3; ++a) {
    if (std::uint64_t(dims[a]) > limit / n) {
      std::ostringstream os;
      os << "dimensions " << dims[0] << "x" << dims[1] << "x" << dims[2]
         << " overflow the sample count";
      fail_input(where, os.str());
    }
    n *= std::uint64_t(dims[a]);
  }
  const std::uint64_t sz = scalar_size(type);
  if (n > limit / sz) {
    std::ostringstream os;
    os << "dimensions " << dims[0] << "x" << dims[1] << "x" << dims[2] << " overflow the byte size";
    fail_input(where, os.str());
  }
  const std::uint64_t bytes = n * sz;
  const std::uint64_t avail = available_memory_bytes();
  if (bytes > avail) {
    std::ostringstream os;
    os << "dimensions " << dims[0] << "x" << dims[1] << "x" << dims[2] << " of " << to_string(type)
       << " need " << bytes / (1024.0 * 1024.0) << " MiB, more than the "
       << avail / (1024.0 * 1024.0) << " MiB of memory available";
    fail_input(where, os.str());
  }
  return static_cast<std::size_t>(bytes);
}

Volume allocate_volume(const Grid& grid, ScalarType type, const std::string& where) {
  const std::size_t bytes = checked_volume_bytes(grid.dims, type, where);
  Volume v;
  v.grid = grid;
  v.type = type;
  v.source = where;
  try {
    v.data = SampleBuffer(bytes);
  } catch (const std::bad_alloc&) {
    fail_input(where, "cannot allocate " + std::to_string(bytes) + " bytes for the samples");
  }
  return v;
}

}  // namespace adamesh
