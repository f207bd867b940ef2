// NIfTI-1 and NIfTI-2 reader (.nii, .nii.gz, and .hdr/.img pairs, each optionally gzipped),
// following nifti1.h / nifti2.h of nifti_clib (the header structs used here come from Debian's
// libnifti2-dev; nifti_swap_as_nifti1/2 swap foreign-endian headers and
// nifti_quatern_to_dmat44 converts the qform quaternion — both compute only, never print).
//
// World space, in the file's own frame (RAS+ for NIfTI; nothing is flipped):
//   sform_code > 0: index → world is the srow_x/y/z affine;
//   else qform_code > 0: rotation from the quaternion, pixdim spacing, qfac = pixdim[0] sign
//                        applied to the k axis, origin qoffset;
//   else: spacing |pixdim[1..3]| (0 → 1), identity direction, origin 0.
// Scaling: scl_slope 0 / non-finite or (slope 1, inter 0) means unscaled samples of the file's
// type; otherwise the samples become v·slope + inter in float32 (float64 data stays float64),
// converted in place in the one sample buffer. 4-D files with one volume (dim[4..7] = 1) load;
// more volumes are Status::unsupported, as are complex, RGB, 64-bit integer and float128 data
// and Analyze 7.5 headers (no NIfTI magic).
#include <nifti2_io.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "adamesh/error.h"
#include "io_util.h"
#include "volume_readers.h"

namespace adamesh::detail {
namespace {

struct Info {
  int version = 1;
  bool swapped = false;
  bool single_file = true;
  std::int64_t dim[8] = {};
  int datatype = 0;
  double pixdim[8] = {};
  std::int64_t vox_offset = 0;
  double slope = 0, inter = 0;
  int qform_code = 0, sform_code = 0;
  double quatern[6] = {};  // b, c, d, qoffset x, y, z
  double srow[3][4] = {};
};

// Reads the first n header bytes from a plain or gzipped file.
class HeaderSource {
 public:
  HeaderSource(const std::string& path, bool gz) : file_(path) {
    if (gz) reader_.emplace(file_, 0, file_.size(), ZWrap::gzip);
  }
  void read(void* dst, std::size_t n) {
    if (reader_) reader_->read_exact(dst, n, "header");
    else file_.read_exact(pos_, dst, n, "header");
    pos_ += n;
  }
  const InputFile& file() const { return file_; }
  InflateReader* reader() { return reader_ ? &*reader_ : nullptr; }
  std::uint64_t pos() const { return pos_; }

