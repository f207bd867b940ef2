// NRRD reader tests: synthetic attached and detached files for every encoding, endianness,
// data-file form and world-space field, plus the bad-input cases.
#include <cmath>

#include "io_volume_test_util.h"

namespace adamesh {
namespace {

using namespace testutil;

std::string header(const std::string& fields) { return "NRRD0004\n# test file\n" + fields; }

TEST(NrrdRead, AttachedRawLittleEndianWithSpaceDirections) {
  TempDir tmp;
  const auto values = ramp<std::int16_t>(4 * 3 * 2, -10, 3);
  const std::string path = tmp.file("a.nrrd");
  write_bytes(path, header("type: short\ndimension: 3\nsizes: 4 3 2\nendian: little\n"
                           "encoding: raw\nspace: right-anterior-superior\n"
                           "space directions: (0,2,0) (-1.5,0,0) (0,0,0.5)\n"
                           "space origin: (10,-20,30.25)\n\n") +
                        to_bytes(values));
  const Volume v = read_volume(path);
  EXPECT_EQ(v.format, "NRRD");
  EXPECT_EQ(v.source, path);
  EXPECT_EQ(v.type, ScalarType::i16);
  EXPECT_EQ(v.grid.dims, (std::array<std::int64_t, 3>{4, 3, 2}));
  expect_vec(v.grid.spacing, {2, 1.5, 0.5});
  expect_vec(v.grid.origin, {10, -20, 30.25});
  expect_mat(v.grid.direction, Mat3::from_columns({0, 1, 0}, {-1, 0, 0}, {0, 0, 1}));
  // world position of sample (1, 2, 1) = origin + (0,2,0) + 2·(-1.5,0,0) + (0,0,0.5)
  expect_vec(v.grid.to_world({1, 2, 1}), {10 - 3, -20 + 2, 30.75});
  expect_samples(v, values);
  EXPECT_EQ(volume_format_for(path), "NRRD");
}

TEST(NrrdRead, BigEndianFloatWithSpacingsAndLeftHandedSpace) {
  TempDir tmp;
  const std::vector<float> values = {1.5f, -2.25f, 3e10f, NAN, INFINITY, 0.f, 7.f, 8.f};
  const std::string path = tmp.file("b.nrrd");
  write_bytes(path, header("type: float\ndimension: 3\nsizes: 2 2 2\nspacings: 3.2 3.2 1.5\n"
                           "space: 3D-left-handed\nendian: big\nencoding: raw\n\n") +
                        to_bytes(values, true));
  const Volume v = read_volume(path);
  EXPECT_EQ(v.type, ScalarType::f32);
  expect_vec(v.grid.spacing, {3.2, 3.2, 1.5});
  EXPECT_TRUE(v.grid.axis_aligned());
  EXPECT_EQ(v.at(0), 1.5);
  EXPECT_EQ(v.at(1), -2.25);
  EXPECT_EQ(v.at(2), double(3e10f));
  EXPECT_TRUE(std::isnan(v.at(3)));  // NaN/Inf are loaded as they are
  EXPECT_TRUE(std::isinf(v.at(4)));
  EXPECT_EQ(v.at(7), 8.0);
}

TEST(NrrdRead, GzipBigEndianUint16AndGzipByteSkip) {
  TempDir tmp;
  const auto values = ramp<std::uint16_t>(5 * 4 * 3, 60000, 7);
  const std::string path = tmp.file("c.nrrd");
  write_bytes(path, header("type: unsigned short int\ndimension: 3\nsizes: 5 4 3\n"
                           "endian: big\nencoding: gzip\n\n") +
                        gzip(to_bytes(values, true)));
  expect_samples(read_volume(path), values);

  // For gzip, byte skip counts decompressed bytes.
  const std::string skip = tmp.file("d.nrrd");
  write_bytes(skip, header("type: uint16\ndimension: 3\nsizes: 5 4 3\nendian: little\n"
                           "encoding: gz\nbyte skip: 6\n\n") +
                        gzip("SKIPME" + to_bytes(values)));
  expect_samples(read_volume(skip), values);
}

TEST(NrrdRead, DetachedHeaderInSubdirectoryWithLineAndByteSkip) {
  TempDir tmp;
  std::filesystem::create_directory(tmp.path() / "data");
  const auto values = ramp<std::int32_t>(3 * 3 * 3, -100000, 12345);
  write_bytes(tmp.file("data/vol.bin"), "first line\nXXXX" + to_bytes(values));
  const std::string path = tmp.file("d.nhdr");
  write_bytes(path, header("type: int\ndimension: 3\nsizes: 3 3 3\nendian: little\n"
                           "encoding: raw\nline skip: 1\nbyte skip: 4\ndata file: data/vol.bin\n"));
  expect_samples(read_volume(path), values);
}

TEST(NrrdRead, DetachedByteSkipMinusOneReadsTheFileEnd) {
  TempDir tmp;
  const auto values = ramp<std::uint8_t>(2 * 3 * 4, 1, 9);
  write_bytes(tmp.file("tail.raw"), std::string(100, 'j') + to_bytes(values));
  const std::string path = tmp.file("e.nhdr");
  write_bytes(path, header("type: uchar\ndimension: 3\nsizes: 2 3 4\nencoding: raw\n"
                           "byte skip: -1\ndata file: tail.raw\n"));
  expect_samples(read_volume(path), values);
}

TEST(NrrdRead, PrintfPatternDataFilesRawAndGzip) {
  TempDir tmp;
  const auto values = ramp<std::int16_t>(4 * 2 * 3, 5, -2);
  const std::string slice_bytes = to_bytes(values);
  for (int z = 0; z < 3; ++z) {
    const std::string slice = slice_bytes.substr(z * 16, 16);
    // files numbered 10, 8, 6 (descending step): slice z is in file 10 - 2z
    const std::string raw_name = std::string("s").append(std::to_string(10 - 2 * z)).append(".raw");
    const std::string gz_name = std::string("g00").append(std::to_string(z + 1)).append(".gz");
    write_bytes(tmp.file(raw_name), slice);
    write_bytes(tmp.file(gz_name), gzip(slice));
  }
  const std::string raw_hdr = tmp.file("p.nhdr");
  write_bytes(raw_hdr, header("type: short\ndimension: 3\nsizes: 4 2 3\nendian: little\n"
                              "encoding: raw\ndata file: s%d.raw 10 6 -2\n"));
  expect_samples(read_volume(raw_hdr), values);
  const std::string gz_hdr = tmp.file("q.nhdr");
  write_bytes(gz_hdr, header("type: short\ndimension: 3\nsizes: 4 2 3\nendian: little\n"
                             "encoding: gzip\ndata file: g%03d.gz 1 3 1 2\n"));
  expect_samples(read_volume(gz_hdr), values);
}

TEST(NrrdRead, ListDataFiles) {
  TempDir tmp;
  const auto values = ramp<float>(2 * 2 * 2, 0.5, 0.25);
  const std::string bytes = to_bytes(values);
  write_bytes(tmp.file("first.raw"), bytes.substr(0, 16));
  write_bytes(tmp.file("second.raw"), bytes.substr(16));
  const std::string path = tmp.file("l.nhdr");
  write_bytes(path, header("type: float\ndimension: 3\nsizes: 2 2 2\nendian: little\n"
                           "encoding: raw\ndata file: LIST\nfirst.raw\nsecond.raw\n"));
  expect_samples(read_volume(path), values);
}

TEST(NrrdRead, AsciiEncoding) {
  TempDir tmp;
  const std::string path = tmp.file("t.nrrd");
  write_bytes(path, header("type: signed char\ndimension: 3\nsizes: 2 2 2\nencoding: text\n\n") +
                        "-128 127\n 0 1\r\n+5\t-6 7.0 1e1\n");
  expect_samples(read_volume(path), std::vector<int>{-128, 127, 0, 1, 5, -6, 7, 10});
  const std::string fpath = tmp.file("tf.nrrd");
  write_bytes(fpath, header("type: double\ndimension: 3\nsizes: 1 1 3\nencoding: ascii\n\n") +
                         "0.1 -2.5e-3 nan");
  const Volume f = read_volume(fpath);
  EXPECT_EQ(f.type, ScalarType::f64);
  EXPECT_EQ(f.at(0), 0.1);
  EXPECT_EQ(f.at(1), -2.5e-3);
  EXPECT_TRUE(std::isnan(f.at(2)));
}

TEST(NrrdRead, FourDimensionalWithSizeOneComponentAxis) {
  TempDir tmp;
  const auto values = ramp<std::uint8_t>(3 * 2 * 2);
  const std::string path = tmp.file("v.nrrd");
  write_bytes(path, header("type: uint8\ndimension: 4\nsizes: 1 3 2 2\nencoding: raw\n"
                           "kinds: vector domain domain domain\n"
                           "space directions: none (1,0,0) (0,2,0) (0,0,3)\n\n") +
                        to_bytes(values));
  const Volume v = read_volume(path);
  EXPECT_EQ(v.grid.dims, (std::array<std::int64_t, 3>{3, 2, 2}));
  expect_vec(v.grid.spacing, {1, 2, 3});
  expect_samples(v, values);
}

TEST(NrrdRead, AllTypeSpellings) {
  const std::vector<std::pair<std::string, ScalarType>> spellings = {
      {"signed char", ScalarType::i8},     {"int8", ScalarType::i8},
      {"int8_t", ScalarType::i8},          {"uchar", ScalarType::u8},
      {"unsigned char", ScalarType::u8},   {"uint8", ScalarType::u8},
      {"uint8_t", ScalarType::u8},         {"short", ScalarType::i16},
      {"short int", ScalarType::i16},      {"signed short", ScalarType::i16},
      {"signed short int", ScalarType::i16}, {"int16", ScalarType::i16},
      {"int16_t", ScalarType::i16},        {"ushort", ScalarType::u16},
      {"unsigned short", ScalarType::u16}, {"unsigned short int", ScalarType::u16},
      {"uint16", ScalarType::u16},         {"uint16_t", ScalarType::u16},
      {"int", ScalarType::i32},            {"signed int", ScalarType::i32},
      {"int32", ScalarType::i32},          {"int32_t", ScalarType::i32},
      {"uint", ScalarType::u32},           {"unsigned int", ScalarType::u32},
      {"uint32", ScalarType::u32},         {"uint32_t", ScalarType::u32},
      {"float", ScalarType::f32},          {"double", ScalarType::f64}};
  TempDir tmp;
  for (const auto& [name, type] : spellings) {
    const std::string path = tmp.file("s.nrrd");
    const std::size_t n = 8 * scalar_size(type);
    write_bytes(path, header("type: " + name + "\ndimension: 3\nsizes: 2 2 2\nendian: little\n"
                             "encoding: raw\n\n") +
                          std::string(n, '\0'));
    EXPECT_EQ(read_volume(path).type, type) << name;
  }
}

TEST(NrrdRead, ShippedCtHeadLoads) {
  const std::string path = source_dir() + "/data/ct_headsq/quarter.nhdr";
  const Volume v = read_volume(path);
  EXPECT_EQ(v.grid.dims, (std::array<std::int64_t, 3>{64, 64, 93}));
  expect_vec(v.grid.spacing, {3.2, 3.2, 1.5});
  EXPECT_EQ(v.type, ScalarType::i16);
  double lo = 1e9, hi = -1e9;
  for (std::int64_t i = 0; i < v.grid.num_samples(); ++i) {
    lo = std::min(lo, v.at(i));
    hi = std::max(hi, v.at(i));
  }
  EXPECT_EQ(lo, 0);
  EXPECT_EQ(hi, 3926);
}

// ------------------------------------------------------------------------------- bad input

class NrrdBad : public ::testing::Test {
 protected:
  std::string write(const std::string& fields, const std::string& data = "") {
    const std::string path = tmp.file("bad.nrrd");
    write_bytes(path, header(fields) + "\n" + data);
    return path;
  }
  TempDir tmp;
};

TEST_F(NrrdBad, MissingRequiredField) {
  expect_read_error(write("dimension: 3\nsizes: 2 2 2\nencoding: raw\n"),
                    Status::invalid_input, {"missing required field 'type'"});
}

TEST_F(NrrdBad, NotANrrdFile) {
  const std::string path = tmp.file("x.nrrd");
  write_bytes(path, "hello world\n");
  expect_read_error(path, Status::invalid_input, {"not a NRRD file"});
}

TEST_F(NrrdBad, ZeroAndNegativeDims) {
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 0 2 2\nencoding: raw\n"),
                    Status::invalid_input, {"sizes", "at least 1"});
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 2 -2 2\nencoding: raw\n"),
                    Status::invalid_input, {"sizes", "at least 1"});
}

