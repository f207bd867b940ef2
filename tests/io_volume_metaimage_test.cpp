// MetaImage reader tests: .mhd + raw, .mha LOCAL, zlib-compressed data, LIST and pattern data
// files, byte orders, HeaderSize, ASCII data, TransformMatrix, and the bad-input cases.
#include "io_volume_test_util.h"

namespace adamesh {
namespace {

using namespace testutil;

TEST(MetaImageRead, MhdWithRawFileTransformAndOffset) {
  TempDir tmp;
  const auto values = ramp<std::int16_t>(4 * 3 * 2, -300, 25);
  write_bytes(tmp.file("v.raw"), to_bytes(values));
  const std::string path = tmp.file("v.mhd");
  write_bytes(path, "ObjectType = Image\nNDims = 3\nDimSize = 4 3 2\nElementType = MET_SHORT\n"
                    "ElementSpacing = 0.5 2 3\nOffset = 1 -2 3.5\n"
                    "TransformMatrix = 0 1 0 0 0 1 1 0 0\nAnatomicalOrientation = RAI\n"
                    "ElementByteOrderMSB = False\nElementDataFile = v.raw\n");
  const Volume v = read_volume(path);
  EXPECT_EQ(v.format, "MetaImage");
  EXPECT_EQ(v.type, ScalarType::i16);
  EXPECT_EQ(v.grid.dims, (std::array<std::int64_t, 3>{4, 3, 2}));
  expect_vec(v.grid.spacing, {0.5, 2, 3});
  expect_vec(v.grid.origin, {1, -2, 3.5});
  // Consecutive triples are the world directions of i, j, k.
  expect_mat(v.grid.direction, Mat3::from_columns({0, 1, 0}, {0, 0, 1}, {1, 0, 0}));
  expect_vec(v.grid.to_world({2, 1, 1}), {1 + 3, -2 + 1, 3.5 + 2});
  expect_samples(v, values);
}

TEST(MetaImageRead, MhaLocalBigEndianWithoutObjectType) {
  TempDir tmp;
  const auto values = ramp<float>(3 * 3 * 3, -1, 0.125);
  const std::string path = tmp.file("v.mha");
  write_bytes(path, "NDims = 3\r\nDimSize = 3 3 3\r\nElementSize = 2 2 2\r\nElementType = MET_FLOAT\r\n"
                    "BinaryDataByteOrderMSB = True\r\nElementDataFile = LOCAL\r\n" +
                        to_bytes(values, true));
  const Volume v = read_volume(path);
  expect_vec(v.grid.spacing, {2, 2, 2});
  expect_samples(v, values);
}

TEST(MetaImageRead, CompressedDataWithAndWithoutSize) {
  TempDir tmp;
  const auto values = ramp<std::uint16_t>(5 * 4 * 3, 7, 1000);
  const std::string z = compress(to_bytes(values));
  write_bytes(tmp.file("c.zraw"), z);
  const std::string path = tmp.file("c.mhd");
  write_bytes(path, "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
                    "CompressedData = True\nCompressedDataSize = " + std::to_string(z.size()) +
                        "\nDimSize = 5 4 3\nElementType = MET_USHORT\nElementDataFile = c.zraw\n");
  expect_samples(read_volume(path), values);
  const std::string local = tmp.file("c.mha");
  write_bytes(local, "NDims = 3\nCompressedData = True\nDimSize = 5 4 3\nElementType = MET_USHORT\n"
                     "ElementDataFile = LOCAL\n" + gzip(to_bytes(values)));
  expect_samples(read_volume(local), values);
}

TEST(MetaImageRead, ListAndPatternDataFiles) {
  TempDir tmp;
  const auto values = ramp<std::uint8_t>(2 * 2 * 3, 3, 11);
  const std::string bytes = to_bytes(values);
  for (int z = 0; z < 3; ++z) {
    write_bytes(tmp.file(std::string("slice_").append(std::to_string(z)).append(".raw")), bytes.substr(z * 4, 4));
    write_bytes(tmp.file(std::string("img").append(std::to_string(z + 5)).append(".raw")), bytes.substr(z * 4, 4));
  }
  const std::string list = tmp.file("list.mhd");
  write_bytes(list, "NDims = 3\nDimSize = 2 2 3\nElementType = MET_UCHAR\nElementDataFile = LIST 2\n"
                    "slice_0.raw\nslice_1.raw\nslice_2.raw\n");
  expect_samples(read_volume(list), values);
  const std::string pattern = tmp.file("pattern.mhd");
  write_bytes(pattern, "NDims = 3\nDimSize = 2 2 3\nElementType = MET_UCHAR\n"
                       "ElementDataFile = img%d.raw 5 7 1\n");
  expect_samples(read_volume(pattern), values);
}

TEST(MetaImageRead, HeaderSizeSkipsAndMinusOneReadsTheEnd) {
  TempDir tmp;
  const auto values = ramp<std::int32_t>(8, -5, 1000000);
  write_bytes(tmp.file("h.raw"), std::string(10, 'h') + to_bytes(values));
  const std::string skip = tmp.file("skip.mhd");
  write_bytes(skip, "NDims = 3\nDimSize = 2 2 2\nElementType = MET_INT\nHeaderSize = 10\n"
                    "ElementDataFile = h.raw\n");
  expect_samples(read_volume(skip), values);
  const std::string end = tmp.file("end.mhd");
  write_bytes(end, "NDims = 3\nDimSize = 2 2 2\nElementType = MET_INT\nHeaderSize = -1\n"
                   "ElementDataFile = h.raw\n");
  expect_samples(read_volume(end), values);
}

TEST(MetaImageRead, AsciiDataAndFourDimensionalWithUnitSize) {
  TempDir tmp;
  const std::string path = tmp.file("a.mha");
  write_bytes(path, "NDims = 4\nDimSize = 2 1 2 1\nElementSpacing = 1 1 1 1\nElementType = MET_DOUBLE\n"
                    "BinaryData = False\nElementDataFile = LOCAL\n1.5 -2\n3e2 4\n");
  const Volume v = read_volume(path);
  EXPECT_EQ(v.grid.dims, (std::array<std::int64_t, 3>{2, 1, 2}));
  expect_samples(v, std::vector<double>{1.5, -2, 300, 4});
}

TEST(MetaImageBad, MissingFieldsAndBadValues) {
  TempDir tmp;
  const std::string path = tmp.file("b.mhd");
  write_bytes(path, "NDims = 3\nDimSize = 2 2 2\nElementDataFile = x.raw\n");
  expect_read_error(path, Status::invalid_input, {"missing required field 'ElementType'"});
  write_bytes(path, "NDims = 3\nDimSize = 2 2\nElementType = MET_UCHAR\nElementDataFile = x.raw\n");
  expect_read_error(path, Status::invalid_input, {"DimSize needs 3 values, got 2"});
  write_bytes(path, "NDims = 3\nDimSize = 2 2 0\nElementType = MET_UCHAR\nElementDataFile = x.raw\n");
  expect_read_error(path, Status::invalid_input, {"DimSize", "at least 1"});
  write_bytes(path, "NDims = three\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementDataFile = x.raw\n");
  expect_read_error(path, Status::invalid_input, {"non-numeric value 'three' for NDims"});
  write_bytes(path, "NDims = 3\nDimSize = 2 2 2\nElementSpacing = 1 0 1\nElementType = MET_UCHAR\n"
                    "ElementDataFile = x.raw\n");
  expect_read_error(path, Status::invalid_input, {"invalid ElementSpacing"});
  write_bytes(path, "NDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\n");
  expect_read_error(path, Status::invalid_input, {"missing required field 'ElementDataFile'"});
}

TEST(MetaImageBad, UnsupportedTypeChannelsAndObject) {
  TempDir tmp;
  const std::string path = tmp.file("u.mhd");
  write_bytes(path, "NDims = 3\nDimSize = 2 2 2\nElementType = MET_LONG_LONG\nElementDataFile = x.raw\n");
  expect_read_error(path, Status::unsupported, {"ElementType MET_LONG_LONG"});
  write_bytes(path, "NDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementNumberOfChannels = 3\n"
                    "ElementDataFile = x.raw\n");
  expect_read_error(path, Status::unsupported, {"3 channels"});
  write_bytes(path, "ObjectType = Mesh\nNDims = 3\nElementDataFile = x.raw\n");
  expect_read_error(path, Status::unsupported, {"ObjectType Mesh"});
  write_bytes(path, "NDims = 4\nDimSize = 2 2 2 5\nElementType = MET_UCHAR\nElementDataFile = x.raw\n");
  expect_read_error(path, Status::unsupported, {"only 3-D"});
}

TEST(MetaImageBad, MissingTruncatedAndCorruptData) {
  TempDir tmp;
  const std::string path = tmp.file("d.mhd");
  write_bytes(path, "NDims = 3\nDimSize = 2 2 2\nElementType = MET_USHORT\nElementDataFile = gone.raw\n");
  expect_read_error(path, Status::invalid_input, {"data file", "gone.raw", "not found"});
  write_bytes(tmp.file("short.raw"), std::string(15, 's'));
  write_bytes(path, "NDims = 3\nDimSize = 2 2 2\nElementType = MET_USHORT\nElementDataFile = short.raw\n");
  expect_read_error(path, Status::invalid_input, {"truncated", "expected 16 bytes"});
  std::string z = compress(std::string(16, 'z'));
  z[2] = static_cast<char>(0xff);  // first deflate block: reserved block type 3
  write_bytes(tmp.file("bad.zraw"), z);
  write_bytes(path, "NDims = 3\nDimSize = 2 2 2\nElementType = MET_USHORT\nCompressedData = True\n"
                    "ElementDataFile = bad.zraw\n");
  expect_read_error(path, Status::invalid_input, {"corrupt compressed data"});
  write_bytes(tmp.file("long.zraw"), compress(std::string(17, 'z')));
  write_bytes(path, "NDims = 3\nDimSize = 2 2 2\nElementType = MET_USHORT\nCompressedData = True\n"
                    "ElementDataFile = long.zraw\n");
  expect_read_error(path, Status::invalid_input, {"larger than expected"});
}

}  // namespace
}  // namespace adamesh
