// VolVis SLC and CCP4/MRC reader tests: RLE and raw slices with the short-slice quirk, MRC
// modes, byte orders, axis permutation, extended headers, origins, skewed cells, bad input.
#include <cmath>

#include "io_volume_test_util.h"

namespace adamesh {
namespace {

using namespace testutil;

// ------------------------------------------------------------------------------------ SLC

std::string slc_header(int nx, int ny, int nz, int bits, int compression, const std::string& spacing = "1 1 1") {
  std::string h = "11111\n" + std::to_string(nx) + " " + std::to_string(ny) + " " + std::to_string(nz) + " " +
                  std::to_string(bits) + "\n" + spacing + "\n1 6 0 " + std::to_string(compression) + "\n";
  return h + "2 1 X" + std::string(6, '\x7f');  // 2x1 icon, three planes
}

std::string slc_slice(const std::string& rle) { return std::to_string(rle.size()) + " X" + rle; }

TEST(SlcRead, RunLengthSlicesLiteralAndRepeatRuns) {
  TempDir tmp;
  const std::string path = tmp.file("r.slc");
  // slice 0: literal 3 (1 2 3), repeat 3 × 200, end;  slice 1: repeat 6 × 7 without terminator
  write_bytes(path, slc_header(3, 2, 2, 8, 1, "0.5 0.25 2") +
                        slc_slice(std::string("\x83\x01\x02\x03\x03\xc8\x00", 7)) + "\n" +
                        slc_slice(std::string("\x06\x07", 2)));
  const Volume v = read_volume(path);
  EXPECT_EQ(v.format, "VolVis SLC");
  EXPECT_EQ(v.type, ScalarType::u8);
  EXPECT_EQ(v.grid.dims, (std::array<std::int64_t, 3>{3, 2, 2}));
  expect_vec(v.grid.spacing, {0.5, 0.25, 2});
  expect_samples(v, std::vector<int>{1, 2, 3, 200, 200, 200, 7, 7, 7, 7, 7, 7});
}

TEST(SlcRead, UncompressedSlices) {
  TempDir tmp;
  const auto values = ramp<std::uint8_t>(12, 5, 20);
  const std::string path = tmp.file("u.slc");
  write_bytes(path, slc_header(2, 3, 2, 8, 0) + to_bytes(values));
  expect_samples(read_volume(path), values);
}

TEST(SlcRead, SliceShortByLessThanARowIsPaddedWithZero) {
  TempDir tmp;
  const std::string path = tmp.file("q.slc");  // like embryo.slc: x·y − 1 voxels per slice
  write_bytes(path, slc_header(3, 2, 1, 8, 1) + slc_slice(std::string("\x05\x09\x00", 3)));
  expect_samples(read_volume(path), std::vector<int>{9, 9, 9, 9, 9, 0});
}

TEST(SlcBad, CorruptSlicesAndHeaders) {
  TempDir tmp;
  const std::string path = tmp.file("b.slc");
  write_bytes(path, slc_header(2, 2, 1, 8, 1) + slc_slice(std::string("\x05\x09\x00", 3)));
  expect_read_error(path, Status::invalid_input, {"slice 0", "more than 4 voxels"});
  write_bytes(path, slc_header(3, 3, 1, 8, 1) + slc_slice(std::string("\x85\x01\x02", 3)));
  expect_read_error(path, Status::invalid_input, {"slice 0", "literal run passes the end"});
  write_bytes(path, slc_header(2, 2, 1, 8, 1) + "5000 X" + std::string(10, '\x01'));
  expect_read_error(path, Status::invalid_input, {"truncated data: slice 0 needs 5000 bytes"});
  write_bytes(path, slc_header(4, 2, 1, 8, 1) + slc_slice(std::string("\x03\x09\x00", 3)));
  expect_read_error(path, Status::invalid_input, {"slice 0 decodes to only 3 of 8 voxels"});
  write_bytes(path, slc_header(2, 2, 2, 8, 1) + slc_slice(std::string("\x04\x09\x00", 3)));
  expect_read_error(path, Status::invalid_input, {"missing slice 1 size"});
  write_bytes(path, slc_header(2, 2, 1, 16, 1));
  expect_read_error(path, Status::unsupported, {"16 bits per voxel"});
  write_bytes(path, "11111\n2 two 2 8\n");
  expect_read_error(path, Status::invalid_input, {"non-numeric value 'two' for dimensions"});
  write_bytes(path, "11111\n2 2 -2 8\n1 1 1\n1 6 0 1\n");
  expect_read_error(path, Status::invalid_input, {"2x2x-2"});
  write_bytes(path, slc_header(2, 2, 1, 8, 0) + "abc");
  expect_read_error(path, Status::invalid_input, {"truncated", "expected 4 bytes"});
}

// ------------------------------------------------------------------------------------ MRC

struct Mrc {
  std::int32_t w[256] = {};
  bool big = false;
  Mrc(int nc, int nr, int ns, int mode) {
    w[0] = nc, w[1] = nr, w[2] = ns, w[3] = mode;
    w[7] = nc, w[8] = nr, w[9] = ns;
    setf(10, float(nc)), setf(11, float(nr)), setf(12, float(ns));
    setf(13, 90), setf(14, 90), setf(15, 90);
    w[16] = 1, w[17] = 2, w[18] = 3;
    std::memcpy(&w[52], "MAP ", 4);
  }
  void setf(int i, float v) { std::memcpy(&w[i], &v, 4); }
  std::string file(const std::string& data, int nsymbt = 0) {
    w[23] = nsymbt;
    std::string out;
    for (int i = 0; i < 256; ++i) {
      if (i == 52) out += "MAP ";
      else if (i == 53) out += big ? std::string("\x11\x11\x00\x00", 4) : std::string("\x44\x44\x00\x00", 4);
      else out += pod_bytes(w[i], big);
    }
    return out + std::string(static_cast<std::size_t>(nsymbt), 'e') + data;
  }
};

TEST(MrcRead, Float32WithCellSpacingAndOriginField) {
  TempDir tmp;
  Mrc m(3, 2, 2, 2);
  m.setf(10, 6), m.setf(11, 1), m.setf(12, 4);  // spacing 2, 0.5, 2
  m.setf(49, -5), m.setf(50, 6), m.setf(51, 7.5);
  const auto values = ramp<float>(12, -1, 0.5);
  const std::string path = tmp.file("a.mrc");
  write_bytes(path, m.file(to_bytes(values)));
  const Volume v = read_volume(path);
  EXPECT_EQ(v.format, "MRC");
  EXPECT_EQ(v.type, ScalarType::f32);
  expect_vec(v.grid.spacing, {2, 0.5, 2});
  expect_vec(v.grid.origin, {-5, 6, 7.5});
  expect_samples(v, values);
}

TEST(MrcRead, BigEndianInt16PermutedAxes) {
  TempDir tmp;
  // Columns run along z, rows along x, sections along y: file dims (nc, nr, ns) = (4, 2, 3)
  // → volume dims x = 2, y = 3, z = 4.
  Mrc m(4, 2, 3, 1);
  m.big = true;
  m.w[16] = 3, m.w[17] = 1, m.w[18] = 2;
  m.w[7] = 2, m.w[8] = 3, m.w[9] = 4;  // MX MY MZ are along x, y, z
  m.setf(10, 2), m.setf(11, 3), m.setf(12, 4);
  std::vector<std::int16_t> file_values;
  for (int s = 0; s < 3; ++s)
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 4; ++c) file_values.push_back(static_cast<std::int16_t>(100 * s + 10 * r + c));
  const std::string path = tmp.file("p.map");
  write_bytes(path, m.file(to_bytes(file_values, true)));
  const Volume v = read_volume(path);
  EXPECT_EQ(v.grid.dims, (std::array<std::int64_t, 3>{2, 3, 4}));
  for (int x = 0; x < 2; ++x)
    for (int y = 0; y < 3; ++y)
      for (int z = 0; z < 4; ++z)
        ASSERT_EQ(v.at(x, y, z), 100 * y + 10 * x + z) << x << "," << y << "," << z;
}

TEST(MrcRead, Uint16ExtendedHeaderStartOriginNoStamp) {
  TempDir tmp;
  Mrc m(2, 2, 2, 6);
  m.w[4] = 10, m.w[5] = -2, m.w[6] = 1;  // start indices
  m.setf(10, 3), m.setf(11, 3), m.setf(12, 3);  // spacing 1.5
  std::string bytes = m.file(to_bytes(ramp<std::uint16_t>(8, 60000, 100)), 80);
  std::memset(bytes.data() + 208, 0, 8);  // old CCP4 file: no "MAP " and no machine stamp
  const std::string path = tmp.file("s.ccp4");
  write_bytes(path, bytes);
  const Volume v = read_volume(path);
  EXPECT_EQ(v.type, ScalarType::u16);
  expect_vec(v.grid.origin, {15, -3, 1.5});
  expect_samples(v, ramp<std::uint16_t>(8, 60000, 100));
}

TEST(MrcRead, Mode0SignedOrImodUnsignedAndSkewedCell) {
  TempDir tmp;
  Mrc m(2, 1, 1, 0);
  m.setf(15, 120);  // gamma
  const std::string path = tmp.file("b.mrc");
  write_bytes(path, m.file(std::string("\xff\x05", 2)));
  const Volume s = read_volume(path);
  EXPECT_EQ(s.type, ScalarType::i8);
  expect_samples(s, std::vector<int>{-1, 5});
  expect_mat(s.grid.direction, Mat3::from_columns({1, 0, 0}, {-0.5, std::sqrt(3.0) / 2, 0}, {0, 0, 1}), 1e-6);
  m.w[38] = 1146047817;
  m.w[39] = 1;
  write_bytes(path, m.file(std::string("\xff\x05", 2)));
  const Volume u = read_volume(path);
  EXPECT_EQ(u.type, ScalarType::u8);
  expect_samples(u, std::vector<int>{255, 5});
}

TEST(MrcBad, UnsupportedModesTruncationAxes) {
  TempDir tmp;
  const std::string path = tmp.file("x.mrc");
  for (int mode : {3, 4}) {
    write_bytes(path, Mrc(2, 2, 2, mode).file(std::string(64, '\0')));
    expect_read_error(path, Status::unsupported, {"mode " + std::to_string(mode), "complex"});
  }
  write_bytes(path, Mrc(2, 2, 2, 2).file(std::string(31, '\0')));
  expect_read_error(path, Status::invalid_input, {"truncated", "expected 32 bytes at offset 1024"});
  Mrc bad(2, 2, 2, 2);
  bad.w[16] = 1, bad.w[17] = 1, bad.w[18] = 3;
  write_bytes(path, bad.file(std::string(32, '\0')));
  expect_read_error(path, Status::invalid_input, {"invalid axis order"});
  write_bytes(path, Mrc(2, 0, 2, 2).file(""));
  expect_read_error(path, Status::invalid_input, {"2x0x2"});
  write_bytes(path, std::string(500, 'm'));
  expect_read_error(path, Status::invalid_input, {"truncated header"});
}

}  // namespace
}  // namespace adamesh
