// read_volume() dispatch, headerless raw volumes and the bad-input cases common to all formats
// (missing, unreadable, empty, directory, unknown format, extension/content mismatch).
#include <sys/stat.h>
#include <unistd.h>

#include "io_volume_test_util.h"

namespace adamesh {
namespace {

using namespace testutil;

TEST(ReadVolume, FormatForExtensions) {
  EXPECT_EQ(volume_format_for("x.nrrd"), "NRRD");
  EXPECT_EQ(volume_format_for("x.NHDR"), "NRRD");
  EXPECT_EQ(volume_format_for("x.mhd"), "MetaImage");
  EXPECT_EQ(volume_format_for("x.mha"), "MetaImage");
  EXPECT_EQ(volume_format_for("x.nii.gz"), "NIfTI-1");
  EXPECT_EQ(volume_format_for("x.vtk"), "VTK legacy");
  EXPECT_EQ(volume_format_for("x.vti"), "VTK XML ImageData");
  EXPECT_EQ(volume_format_for("x.slc"), "VolVis SLC");
  EXPECT_EQ(volume_format_for("x.mrc"), "MRC");
  EXPECT_EQ(volume_format_for("x.map"), "MRC");
  EXPECT_EQ(volume_format_for("x.ccp4"), "MRC");
  EXPECT_EQ(volume_format_for("x.raw"), "raw");
  EXPECT_EQ(volume_format_for("x.unknown"), "");
  RawOptions raw;
  raw.dims = std::array<std::int64_t, 3>{2, 2, 2};
  EXPECT_EQ(volume_format_for("x.nrrd", raw), "raw");
}

TEST(ReadVolume, UnknownExtensionIsIdentifiedByMagic) {
  TempDir tmp;
  const std::string path = tmp.file("volume.dat");
  write_bytes(path, "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 1 1 2\nencoding: raw\n\nab");
  EXPECT_EQ(volume_format_for(path), "NRRD");
  const Volume v = read_volume(path);
  EXPECT_EQ(v.format, "NRRD");
  EXPECT_EQ(v.at(1), 'b');
}

TEST(RawRead, DimsTypeSpacingOriginEndianHeader) {
  TempDir tmp;
  const auto values = ramp<std::uint16_t>(3 * 4 * 5, 1000, 321);
  const std::string path = tmp.file("v.raw");
  write_bytes(path, "HEADER" + to_bytes(values, true));
  RawOptions raw;
  raw.dims = std::array<std::int64_t, 3>{3, 4, 5};
  raw.type = ScalarType::u16;
  raw.spacing = {0.5, 0.25, 2};
  raw.origin = {-1, 2, -3};
  raw.big_endian = true;
  raw.header_bytes = 6;
  const Volume v = read_volume(path, raw);
  EXPECT_EQ(v.format, "raw");
  EXPECT_EQ(v.source, path);
  EXPECT_EQ(v.grid.dims, (std::array<std::int64_t, 3>{3, 4, 5}));
  expect_vec(v.grid.spacing, {0.5, 0.25, 2});
  expect_vec(v.grid.origin, {-1, 2, -3});
  EXPECT_TRUE(v.grid.axis_aligned());
  expect_samples(v, values);
}

TEST(RawRead, AnyExtensionWithDims) {
  TempDir tmp;
  const auto values = ramp<float>(8, -1, 0.5);
  const std::string path = tmp.file("v.nrrd");  // raw options win over the extension
  write_bytes(path, to_bytes(values));
  RawOptions raw;
  raw.dims = std::array<std::int64_t, 3>{2, 2, 2};
  raw.type = ScalarType::f32;
  expect_samples(read_volume(path, raw), values);
}

TEST(RawBad, MissingOptionsAreNamed) {
  TempDir tmp;
  const std::string path = tmp.file("v.raw");
  write_bytes(path, std::string(8, 'x'));
  expect_read_error(path, Status::invalid_input, {"--dims", "--type", "both missing"});
  RawOptions raw;
  raw.dims = std::array<std::int64_t, 3>{2, 2, 2};
  expect_read_error(path, Status::invalid_input, {"--type T (missing)"}, raw);
  RawOptions typed;
  typed.type = ScalarType::u8;
  expect_read_error(path, Status::invalid_input, {"--dims X,Y,Z (missing)"}, typed);
}

TEST(RawBad, SizeMismatchSaysWhichIsLarger) {
  TempDir tmp;
  const std::string path = tmp.file("v.raw");
  write_bytes(path, std::string(17, 'x'));
  RawOptions raw;
  raw.dims = std::array<std::int64_t, 3>{2, 2, 2};
  raw.type = ScalarType::i16;
  expect_read_error(path, Status::invalid_input, {"size mismatch", "need 16 bytes", "has 17", "file is larger"}, raw);
  write_bytes(path, std::string(15, 'x'));
  expect_read_error(path, Status::invalid_input, {"need 16 bytes", "has 15", "file is smaller"}, raw);
  raw.header_bytes = 4;
  write_bytes(path, std::string(16, 'x'));
  expect_read_error(path, Status::invalid_input, {"after 4 header bytes", "need 20 bytes", "smaller"}, raw);
}

TEST(RawBad, InvalidDimsOverflowAndMemory) {
  TempDir tmp;
  const std::string path = tmp.file("v.raw");
  write_bytes(path, std::string(8, 'x'));
  RawOptions raw;
  raw.type = ScalarType::u8;
  raw.dims = std::array<std::int64_t, 3>{0, 2, 2};
  expect_read_error(path, Status::invalid_input, {"0x2x2", "at least 1"}, raw);
  raw.dims = std::array<std::int64_t, 3>{-4, 2, 2};
  expect_read_error(path, Status::invalid_input, {"-4x2x2"}, raw);
  raw.dims = std::array<std::int64_t, 3>{std::int64_t(1) << 40, std::int64_t(1) << 40, 16};
  expect_read_error(path, Status::invalid_input, {"overflow"}, raw);
  raw.dims = std::array<std::int64_t, 3>{1 << 20, 1 << 20, 1 << 10};
  expect_read_error(path, Status::invalid_input, {"memory available"}, raw);
}

TEST(VolumeBad, MissingFile) {
  TempDir tmp;
  const std::string path = tmp.file("nothere.nrrd");
  expect_read_error(path, Status::invalid_input, {"file not found"});
}

TEST(VolumeBad, UnreadableFile) {
  TempDir tmp;
  const std::string path = tmp.file("secret.nrrd");
  write_bytes(path, "NRRD0004\n");
  // A path through a regular file fails to open for every user (ENOTDIR).
  expect_read_error(path + "/inner.nrrd", Status::invalid_input, {"cannot open", "Not a directory"});
  ASSERT_EQ(::chmod(path.c_str(), 0), 0);
  if (::access(path.c_str(), R_OK) == 0) GTEST_SKIP() << "running with permission to read mode-000 files (root)";
  expect_read_error(path, Status::invalid_input, {"cannot open", "Permission denied"});
}

TEST(VolumeBad, EmptyFileAndDirectory) {
  TempDir tmp;
  for (const char* name : {"e.nrrd", "e.mhd", "e.nii", "e.vtk", "e.vti", "e.slc", "e.mrc"}) {
    const std::string path = tmp.file(name);
    write_bytes(path, "");
    expect_read_error(path, Status::invalid_input, {"file is empty"});
  }
  std::filesystem::create_directory(tmp.path() / "dir.nrrd");
  expect_read_error(tmp.file("dir.nrrd"), Status::invalid_input, {"is a directory"});
}

TEST(VolumeBad, UnknownFormat) {
  TempDir tmp;
  const std::string path = tmp.file("data.xyz");
  write_bytes(path, "just some bytes");
  expect_read_error(path, Status::unsupported, {"unknown volume format", "'.xyz'", "--dims"});
}

TEST(VolumeBad, ExtensionContradictsContent) {
  TempDir tmp;
  const std::string path = tmp.file("head.mhd");
  write_bytes(path, "NRRD0004\ntype: uint8\n");
  expect_read_error(path, Status::invalid_input, {"extension says MetaImage", "content is NRRD"});
}

}  // namespace
}  // namespace adamesh