 private:
  InputFile file_;
  std::optional<InflateReader> reader_;
  std::uint64_t pos_ = 0;
};

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && to_lower(s.substr(s.size() - suffix.size())) == suffix;
}

Info parse_header(const std::string& path, HeaderSource& src) {
  Info info;
  alignas(8) unsigned char buf[sizeof(nifti_2_header)] = {};
  src.read(buf, sizeof(nifti_1_header));
  std::int32_t sizeof_hdr = 0;
  std::memcpy(&sizeof_hdr, buf, 4);
  const std::int32_t swapped_size = static_cast<std::int32_t>(__builtin_bswap32(static_cast<std::uint32_t>(sizeof_hdr)));
  if (sizeof_hdr == 348 || swapped_size == 348) {
    nifti_1_header h;
    std::memcpy(&h, buf, sizeof h);
    info.swapped = sizeof_hdr != 348;
    if (info.swapped) nifti_swap_as_nifti1(&h);
    const bool n1 = std::memcmp(h.magic, "n+1\0", 4) == 0, ni1 = std::memcmp(h.magic, "ni1\0", 4) == 0;
    if (!n1 && !ni1)
      fail(Status::unsupported, path + ": Analyze 7.5 header (no NIfTI magic): not supported");
    info.single_file = n1;
    for (int i = 0; i < 8; ++i) info.dim[i] = h.dim[i], info.pixdim[i] = h.pixdim[i];
    info.datatype = h.datatype;
    if (!std::isfinite(h.vox_offset) || h.vox_offset < 0 || h.vox_offset > 1e15 ||
        h.vox_offset != std::floor(h.vox_offset))
      fail_input(path, "invalid vox_offset " + format_number(h.vox_offset));
    info.vox_offset = static_cast<std::int64_t>(h.vox_offset);
    info.slope = h.scl_slope;
    info.inter = h.scl_inter;
    info.qform_code = h.qform_code;
    info.sform_code = h.sform_code;
    const float q[6] = {h.quatern_b, h.quatern_c, h.quatern_d, h.qoffset_x, h.qoffset_y, h.qoffset_z};
    for (int i = 0; i < 6; ++i) info.quatern[i] = q[i];
    for (int c = 0; c < 4; ++c) {
      info.srow[0][c] = h.srow_x[c];
      info.srow[1][c] = h.srow_y[c];
      info.srow[2][c] = h.srow_z[c];
    }
  } else if (sizeof_hdr == 540 || swapped_size == 540) {
    src.read(buf + sizeof(nifti_1_header), sizeof(nifti_2_header) - sizeof(nifti_1_header));
    nifti_2_header h;
    std::memcpy(&h, buf, sizeof h);
    info.version = 2;
    info.swapped = sizeof_hdr != 540;
    if (info.swapped) nifti_swap_as_nifti2(&h);
    const bool n2 = std::memcmp(h.magic, "n+2\0", 4) == 0, ni2 = std::memcmp(h.magic, "ni2\0", 4) == 0;
    if (!n2 && !ni2) fail_input(path, "not a NIfTI-2 file (bad magic)");
    info.single_file = n2;
    for (int i = 0; i < 8; ++i) info.dim[i] = h.dim[i], info.pixdim[i] = h.pixdim[i];
    info.datatype = h.datatype;
    if (h.vox_offset < 0) fail_input(path, "invalid vox_offset " + std::to_string(h.vox_offset));
    info.vox_offset = h.vox_offset;
    info.slope = h.scl_slope;
    info.inter = h.scl_inter;
    info.qform_code = h.qform_code;
    info.sform_code = h.sform_code;
    const double q[6] = {h.quatern_b, h.quatern_c, h.quatern_d, h.qoffset_x, h.qoffset_y, h.qoffset_z};
    for (int i = 0; i < 6; ++i) info.quatern[i] = q[i];
    for (int c = 0; c < 4; ++c) {
      info.srow[0][c] = h.srow_x[c];
      info.srow[1][c] = h.srow_y[c];
      info.srow[2][c] = h.srow_z[c];
    }
  } else {
    fail_input(path, "not a NIfTI file (header size " + std::to_string(sizeof_hdr) +
                         ", expected 348 or 540)");
  }
  return info;
}

ScalarType nifti_type(const std::string& path, int dt) {
  switch (dt) {
    case DT_UINT8: return ScalarType::u8;
    case DT_INT8: return ScalarType::i8;
    case DT_UINT16: return ScalarType::u16;
    case DT_INT16: return ScalarType::i16;
    case DT_UINT32: return ScalarType::u32;
    case DT_INT32: return ScalarType::i32;
    case DT_FLOAT32: return ScalarType::f32;
    case DT_FLOAT64: return ScalarType::f64;
    default: break;
  }
  const char* name = nullptr;
  switch (dt) {
    case DT_BINARY: name = "binary (1 bit)"; break;
    case DT_COMPLEX64: name = "complex64"; break;
    case DT_COMPLEX128: name = "complex128"; break;
    case DT_COMPLEX256: name = "complex256"; break;
    case DT_RGB24: name = "RGB24"; break;
    case DT_RGBA32: name = "RGBA32"; break;
    case DT_INT64: name = "int64"; break;
    case DT_UINT64: name = "uint64"; break;
    case DT_FLOAT128: name = "float128"; break;
    default: break;
  }
  if (name) fail(Status::unsupported, path + ": NIfTI datatype " + name + " is not supported");
  fail_input(path, "unknown NIfTI datatype " + std::to_string(dt));
}

// Grid from sform / qform / pixdim (see the file comment).
Grid nifti_grid(const std::string& path, const Info& in) {
  Grid g;
  for (int a = 0; a < 3; ++a) g.dims[a] = in.dim[a + 1];
  if (in.sform_code > 0) {
    Vec3 cols[3];
    for (int c = 0; c < 3; ++c) cols[c] = {in.srow[0][c], in.srow[1][c], in.srow[2][c]};
    set_axes_from_vectors(g, cols[0], cols[1], cols[2], path, "sform");
    g.origin = {in.srow[0][3], in.srow[1][3], in.srow[2][3]};
  } else if (in.qform_code > 0) {
    const double qfac = in.pixdim[0] < 0 ? -1.0 : 1.0;
    const nifti_dmat44 m = nifti_quatern_to_dmat44(in.quatern[0], in.quatern[1], in.quatern[2],
                                                   in.quatern[3], in.quatern[4], in.quatern[5],
                                                   in.pixdim[1], in.pixdim[2], in.pixdim[3], qfac);
    Vec3 cols[3];
    for (int c = 0; c < 3; ++c) cols[c] = {m.m[0][c], m.m[1][c], m.m[2][c]};
    set_axes_from_vectors(g, cols[0], cols[1], cols[2], path, "qform");
    g.origin = {m.m[0][3], m.m[1][3], m.m[2][3]};
  } else {
    for (int a = 0; a < 3; ++a) {
      const double s = std::abs(in.pixdim[a + 1]);
      g.spacing[a] = std::isfinite(s) && s > 0 ? s : 1.0;
    }
  }
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(g.origin[a])) fail_input(path, "non-finite origin in the qform/sform");
  return g;
}

