// CCP4 / MRC density map reader (.mrc, .map, .ccp4, .mrcs), following the MRC2014 format
// description (ccpem.ac.uk/mrc_format/mrc2014.php) and the CCP4 map format.
//
// 1024-byte header of 4-byte words: NC NR NS, MODE, NCSTART NRSTART NSSTART, MX MY MZ,
// CELLA (x y z, Å), CELLB (α β γ), MAPC MAPR MAPS, ..., NSYMBT (extended header bytes),
// ORIGIN (x y z) at byte 196, "MAP " at 208, machine stamp at 212 (0x44 = little-endian,
// 0x11 = big-endian; without a stamp the byte order that gives a sane header wins).
// Modes 0 (int8; uint8 when IMOD's flag says so), 1 (int16), 2 (float32), 6 (uint16); complex
// modes 3/4, float16 (12) and 4-bit (101) are Status::unsupported. The file's column/row/
// section axes (MAPC/MAPR/MAPS) are permuted so that x varies fastest, one section at a time.
// Spacing = CELLA / (MX, MY, MZ) (1 when undefined). Non-orthogonal cells (angles ≠ 90°) give
// a skewed direction matrix (a along x, b in the xy plane). Origin = ORIGIN when non-zero,
// else the start indices × spacing.
#include <cmath>
#include <cstring>
#include <sstream>

#include "adamesh/error.h"
#include "io_util.h"
#include "volume_readers.h"

namespace adamesh::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Header {
  std::uint8_t raw[1024];
  bool swap = false;
  std::int32_t i(int w) const {
    std::uint32_t v;
    std::memcpy(&v, raw + 4 * w, 4);
    if (swap) v = __builtin_bswap32(v);
    return static_cast<std::int32_t>(v);
  }
  double f(int w) const {
    std::uint32_t v;
    std::memcpy(&v, raw + 4 * w, 4);
    if (swap) v = __builtin_bswap32(v);
    float x;
    std::memcpy(&x, &v, 4);
    return x;
  }
};

bool sane(const Header& h) {
  const int modes[] = {0, 1, 2, 3, 4, 6, 12, 101};
  bool mode_ok = false;
  for (int m : modes) mode_ok = mode_ok || h.i(3) == m;
  return mode_ok && h.i(0) > 0 && h.i(1) > 0 && h.i(2) > 0 && h.i(0) < (1 << 24) && h.i(1) < (1 << 24) &&
         h.i(2) < (1 << 24);
}

}  // namespace

