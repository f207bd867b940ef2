// VTK legacy STRUCTURED_POINTS reader tests: ASCII and big-endian BINARY, version-1.0 headers
// with blank lines and ASPECT_RATIO, arrays before and after the scalars, bad input.
#include "io_volume_test_util.h"

namespace adamesh {
namespace {

using namespace testutil;

const std::string kHead = "# vtk DataFile Version 3.0\ntest volume\n";

TEST(VtkLegacyRead, AsciiShortWithSpacingOrigin) {
  TempDir tmp;
  const std::string path = tmp.file("a.vtk");
  write_bytes(path, kHead + "ASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 3 2 2\nSPACING 0.5 1 2\n"
                            "ORIGIN -1 0 10\nPOINT_DATA 12\nSCALARS density short 1\nLOOKUP_TABLE default\n"
                            "1 2 3\n-4 5 6\n7 8 9 10\n-32768 32767\n");
  const Volume v = read_volume(path);
  EXPECT_EQ(v.format, "VTK legacy");
  EXPECT_EQ(v.type, ScalarType::i16);
  EXPECT_EQ(v.grid.dims, (std::array<std::int64_t, 3>{3, 2, 2}));
  expect_vec(v.grid.spacing, {0.5, 1, 2});
  expect_vec(v.grid.origin, {-1, 0, 10});
  expect_samples(v, std::vector<int>{1, 2, 3, -4, 5, 6, 7, 8, 9, 10, -32768, 32767});
}

TEST(VtkLegacyRead, BinaryBigEndianFloatFollowedByVectors) {
  TempDir tmp;
  const auto values = ramp<float>(2 * 3 * 2, -1.5, 0.75);
  const std::string path = tmp.file("b.vtk");
  write_bytes(path, kHead + "BINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 3 2\nSPACING 1 1 1\n"
                            "ORIGIN 100 80 1\nPOINT_DATA 12\nSCALARS scalars float\nLOOKUP_TABLE default\n" +
                        to_bytes(values, true) + "\nVECTORS vectors float\n" +
                        to_bytes(ramp<float>(36), true) + "\n");
  const Volume v = read_volume(path);
  expect_vec(v.grid.origin, {100, 80, 1});
  expect_samples(v, values);
}

TEST(VtkLegacyRead, Version1BlankLinesAspectRatio) {
  TempDir tmp;
  const auto values = ramp<std::uint8_t>(27, 0, 9);
  const std::string path = tmp.file("old.vtk");
  write_bytes(path, "# vtk DataFile Version 1.0\nIron protein\n\nBINARY\n\nDATASET STRUCTURED_POINTS\n"
                    "DIMENSIONS 3 3 3\nASPECT_RATIO 2.0 1.0 0.5\nORIGIN 0.0 0.0 0.0\n\nPOINT_DATA 27\n"
                    "SCALARS scalars unsigned_char\nLOOKUP_TABLE default\n" +
                        to_bytes(values));
  const Volume v = read_volume(path);
  expect_vec(v.grid.spacing, {2, 1, 0.5});
  expect_samples(v, values);
}

TEST(VtkLegacyRead, ArraysBeforeTheScalarsAreSkipped) {
  TempDir tmp;
  const auto values = ramp<double>(8, 0.25, -0.5);
  // Binary: CELL_DATA scalars, point VECTORS and a FIELD before the point SCALARS.
  const std::string bin = tmp.file("skip_bin.vtk");
  write_bytes(bin, kHead + "BINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\nORIGIN 0 0 0\n"
                           "SPACING 1 1 1\nCELL_DATA 1\nSCALARS c int 1\nLOOKUP_TABLE default\n" +
                       to_bytes(std::vector<std::int32_t>{42}, true) +
                       "\nPOINT_DATA 8\nVECTORS v double\n" + to_bytes(ramp<double>(24), true) +
                       "\nFIELD fd 1\nlabels 2 8 unsigned_short\n" + to_bytes(ramp<std::uint16_t>(16), true) +
                       "\nSCALARS s double\nLOOKUP_TABLE default\n" + to_bytes(values, true) + "\n");
  expect_samples(read_volume(bin), values);
}

TEST(VtkLegacyRead, AsciiNormalsThenScalarsWithoutLookupTable) {
  TempDir tmp;
  std::string normals;
  for (int i = 0; i < 24; ++i) normals += std::to_string(i % 3) + (i % 6 == 5 ? "\n" : " ");
  const std::string path = tmp.file("n.vtk");
  write_bytes(path, kHead + "ASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\nPOINT_DATA 8\n"
                            "NORMALS n float\n" + normals + "SCALARS s unsigned_short\n9 8 7 6 5 4 3 2\n");
  expect_samples(read_volume(path), std::vector<int>{9, 8, 7, 6, 5, 4, 3, 2});
}

TEST(VtkLegacyBad, UnsupportedDatasetAndArrays) {
  TempDir tmp;
  const std::string path = tmp.file("u.vtk");
  write_bytes(path, kHead + "ASCII\nDATASET STRUCTURED_GRID\nDIMENSIONS 2 2 2\n");
  expect_read_error(path, Status::unsupported, {"STRUCTURED_GRID"});
  write_bytes(path, kHead + "ASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 1 1 2\nPOINT_DATA 2\n"
                            "SCALARS rgb float 3\nLOOKUP_TABLE default\n1 2 3 4 5 6\n");
  expect_read_error(path, Status::unsupported, {"3 components"});
  write_bytes(path, kHead + "ASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 1 1 2\nPOINT_DATA 2\n"
                            "SCALARS b bit\nLOOKUP_TABLE default\n0 1\n");
  expect_read_error(path, Status::unsupported, {"'bit'"});
}

TEST(VtkLegacyBad, InconsistentTruncatedAndMalformed) {
  TempDir tmp;
  const std::string path = tmp.file("b.vtk");
  write_bytes(path, "not vtk\n");
  expect_read_error(path, Status::invalid_input, {"not a VTK legacy file"});
  write_bytes(path, kHead + "BINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\nPOINT_DATA 9\n");
  expect_read_error(path, Status::invalid_input, {"POINT_DATA 9 does not match DIMENSIONS 2x2x2"});
  write_bytes(path, kHead + "BINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\nPOINT_DATA 8\n"
                            "SCALARS s short\nLOOKUP_TABLE default\n" + std::string(15, 'x'));
  expect_read_error(path, Status::invalid_input, {"truncated", "expected 16 bytes"});
  write_bytes(path, kHead + "ASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 x 2\n");
  expect_read_error(path, Status::invalid_input, {"non-numeric value 'x' for DIMENSIONS"});
  write_bytes(path, kHead + "ASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 0 2\nPOINT_DATA 0\n");
  expect_read_error(path, Status::invalid_input, {"2x0x2", "at least 1"});
  write_bytes(path, kHead + "ASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\nPOINT_DATA 8\n"
                            "VECTORS v float\n1 2 3\n");
  expect_read_error(path, Status::invalid_input, {"truncated", "ASCII attribute array"});
  write_bytes(path, kHead + "ASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 1 1 1\nSPACING 1 0 1\n");
  expect_read_error(path, Status::invalid_input, {"invalid spacing 0"});
}

}  // namespace
}  // namespace adamesh