// out[i] = in[i]·slope + inter, in place: the source samples occupy the front of the buffer
// and are no wider than the output, so walking backwards never overwrites an unread sample.
template <class Out, class In>
void scale_in_place(std::byte* data, std::size_t n, double slope, double inter) {
  static_assert(sizeof(In) <= sizeof(Out));
  for (std::size_t i = n; i-- > 0;) {
    In v;
    std::memcpy(&v, data + i * sizeof(In), sizeof(In));
    const Out o = static_cast<Out>(static_cast<double>(v) * slope + inter);
    std::memcpy(data + i * sizeof(Out), &o, sizeof(Out));
  }
}

}  // namespace

Volume read_nifti(const std::string& path) {
  const std::string ext = lower_extension(path);
  std::string header_path = path;
  if (ext == ".img" || ext == ".img.gz")  // the header of a pair is the .hdr next to it
    header_path = path.substr(0, path.size() - ext.size()) + (ext == ".img" ? ".hdr" : ".hdr.gz");
  std::error_code ec;
  if (header_path != path && !std::filesystem::exists(header_path, ec))
    fail_input(path, "header file '" + header_path + "' of the .hdr/.img pair not found");

  HeaderSource src(header_path, ends_with(header_path, ".gz"));
  const Info info = parse_header(header_path, src);
  const std::string fmt = info.version == 1 ? "NIfTI-1" : "NIfTI-2";

  // Dimensions: 3-D, or 4-D..7-D with a single volume.
  if (info.dim[0] < 3 || info.dim[0] > 7) {
    if (info.dim[0] >= 1 && info.dim[0] < 3)
      fail(Status::unsupported, path + ": " + std::to_string(info.dim[0]) + "-D NIfTI: only 3-D volumes are supported");
    fail_input(path, "invalid dim[0] " + std::to_string(info.dim[0]));
  }
  std::int64_t volumes = 1;
  for (int i = 4; i <= info.dim[0]; ++i) {
    if (info.dim[i] < 1) fail_input(path, "invalid dim[" + std::to_string(i) + "] " + std::to_string(info.dim[i]));
    volumes = info.dim[i] > (std::int64_t(1) << 40) / volumes ? (std::int64_t(1) << 40) : volumes * info.dim[i];
  }
  if (volumes > 1)
    fail(Status::unsupported, path + ": 4-D NIfTI with " + std::to_string(volumes) +
                                  " volumes: not supported (only one 3-D volume)");
  const ScalarType file_type = nifti_type(path, info.datatype);
  Grid grid = nifti_grid(path, info);
  const std::size_t src_bytes = checked_volume_bytes(grid.dims, file_type, path);

  const bool scaled = std::isfinite(info.slope) && info.slope != 0 &&
                      !(info.slope == 1 && (info.inter == 0 || !std::isfinite(info.inter)));
  const ScalarType out_type = !scaled ? file_type : (file_type == ScalarType::f64 ? ScalarType::f64 : ScalarType::f32);
  const double inter = std::isfinite(info.inter) ? info.inter : 0.0;

  // Where the samples are: after the header in the same file, or in the .img of a pair.
  std::string data_path = header_path;
  if (!info.single_file) {
    const std::string base = header_path.substr(0, header_path.size() - lower_extension(header_path).size());
    data_path = ends_with(header_path, ".gz") ? base + ".img.gz" : base + ".img";
    if (!std::filesystem::exists(data_path, ec)) {
      const std::string other = ends_with(data_path, ".gz") ? base + ".img" : base + ".img.gz";
      if (std::filesystem::exists(other, ec)) data_path = other;
      else fail_input(path, "data file '" + data_path + "' of the .hdr/.img pair not found");
    }
  } else {
    const std::uint64_t hdr = info.version == 1 ? 348 : 540;
    if (static_cast<std::uint64_t>(info.vox_offset) < hdr)
      fail_input(path, "invalid vox_offset " + std::to_string(info.vox_offset) + " (inside the header)");
  }
  const bool data_gz = ends_with(data_path, ".gz");
  const std::uint64_t offset = static_cast<std::uint64_t>(info.vox_offset);
  std::optional<InputFile> data_file;
  if (data_path != header_path) data_file.emplace(data_path);
  const InputFile& df = data_file ? *data_file : src.file();
  if (!data_gz) {
    require_range(df, offset, src_bytes, "sample data");
  } else if (df.size() < (std::uint64_t(1) << 52) && df.size() * 1100 + 1024 < offset + src_bytes) {
    fail_input(df.path(), "truncated compressed data: " + std::to_string(df.size()) +
                              " bytes cannot inflate to the " + std::to_string(src_bytes) + " bytes of samples");
  }

  Volume v = allocate_volume(grid, out_type, path);
  v.format = fmt;
  if (!data_gz) {
    df.read_exact(offset, v.data.data(), src_bytes, "sample data");
  } else {
    std::optional<InflateReader> own;
    InflateReader* r = nullptr;
    std::uint64_t skip = offset;
    if (data_path == header_path) {
      r = src.reader();
      skip = offset - src.pos();
    } else {
      own.emplace(df, 0, df.size(), ZWrap::gzip);
      r = &*own;
    }
    r->skip(skip, "header extensions before vox_offset");
    r->read_exact(v.data.data(), src_bytes, "sample data");
    r->expect_end(offset + src_bytes);
  }
  const std::size_t n = src_bytes / scalar_size(file_type);
  if (info.swapped) swap_bytes_in_place(v.data.data(), n, scalar_size(file_type));
  if (scaled) {
    const double slope = info.slope;
    dispatch_scalar(file_type, [&](auto zero) {
      using In = decltype(zero);
      if constexpr (std::is_same_v<In, double>) scale_in_place<double, double>(v.data.data(), n, slope, inter);
      else scale_in_place<float, In>(v.data.data(), n, slope, inter);
    });
  }
  return v;
}

}  // namespace adamesh::detail