TEST_F(NrrdBad, NonNumericHeaderValues) {
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 2 two 2\nencoding: raw\n"),
                    Status::invalid_input, {"non-numeric value 'two' for sizes"});
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 2 2 2\nspacings: 1 x 1\nencoding: raw\n"),
                    Status::invalid_input, {"non-numeric value 'x' for spacings"});
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"
                          "space directions: (1,0,0) (0,1,q) (0,0,1)\n"),
                    Status::invalid_input, {"non-numeric value 'q' for space directions"});
}

TEST_F(NrrdBad, DimsOverflowOrExceedMemory) {
  expect_read_error(write("type: double\ndimension: 3\nsizes: 4000000000 4000000000 4000000000\n"
                          "encoding: raw\nendian: little\n"),
                    Status::invalid_input, {"4000000000x4000000000x4000000000", "overflow"});
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 100000 100000 100000\nencoding: raw\n"),
                    Status::invalid_input, {"100000x100000x100000", "memory available"});
}

TEST_F(NrrdBad, UnsupportedTypeAndEncoding) {
  expect_read_error(write("type: block\nblock size: 4\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"),
                    Status::unsupported, {"type 'block'"});
  expect_read_error(write("type: int64\ndimension: 3\nsizes: 2 2 2\nencoding: raw\nendian: little\n"),
                    Status::unsupported, {"64-bit integer"});
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: bzip2\n"),
                    Status::unsupported, {"encoding 'bzip2'"});
  expect_read_error(write("type: uint8\ndimension: 5\nsizes: 2 2 2 2 2\nencoding: raw\n"),
                    Status::unsupported, {"more than three axes"});
}