Volume read_mrc(const std::string& path) {
  const InputFile f(path);
  Header h;
  f.read_exact(0, h.raw, sizeof h.raw, "header (1024 bytes)");
  const bool host_le = host_is_little_endian();
  if (h.raw[212] == 0x44 || h.raw[212] == 0x11) {
    h.swap = (h.raw[212] == 0x44) != host_le;
  } else {
    if (!sane(h)) h.swap = true;
    if (!sane(h)) h.swap = false;  // report the native reading below
  }
  const std::int64_t nc = h.i(0), nr = h.i(1), ns = h.i(2);
  const int mode = h.i(3);
  ScalarType type;
  switch (mode) {
    case 0: {
      // IMOD marks unsigned bytes: imodStamp 1146047817 at word 38, flag bit 0 at word 39.
      const bool imod_unsigned = h.i(38) == 1146047817 && (h.i(39) & 1);
      type = imod_unsigned ? ScalarType::u8 : ScalarType::i8;
      break;
    }
    case 1: type = ScalarType::i16; break;
    case 2: type = ScalarType::f32; break;
    case 6: type = ScalarType::u16; break;
    case 3: case 4:
      fail(Status::unsupported, path + ": MRC mode " + std::to_string(mode) + " (complex data) is not supported");
    case 12: fail(Status::unsupported, path + ": MRC mode 12 (float16) is not supported");
    case 101: fail(Status::unsupported, path + ": MRC mode 101 (4-bit data) is not supported");
    default: fail_input(path, "not an MRC/CCP4 map (unknown mode " + std::to_string(mode) + ")");
  }

  int map[3] = {h.i(16), h.i(17), h.i(18)};  // file axis (column, row, section) → x/y/z (1..3)
  if (map[0] == 0 && map[1] == 0 && map[2] == 0) map[0] = 1, map[1] = 2, map[2] = 3;
  if (map[0] < 1 || map[0] > 3 || map[1] < 1 || map[1] > 3 || map[2] < 1 || map[2] > 3 ||
      map[0] == map[1] || map[1] == map[2] || map[0] == map[2])
    fail_input(path, "invalid axis order MAPC/MAPR/MAPS " + std::to_string(map[0]) + " " +
                         std::to_string(map[1]) + " " + std::to_string(map[2]));
  Grid grid;
  const std::int64_t file_dims[3] = {nc, nr, ns};
  const std::int64_t file_start[3] = {h.i(4), h.i(5), h.i(6)};
  Vec3 start;
  for (int a = 0; a < 3; ++a) {
    grid.dims[map[a] - 1] = file_dims[a];
    start[map[a] - 1] = static_cast<double>(file_start[a]);
  }
  const std::size_t bytes = checked_volume_bytes(grid.dims, type, path);

  for (int a = 0; a < 3; ++a) {
    const double cell = h.f(10 + a);
    const std::int32_t m = h.i(7 + a);
    grid.spacing[a] = (std::isfinite(cell) && cell > 0 && m > 0) ? cell / m : 1.0;
  }
  double ang[3];
  bool skewed = false;
  for (int a = 0; a < 3; ++a) {
    ang[a] = h.f(13 + a);
    if (!std::isfinite(ang[a]) || ang[a] <= 0 || ang[a] >= 180) ang[a] = 90;
    skewed = skewed || std::abs(ang[a] - 90) > 1e-6;
  }
  if (skewed) {
    const double ca = std::cos(ang[0] * kPi / 180), cb = std::cos(ang[1] * kPi / 180),
                 cg = std::cos(ang[2] * kPi / 180), sg = std::sin(ang[2] * kPi / 180);
    const double cy = (ca - cb * cg) / sg;
    const double cz2 = 1 - cb * cb - cy * cy;
    if (cz2 <= 1e-12) fail_input(path, "invalid cell angles (degenerate unit cell)");
    grid.direction = Mat3::from_columns({1, 0, 0}, {cg, sg, 0}, {cb, cy, std::sqrt(cz2)});
  }
  const Vec3 origin_field{h.f(49), h.f(50), h.f(51)};
  const bool has_origin = std::memcmp(h.raw + 208, "MAP ", 4) == 0 && norm2(origin_field) > 0 &&
                          std::isfinite(norm2(origin_field));
  grid.origin = has_origin ? origin_field : grid.index_to_world_matrix() * start;

  const std::int32_t nsymbt = h.i(23);
  if (nsymbt < 0) fail_input(path, "invalid extended header size NSYMBT " + std::to_string(nsymbt));
  const std::uint64_t offset = 1024 + static_cast<std::uint64_t>(nsymbt);
  require_range(f, offset, bytes, "sample data");

  Volume v = allocate_volume(grid, type, path);
  v.format = "MRC";
  const std::size_t sz = scalar_size(type);
  if (map[0] == 1 && map[1] == 2 && map[2] == 3) {
    f.read_exact(offset, v.data.data(), bytes, "sample data");
  } else {
    // Scatter one section at a time into x-fastest order.
    const std::size_t section = static_cast<std::size_t>(nc * nr) * sz;
    std::vector<std::byte> buf(section);
    std::int64_t stride[3];  // linear-index step of x, y, z
    stride[0] = 1;
    stride[1] = grid.dims[0];
    stride[2] = grid.dims[0] * grid.dims[1];
    const std::int64_t sc = stride[map[0] - 1], sr = stride[map[1] - 1], ss = stride[map[2] - 1];
    for (std::int64_t s = 0; s < ns; ++s) {
      f.read_exact(offset + static_cast<std::uint64_t>(s) * section, buf.data(), section, "sample data");
      for (std::int64_t r = 0; r < nr; ++r)
        for (std::int64_t c = 0; c < nc; ++c)
          std::memcpy(v.data.data() + static_cast<std::size_t>(c * sc + r * sr + s * ss) * sz,
                      buf.data() + static_cast<std::size_t>(r * nc + c) * sz, sz);
    }
  }
  if (h.swap) swap_bytes_in_place(v.data.data(), bytes / sz, sz);
  return v;
}

}  // namespace adamesh::detail
