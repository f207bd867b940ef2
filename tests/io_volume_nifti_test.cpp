// NIfTI reader tests: synthetic NIfTI-1 and NIfTI-2 files (.nii, .nii.gz, .hdr/.img) with
// sform, qform and pixdim geometry, both byte orders, scaling, 4-D single volumes, extensions,
// and the bad-input cases.
#include <nifti2_io.h>

#include <cmath>

#include "io_volume_test_util.h"

namespace adamesh {
namespace {

using namespace testutil;

struct N1 {
  nifti_1_header h{};
  N1(std::array<int, 3> dims, int datatype, int bitpix) {
    h.sizeof_hdr = 348;
    h.dim[0] = 3;
    for (int a = 0; a < 3; ++a) h.dim[a + 1] = static_cast<short>(dims[a]);
    for (int a = 4; a < 8; ++a) h.dim[a] = 1;
    h.datatype = static_cast<short>(datatype);
    h.bitpix = static_cast<short>(bitpix);
    for (float& p : h.pixdim) p = 1;
    h.vox_offset = 352;
    std::memcpy(h.magic, "n+1\0", 4);
  }
  /// Header + 4 extension bytes (+ padding up to vox_offset) + data.
  std::string file(const std::string& data, bool big_endian = false) const {
    nifti_1_header out = h;
    const bool swap = big_endian == host_is_le();
    if (swap) nifti_swap_as_nifti1(&out);
    std::string bytes(reinterpret_cast<const char*>(&out), sizeof out);
    bytes.resize(static_cast<std::size_t>(h.vox_offset), '\0');
    return bytes + data;
  }
  static bool host_is_le() {
    const std::uint16_t one = 1;
    return *reinterpret_cast<const std::uint8_t*>(&one) == 1;
  }
};

TEST(NiftiRead, Nifti1SformWithRotationAndScaling) {
  TempDir tmp;
  N1 n({4, 3, 2}, DT_INT16, 16);
  n.h.sform_code = NIFTI_XFORM_MNI_152;
  n.h.qform_code = NIFTI_XFORM_SCANNER_ANAT;  // ignored: sform wins
  n.h.quatern_d = 1;
  // i → (0, 0, 2), j → (-3, 0, 0), k → (0, 4, 0)
  const float sx[4] = {0, -3, 0, 10}, sy[4] = {0, 0, 4, -20}, sz[4] = {2, 0, 0, 30};
  std::memcpy(n.h.srow_x, sx, sizeof sx);
  std::memcpy(n.h.srow_y, sy, sizeof sy);
  std::memcpy(n.h.srow_z, sz, sizeof sz);
  const auto values = ramp<std::int16_t>(24, -1000, 77);
  const std::string path = tmp.file("s.nii");
  write_bytes(path, n.file(to_bytes(values)));
  const Volume v = read_volume(path);
  EXPECT_EQ(v.format, "NIfTI-1");
  EXPECT_EQ(v.type, ScalarType::i16);
  EXPECT_EQ(v.grid.dims, (std::array<std::int64_t, 3>{4, 3, 2}));
  expect_vec(v.grid.spacing, {2, 3, 4});
  expect_vec(v.grid.origin, {10, -20, 30});
  expect_mat(v.grid.direction, Mat3::from_columns({0, 0, 1}, {-1, 0, 0}, {0, 1, 0}));
  expect_vec(v.grid.to_world({1, 1, 1}), {10 - 3, -20 + 4, 30 + 2});
  expect_samples(v, values);
  EXPECT_EQ(volume_format_for(path), "NIfTI-1");
}

TEST(NiftiRead, Nifti1QformQuaternionWithNegativeQfac) {
  TempDir tmp;
  N1 n({2, 2, 2}, DT_UINT8, 8);
  n.h.qform_code = NIFTI_XFORM_SCANNER_ANAT;
  n.h.quatern_b = 0;
  n.h.quatern_c = 0;
  n.h.quatern_d = static_cast<float>(std::sqrt(0.5));  // 90° about z
  n.h.qoffset_x = 1;
  n.h.qoffset_y = 2;
  n.h.qoffset_z = 3;
  const float pix[8] = {-1, 2, 3, 4, 1, 1, 1, 1};
  std::memcpy(n.h.pixdim, pix, sizeof pix);
  const auto values = ramp<std::uint8_t>(8, 1, 30);
  const std::string path = tmp.file("q.nii");
  write_bytes(path, n.file(to_bytes(values)));
  const Volume v = read_volume(path);
  expect_vec(v.grid.spacing, {2, 3, 4}, 1e-6);
  expect_vec(v.grid.origin, {1, 2, 3});
  // R = rot_z(90°): i → +y, j → −x; qfac −1 flips k: k → −z.
  expect_mat(v.grid.direction, Mat3::from_columns({0, 1, 0}, {-1, 0, 0}, {0, 0, -1}), 1e-6);
  expect_samples(v, values);
}

TEST(NiftiRead, PixdimOnlyGeometry) {
  TempDir tmp;
  N1 n({2, 1, 3}, DT_FLOAT32, 32);
  const float pix[8] = {1, 0.5f, -2, 0, 1, 1, 1, 1};  // |pixdim|, 0 → 1
  std::memcpy(n.h.pixdim, pix, sizeof pix);
  const std::string path = tmp.file("p.nii");
  write_bytes(path, n.file(to_bytes(ramp<float>(6, 0.5, 0.5))));
  const Volume v = read_volume(path);
  expect_vec(v.grid.spacing, {0.5, 2, 1});
  expect_vec(v.grid.origin, {0, 0, 0});
  EXPECT_TRUE(v.grid.axis_aligned());
}

TEST(NiftiRead, GzippedBigEndianFloatWithExtensionBytes) {
  TempDir tmp;
  N1 n({3, 2, 2}, DT_FLOAT32, 32);
  n.h.vox_offset = 400;  // 48 bytes of extensions/padding
  const auto values = ramp<float>(12, -3, 0.75);
  const std::string path = tmp.file("g.nii.gz");
  write_bytes(path, gzip(n.file(to_bytes(values, true), true)));
  const Volume v = read_volume(path);
  EXPECT_EQ(v.type, ScalarType::f32);
  expect_samples(v, values);
}

TEST(NiftiRead, ScalingConvertsToFloat) {
  TempDir tmp;
  N1 n({2, 2, 1}, DT_UINT8, 8);
  n.h.scl_slope = 2;
  n.h.scl_inter = -1;
  const std::string path = tmp.file("scaled.nii");
  write_bytes(path, n.file(to_bytes(std::vector<std::uint8_t>{0, 1, 100, 255})));
  const Volume v = read_volume(path);
  EXPECT_EQ(v.type, ScalarType::f32);
  expect_samples(v, std::vector<float>{-1, 1, 199, 509});

  N1 d({2, 1, 1}, DT_FLOAT64, 64);
  d.h.scl_slope = 0.5;
  write_bytes(path, d.file(to_bytes(std::vector<double>{3, -4})));
  const Volume vd = read_volume(path);
  EXPECT_EQ(vd.type, ScalarType::f64);
  expect_samples(vd, std::vector<double>{1.5, -2});

  for (auto [slope, inter] : {std::pair<float, float>{1, 0}, {0, 5}}) {  // both mean unscaled
    N1 u({2, 1, 1}, DT_INT16, 16);
    u.h.scl_slope = slope;
    u.h.scl_inter = inter;
    write_bytes(path, u.file(to_bytes(std::vector<std::int16_t>{-7, 9})));
    const Volume vu = read_volume(path);
    EXPECT_EQ(vu.type, ScalarType::i16);
    expect_samples(vu, std::vector<std::int16_t>{-7, 9});
  }
}

TEST(NiftiRead, FourDimensionalSingleVolume) {
  TempDir tmp;
  N1 n({2, 2, 2}, DT_UINT16, 16);
  n.h.dim[0] = 4;
  n.h.dim[4] = 1;
  const auto values = ramp<std::uint16_t>(8, 100, 1000);
  const std::string path = tmp.file("t.nii");
  write_bytes(path, n.file(to_bytes(values)));
  expect_samples(read_volume(path), values);
}

TEST(NiftiRead, HdrImgPair) {
  TempDir tmp;
  N1 n({2, 3, 1}, DT_INT32, 32);
  std::memcpy(n.h.magic, "ni1\0", 4);
  n.h.vox_offset = 0;
  const auto values = ramp<std::int32_t>(6, -70000, 30000);
  nifti_1_header h = n.h;
  write_bytes(tmp.file("pair.hdr"), std::string(reinterpret_cast<const char*>(&h), sizeof h));
  write_bytes(tmp.file("pair.img"), to_bytes(values));
  expect_samples(read_volume(tmp.file("pair.hdr")), values);
  expect_samples(read_volume(tmp.file("pair.img")), values);
}

TEST(NiftiRead, Nifti2WithSform) {
  TempDir tmp;
  nifti_2_header h{};
  h.sizeof_hdr = 540;
  std::memcpy(h.magic, "n+2\0\r\n\032\n", 8);
  h.dim[0] = 3;
  h.dim[1] = 3;
  h.dim[2] = 2;
  h.dim[3] = 2;
  for (int a = 4; a < 8; ++a) h.dim[a] = 1;
  h.datatype = DT_INT8;
  h.bitpix = 8;
  for (double& p : h.pixdim) p = 1;
  h.vox_offset = 544;
  h.sform_code = 1;
  const double sx[4] = {0.5, 0, 0, -1}, sy[4] = {0, 0, -1.5, 2}, sz[4] = {0, 2.5, 0, 7};
  std::memcpy(h.srow_x, sx, sizeof sx);
  std::memcpy(h.srow_y, sy, sizeof sy);
  std::memcpy(h.srow_z, sz, sizeof sz);
  const auto values = ramp<std::int8_t>(12, -6, 1);
  nifti_2_header be = h;
  nifti_swap_as_nifti2(&be);  // a foreign-endian file
  std::string bytes(reinterpret_cast<const char*>(&be), sizeof be);
  bytes.resize(544, '\0');
  const std::string path = tmp.file("n2.nii");
  write_bytes(path, bytes + to_bytes(values));
  const Volume v = read_volume(path);
  EXPECT_EQ(v.format, "NIfTI-2");
  EXPECT_EQ(volume_format_for(path), "NIfTI-2");
  const std::string gz = tmp.file("n2.nii.gz");
  write_bytes(gz, gzip(bytes + to_bytes(values)));
  EXPECT_EQ(volume_format_for(gz), "NIfTI-2");
  expect_samples(read_volume(gz), values);
  expect_vec(v.grid.spacing, {0.5, 2.5, 1.5});
  expect_vec(v.grid.origin, {-1, 2, 7});
  expect_mat(v.grid.direction, Mat3::from_columns({1, 0, 0}, {0, 0, 1}, {0, -1, 0}));
  expect_samples(v, values);
}

TEST(NiftiBad, UnsupportedDataAndDimensions) {
  TempDir tmp;
  const std::string path = tmp.file("u.nii");
  write_bytes(path, N1({2, 2, 2}, DT_COMPLEX64, 64).file(std::string(64, '\0')));
  expect_read_error(path, Status::unsupported, {"datatype complex64"});
  N1 t({2, 2, 2}, DT_UINT8, 8);
  t.h.dim[0] = 4;
  t.h.dim[4] = 5;
  write_bytes(path, t.file(std::string(40, '\0')));
  expect_read_error(path, Status::unsupported, {"4-D NIfTI with 5 volumes"});
  N1 a({2, 2, 2}, DT_UINT8, 8);
  std::memset(a.h.magic, 0, 4);
  write_bytes(path, a.file(std::string(8, '\0')));
  expect_read_error(path, Status::unsupported, {"Analyze 7.5"});
  N1 z({2, 0, 2}, DT_UINT8, 8);
  write_bytes(path, z.file(""));
  expect_read_error(path, Status::invalid_input, {"2x0x2", "at least 1"});
}

TEST(NiftiBad, TruncatedCorruptAndBadOffsets) {
  TempDir tmp;
  const std::string path = tmp.file("t.nii");
  write_bytes(path, N1({4, 4, 4}, DT_INT16, 16).file(std::string(127, '\0')));
  expect_read_error(path, Status::invalid_input, {"truncated", "expected 128 bytes"});
  write_bytes(path, std::string(100, 'n'));
  expect_read_error(path, Status::invalid_input, {"truncated header"});
  N1 o({2, 2, 2}, DT_UINT8, 8);
  o.h.vox_offset = 100;
  write_bytes(path, std::string(reinterpret_cast<const char*>(&o.h), sizeof o.h) + std::string(400, '\0'));
  expect_read_error(path, Status::invalid_input, {"vox_offset 100"});
  const std::string gz = tmp.file("c.nii.gz");
  std::string z = gzip(N1({2, 2, 2}, DT_UINT8, 8).file(std::string(8, 'x')));
  write_bytes(gz, z.substr(0, z.size() - 12));
  expect_read_error(gz, Status::invalid_input, {"truncated compressed data"});
  z[10] = static_cast<char>(0xff);
  write_bytes(gz, z);
  expect_read_error(gz, Status::invalid_input, {"corrupt compressed data"});
  N1 p({2, 2, 2}, DT_UINT8, 8);
  std::memcpy(p.h.magic, "ni1\0", 4);
  p.h.vox_offset = 0;
  nifti_1_header h = p.h;
  write_bytes(tmp.file("lone.hdr"), std::string(reinterpret_cast<const char*>(&h), sizeof h));
  expect_read_error(tmp.file("lone.hdr"), Status::invalid_input, {"lone.img", "not found"});
}

}  // namespace
}  // namespace adamesh