TEST_F(NrrdBad, MissingEndianForMultiByteData) {
  expect_read_error(write("type: short\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n", std::string(16, 'a')),
                    Status::invalid_input, {"missing 'endian'"});
}

TEST_F(NrrdBad, TruncatedRawData) {
  expect_read_error(write("type: short\ndimension: 3\nsizes: 2 2 2\nencoding: raw\nendian: little\n",
                          std::string(15, 'a')),
                    Status::invalid_input, {"truncated", "expected 16 bytes", "file has"});
}

TEST_F(NrrdBad, CorruptAndShortAndLongGzip) {
  std::string z = gzip(std::string(64, 'q'));
  z[12] = static_cast<char>(z[12] ^ 0x55);
  z[13] = static_cast<char>(z[13] ^ 0x55);
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: gzip\n", z),
                    Status::invalid_input, {"corrupt compressed data"});
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: gzip\n",
                          gzip(std::string(63, 'q'))),
                    Status::invalid_input, {"truncated compressed data"});
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: gzip\n",
                          gzip(std::string(65, 'q'))),
                    Status::invalid_input, {"larger than expected", "64 bytes"});
  // A cut-off stream: the first half of a valid gzip member.
  const std::string full = gzip(to_bytes(ramp<std::uint8_t>(64, 0, 7)));
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: gzip\n",
                          full.substr(0, full.size() / 2)),
                    Status::invalid_input, {"truncated compressed data"});
}

TEST_F(NrrdBad, CompressedDataTooSmallIsRejectedBeforeAllocating) {
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 1000 1000 1000\nencoding: gzip\n",
                          gzip("abc")),
                    Status::invalid_input, {"cannot inflate to the 1000000000 bytes"});
}

TEST_F(NrrdBad, MissingDetachedDataFileIsNamed) {
  const std::string path = tmp.file("m.nhdr");
  write_bytes(path, header("type: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"
                           "data file: slices/nothere.%d 1 2 1\n"));
  expect_read_error(path, Status::invalid_input, {"data file", "slices/nothere.1", "not found"});
}

TEST_F(NrrdBad, DataFileCountMismatch) {
  write_bytes(tmp.file("f.1"), "abcd");
  write_bytes(tmp.file("f.2"), "abcd");
  write_bytes(tmp.file("f.3"), "abcd");
  const std::string path = tmp.file("c.nhdr");
  write_bytes(path, header("type: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"
                           "data file: f.%d 1 3 1\n"));
  expect_read_error(path, Status::invalid_input, {"3 data files do not divide 8 samples"});
}

TEST_F(NrrdBad, BadAsciiValues) {
  expect_read_error(write("type: uint8\ndimension: 3\nsizes: 2 1 1\nencoding: text\n", "1 300\n"),
                    Status::invalid_input, {"out of range for uint8", "'300'"});
  expect_read_error(write("type: float\ndimension: 3\nsizes: 2 1 1\nencoding: text\n", "1 abc\n"),
                    Status::invalid_input, {"non-numeric value 'abc'"});
  expect_read_error(write("type: float\ndimension: 3\nsizes: 3 1 1\nencoding: text\n", "1 2\n"),
                    Status::invalid_input, {"truncated", "2 of 3"});
}

}  // namespace
}  // namespace adamesh
