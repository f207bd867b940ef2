// DICOM series (PS3.3 C.7.6.2 Image Plane module) read with GDCM: the headers of every file are
// scanned (gdcm::Scanner), the files of one SeriesInstanceUID are sorted by the position of
// ImagePositionPatient along the slice normal (row × column of ImageOrientationPatient), the slice
// spacing comes from those positions (not SliceThickness), and the pixels of each slice are
// decoded by gdcm::ImageReader (any transfer syntax GDCM supports) and rescaled with the slice's
// RescaleSlope / RescaleIntercept. The world frame is DICOM's patient frame (LPS, millimetres):
// direction = [row cosines, column cosines, normal], origin = the first slice's position
// (docs/FORMATS.md, "DICOM"). GDCM headers stay in this file.
#include <gdcmAttribute.h>
#include <gdcmDirectory.h>
#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmScanner.h>
#include <gdcmTag.h>
#include <gdcmTrace.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>
#include <type_traits>
#include <utility>
#include <vector>

#include "adamesh/error.h"
#include "io/volume_readers.h"

namespace adamesh::detail {

namespace {

namespace fs = std::filesystem;

const gdcm::Tag kSeriesUid(0x0020, 0x000e);
const gdcm::Tag kSeriesDescription(0x0008, 0x103e);
const gdcm::Tag kModality(0x0008, 0x0060);
const gdcm::Tag kPosition(0x0020, 0x0032);
const gdcm::Tag kOrientation(0x0020, 0x0037);
const gdcm::Tag kPixelSpacing(0x0028, 0x0030);
const gdcm::Tag kRows(0x0028, 0x0010);
const gdcm::Tag kColumns(0x0028, 0x0011);
const gdcm::Tag kFrames(0x0028, 0x0008);

std::string trimmed(const char* s) {
  std::string v = s ? s : "";
  while (!v.empty() && (v.back() == ' ' || v.back() == '\0')) v.pop_back();
  while (!v.empty() && v.front() == ' ') v.erase(v.begin());
  return v;
}

/// Backslash-separated decimal string (DS) values; empty when any is not a number.
std::vector<double> numbers(const std::string& s) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, '\\')) {
    char* end = nullptr;
    const std::string t = trimmed(item.c_str());
    const double v = std::strtod(t.c_str(), &end);
    if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(v)) return {};
    out.push_back(v);
  }
  return out;
}

struct Slice {
  std::string file;
  Vec3 position;
  double along = 0;  // position · normal
};

bool has_dicom_magic(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  char magic[4] = {};
  const bool ok = std::fseek(f, 128, SEEK_SET) == 0 && std::fread(magic, 1, 4, f) == 4;
  std::fclose(f);
  return ok && std::memcmp(magic, "DICM", 4) == 0;
}

/// Why GDCM must not be given a file with the Part 10 preamble, or "" when it may. Debian's GDCM
/// keeps its assertions, and some malformed File Meta Information aborts the process: a meta
/// header cut short (gdcmReader.cxx:385, `is.good()`), an element running past the end of the
/// file (gdcmFileMetaInformation.cxx:436). Both were found by the volume fuzzers, which reach this
/// reader through the DICM magic. So the group 0002 elements are walked here first: explicit VR
/// little endian, each inside the file, and a data set must follow.
std::string meta_header_problem(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return "cannot open the file";
  std::vector<unsigned char> b(1 << 20);  // a meta header is a few hundred bytes
  const std::size_t size = std::fread(b.data(), 1, b.size(), f);
  std::fclose(f);
  std::size_t pos = 132;  // preamble + "DICM"
  int elements = 0;
  for (;;) {
    if (pos + 8 > size) {
      if (size == b.size()) return "File Meta Information larger than 1 MiB";
      return elements == 0 ? "no File Meta Information after the DICM preamble"
                           : "no data set after the File Meta Information (file cut short)";
    }
    const unsigned group = b[pos] | b[pos + 1] << 8u;
    const unsigned element = b[pos + 2] | b[pos + 3] << 8u;
    if (group != 0x0002) {
      if (elements == 0) return "no File Meta Information after the DICM preamble";
      return "";
    }
    const char vr[3] = {static_cast<char>(b[pos + 4]), static_cast<char>(b[pos + 5]), '\0'};
    if (!(vr[0] >= 'A' && vr[0] <= 'Z' && vr[1] >= 'A' && vr[1] <= 'Z'))
      return "File Meta Information element " + std::to_string(elements) + " has no explicit VR";
    static const char* const kLong[] = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ",
                                        "SV", "UC", "UN", "UR", "UT", "UV"};
    bool long_form = false;
    for (const char* l : kLong) long_form |= std::strcmp(vr, l) == 0;
    std::uint64_t header = 8, length = b[pos + 6] | b[pos + 7] << 8u;
    if (long_form) {
      if (pos + 12 > size) return "File Meta Information cut short";
      header = 12;
      length = static_cast<std::uint64_t>(b[pos + 8]) | static_cast<std::uint64_t>(b[pos + 9]) << 8 |
               static_cast<std::uint64_t>(b[pos + 10]) << 16 |
               static_cast<std::uint64_t>(b[pos + 11]) << 24;
    }
    if (pos + header + length > size) {
      char tag[16];
      std::snprintf(tag, sizeof tag, "(0002,%04x)", element);
      return std::string("File Meta Information element ") + tag + " runs past the end of the file";
    }
    pos += static_cast<std::size_t>(header + length);
    ++elements;
  }
}

/// GDCM prints its warnings on stderr; adamesh reports errors itself, on one line.
void quiet_gdcm() {
  gdcm::Trace::WarningOff();
  gdcm::Trace::DebugOff();
  gdcm::Trace::ErrorOff();
}

}  // namespace

bool is_dicom_file(const std::string& path) { return has_dicom_magic(path); }

Volume read_dicom_series(const std::vector<std::string>& all_files, const std::string& where,
                         const std::string& series_uid) {
  quiet_gdcm();
  // Files with the Part 10 preamble and a malformed meta header are not DICOM images GDCM can
  // take (it may abort on them): ignored, as any file that is not a DICOM image.
  std::vector<std::string> files;
  for (const std::string& f : all_files)
    if (!has_dicom_magic(f) || meta_header_problem(f).empty()) files.push_back(f);
  gdcm::Scanner scanner;
  for (const gdcm::Tag& t : {kSeriesUid, kSeriesDescription, kModality, kPosition, kOrientation,
                             kPixelSpacing, kRows, kColumns, kFrames})
    scanner.AddTag(t);
  if (!scanner.Scan(files)) fail_input(where, "cannot scan the DICOM files");
  std::map<std::string, std::vector<std::string>> series;  // uid -> files
  for (const std::string& f : files)
    if (scanner.IsKey(f.c_str()))
      series[trimmed(scanner.GetValue(f.c_str(), kSeriesUid))].push_back(f);
  if (series.empty())
    fail_input(where,
               "no DICOM image files (" + std::to_string(all_files.size()) + " files looked at)");

  std::string uid = series_uid;
  if (uid.empty()) {
    if (series.size() > 1) {
      std::string list;
      for (const auto& [u, fs_] : series) {
        const char* f0 = fs_.front().c_str();
        list += "\n  " + (u.empty() ? std::string("(no SeriesInstanceUID)") : u) + "  " +
                trimmed(scanner.GetValue(f0, kModality)) + ", " + std::to_string(fs_.size()) +
                " files, '" + trimmed(scanner.GetValue(f0, kSeriesDescription)) + "'";
      }
      fail(Status::usage, where + ": " + std::to_string(series.size()) +
                              " DICOM series; choose one with --series UID:" + list);
    }
    uid = series.begin()->first;
  } else if (!series.count(uid)) {
    std::string list;
    for (const auto& s : series) list += " " + s.first;
    fail(Status::usage,
         where + ": no DICOM series with UID " + uid + " (series here:" + list + ")");
  }
  const std::vector<std::string>& names = series[uid];
  if (names.size() < 2)
    fail(Status::unsupported,
         where + ": DICOM series " + uid + " has a single slice: a volume needs at least 2");

  // Geometry from the headers: every slice must share orientation, size and pixel spacing.
  const std::string f0 = names.front();
  const std::vector<double> iop = numbers(trimmed(scanner.GetValue(f0.c_str(), kOrientation)));
  const std::vector<double> ps = numbers(trimmed(scanner.GetValue(f0.c_str(), kPixelSpacing)));
  if (iop.size() != 6) fail_input(f0, "missing or invalid ImageOrientationPatient (0020,0037)");
  if (ps.size() != 2 || !(ps[0] > 0) || !(ps[1] > 0))
    fail_input(f0, "missing or invalid PixelSpacing (0028,0030)");
  const Vec3 row{iop[0], iop[1], iop[2]}, col{iop[3], iop[4], iop[5]};
  if (std::abs(norm(row) - 1) > 1e-3 || std::abs(norm(col) - 1) > 1e-3 ||
      std::abs(dot(row, col)) > 1e-3)
    fail_input(f0, "ImageOrientationPatient is not two orthogonal unit vectors");
  const Vec3 r = normalized(row), c = normalized(col), n = normalized(cross(row, col));
  std::vector<Slice> slices;
  for (const std::string& f : names) {
    const char* fc = f.c_str();
    if (trimmed(scanner.GetValue(fc, kOrientation)) !=
        trimmed(scanner.GetValue(f0.c_str(), kOrientation))) {
      const std::vector<double> o = numbers(trimmed(scanner.GetValue(fc, kOrientation)));
      double diff = o.size() == 6 ? 0 : 1;
      for (std::size_t i = 0; i < o.size() && i < 6; ++i)
        diff = std::max(diff, std::abs(o[i] - iop[i]));
      if (diff > 1e-4)
        fail(Status::unsupported, f + ": ImageOrientationPatient differs from " + f0 +
                                      " (slices in several orientations)");
    }
    if (trimmed(scanner.GetValue(fc, kRows)) != trimmed(scanner.GetValue(f0.c_str(), kRows)) ||
        trimmed(scanner.GetValue(fc, kColumns)) != trimmed(scanner.GetValue(f0.c_str(), kColumns)))
      fail(Status::unsupported, f + ": slice size differs from " + f0);
    const std::vector<double> p2 = numbers(trimmed(scanner.GetValue(fc, kPixelSpacing)));
    if (p2.size() != 2 || std::abs(p2[0] - ps[0]) > 1e-4 * ps[0] ||
        std::abs(p2[1] - ps[1]) > 1e-4 * ps[1])
      fail(Status::unsupported, f + ": PixelSpacing differs from " + f0);
    const std::string frames = trimmed(scanner.GetValue(fc, kFrames));
    if (!frames.empty() && frames != "1")
      fail(Status::unsupported, f + ": multi-frame DICOM (" + frames + " frames) is not supported");
    const std::vector<double> p = numbers(trimmed(scanner.GetValue(fc, kPosition)));
    if (p.size() != 3) fail_input(f, "missing or invalid ImagePositionPatient (0020,0032)");
    Slice s{f, {p[0], p[1], p[2]}, 0};
    s.along = dot(s.position, n);
    slices.push_back(s);
  }
  std::sort(slices.begin(), slices.end(),
            [](const Slice& a, const Slice& b) { return a.along < b.along; });
  const std::size_t nz = slices.size();
  const double dz = (slices.back().along - slices.front().along) / static_cast<double>(nz - 1);
  for (std::size_t k = 1; k < nz; ++k) {
    const double step = slices[k].along - slices[k - 1].along;
    if (step < 1e-6 * std::max(1.0, std::abs(dz)))
      fail(Status::unsupported, where + ": two slices at the same position (" + slices[k - 1].file +
                                    ", " + slices[k].file +
                                    "): several acquisitions, echoes or time points in one series");
    if (std::abs(step - dz) > 0.01 * dz + 1e-4)
      fail(Status::unsupported, where + ": uneven slice spacing: " + std::to_string(step) +
                                    " mm between " + slices[k - 1].file + " and " + slices[k].file +
                                    ", " + std::to_string(dz) +
                                    " mm on average (missing slices?); not resampled");
    // Gantry tilt: the slice origins must move along the normal only.
    const Vec3 d = slices[k].position - slices[0].position;
    const Vec3 lateral = d - n * dot(d, n);
    if (norm(lateral) > 0.01 * std::min({ps[0], ps[1], dz}) * static_cast<double>(k) + 1e-3)
      fail(Status::unsupported,
           where +
               ": slice positions are not along the slice normal (gantry tilt or "
               "sheared series, offset " +
               std::to_string(norm(lateral)) + " mm at " + slices[k].file + "); not resampled");
  }

  // Pixels: read every slice, then choose the output type from the rescaled range.
  Grid grid;
  std::array<std::int64_t, 2> size{0, 0};
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  bool integral = true;
  std::vector<std::pair<double, double>> rescale(nz);
  std::vector<gdcm::PixelFormat> formats;
  std::vector<std::vector<char>> buffers(nz);
  for (std::size_t k = 0; k < nz; ++k) {
    gdcm::ImageReader reader;
    reader.SetFileName(slices[k].file.c_str());
    if (!reader.Read())
      fail_input(slices[k].file,
                 "GDCM cannot read the image (corrupt file or unsupported transfer syntax)");
    const gdcm::Image& img = reader.GetImage();
    const unsigned int* dim = img.GetDimensions();
    if (img.GetNumberOfDimensions() == 3 && dim[2] != 1)
      fail(Status::unsupported, slices[k].file + ": multi-frame DICOM is not supported");
    const gdcm::PixelFormat pf = img.GetPixelFormat();
    if (pf.GetSamplesPerPixel() != 1)
      fail(Status::unsupported, slices[k].file + ": colour DICOM images are not supported");
    if (k == 0) size = {dim[0], dim[1]};
    if (dim[0] != size[0] || dim[1] != size[1])
      fail(Status::unsupported, slices[k].file + ": slice size differs");
    if (pf.GetScalarType() == gdcm::PixelFormat::UNKNOWN || pf.GetBitsAllocated() > 32 ||
        pf.GetBitsAllocated() % 8 != 0)
      fail(Status::unsupported, slices[k].file + ": pixel format with " +
                                    std::to_string(pf.GetBitsAllocated()) +
                                    " bits allocated is not supported");
    buffers[k].resize(img.GetBufferLength());
    if (!img.GetBuffer(buffers[k].data()))
      fail_input(slices[k].file, "cannot decode the pixel data");
    const std::size_t bytes = pf.GetPixelSize();
    if (buffers[k].size() < static_cast<std::size_t>(size[0] * size[1]) * bytes)
      fail_input(slices[k].file, "pixel data shorter than the image size");
    rescale[k] = {img.GetSlope(), img.GetIntercept()};
    formats.push_back(pf);
    // Plain variables, not a structured binding: clang 14 (the fuzz preset) cannot capture
    // those in the lambdas below.
    const double slope = std::get<0>(rescale[k]), icpt = std::get<1>(rescale[k]);
    if (slope != std::floor(slope) || icpt != std::floor(icpt) || !(slope != 0)) integral = false;
    // Range of the rescaled values: the output type is the smallest that holds them exactly.
    const char* src = buffers[k].data();
    const std::size_t count = static_cast<std::size_t>(size[0] * size[1]);
    auto range = [&](auto in_tag) {
      using In = decltype(in_tag);
      if constexpr (std::is_floating_point_v<In>) integral = false;
      for (std::size_t i = 0; i < count; ++i) {
        In x;
        std::memcpy(&x, src + i * sizeof(In), sizeof(In));
        const double y = static_cast<double>(x) * slope + icpt;
        if (!std::isfinite(y)) continue;  // NaN/Inf samples: load_input reports them
        lo = std::min(lo, y);
        hi = std::max(hi, y);
      }
    };
    switch (pf.GetScalarType()) {
      case gdcm::PixelFormat::UINT8:
        range(std::uint8_t{});
        break;
      case gdcm::PixelFormat::INT8:
        range(std::int8_t{});
        break;
      case gdcm::PixelFormat::UINT16:
        range(std::uint16_t{});
        break;
      case gdcm::PixelFormat::INT16:
        range(std::int16_t{});
        break;
      case gdcm::PixelFormat::UINT32:
        range(std::uint32_t{});
        break;
      case gdcm::PixelFormat::INT32:
        range(std::int32_t{});
        break;
      case gdcm::PixelFormat::FLOAT32:
        range(float{});
        break;
      case gdcm::PixelFormat::FLOAT64:
        range(double{});
        break;
      default:
        fail(Status::unsupported,
             slices[k].file + ": unsupported pixel type " + pf.GetScalarTypeAsString());
    }
  }
  ScalarType type = ScalarType::f32;
  if (integral) {
    if (lo >= 0 && hi <= 255)
      type = ScalarType::u8;
    else if (lo >= -32768 && hi <= 32767)
      type = ScalarType::i16;
    else if (lo >= 0 && hi <= 65535)
      type = ScalarType::u16;
    else if (lo >= -2147483648.0 && hi <= 2147483647.0)
      type = ScalarType::i32;
  }

  grid.dims = {size[0], size[1], static_cast<std::int64_t>(nz)};
  grid.spacing = {ps[1], ps[0], dz};  // PixelSpacing = (between rows, between columns)
  grid.origin = slices.front().position;
  grid.direction = Mat3::from_columns(r, c, n);
  Volume v = allocate_volume(grid, type, where);
  v.format = "DICOM";
  const std::size_t per_slice = static_cast<std::size_t>(size[0] * size[1]);
  for (std::size_t k = 0; k < nz; ++k) {
    const gdcm::PixelFormat& pf = formats[k];
    // Plain variables, not a structured binding: clang 14 (the fuzz preset) cannot capture
    // those in the lambdas below.
    const double slope = std::get<0>(rescale[k]), icpt = std::get<1>(rescale[k]);
    const char* src = buffers[k].data();
    dispatch_scalar(type, [&](auto out_tag) {
      using Out = decltype(out_tag);
      Out* dst = v.samples<Out>() + k * per_slice;
      constexpr double omin = static_cast<double>(std::numeric_limits<Out>::lowest());
      constexpr double omax = static_cast<double>(std::numeric_limits<Out>::max());
      auto convert = [&](auto in_tag) {
        using In = decltype(in_tag);
        for (std::size_t i = 0; i < per_slice; ++i) {
          In x;
          std::memcpy(&x, src + i * sizeof(In), sizeof(In));
          const double y = static_cast<double>(x) * slope + icpt;
          dst[i] = static_cast<Out>(std::clamp(y, omin, omax));
        }
      };
      switch (pf.GetScalarType()) {
        case gdcm::PixelFormat::UINT8:
          convert(std::uint8_t{});
          break;
        case gdcm::PixelFormat::INT8:
          convert(std::int8_t{});
          break;
        case gdcm::PixelFormat::UINT16:
          convert(std::uint16_t{});
          break;
        case gdcm::PixelFormat::INT16:
          convert(std::int16_t{});
          break;
        case gdcm::PixelFormat::UINT32:
          convert(std::uint32_t{});
          break;
        case gdcm::PixelFormat::INT32:
          convert(std::int32_t{});
          break;
        case gdcm::PixelFormat::FLOAT32:
          convert(float{});
          break;
        case gdcm::PixelFormat::FLOAT64:
          convert(double{});
          break;
        default:
          fail(Status::unsupported, slices[k].file + ": unsupported pixel type");
      }
    });
    std::vector<char>().swap(buffers[k]);
  }
  return v;
}

Volume read_dicom(const std::string& path, const std::string& series_uid) {
  std::error_code ec;
  std::vector<std::string> files;
  std::string uid = series_uid;
  if (fs::is_directory(path, ec)) {
    for (const auto& e : fs::directory_iterator(path, ec))
      if (e.is_regular_file(ec)) files.push_back(e.path().string());
    if (ec) fail_input(path, "cannot list the directory: " + ec.message());
    std::sort(files.begin(), files.end());
  } else {
    // One slice named: its series, read from the slice's directory.
    quiet_gdcm();
    if (has_dicom_magic(path))
      if (const std::string problem = meta_header_problem(path); !problem.empty())
        fail_input(path, "not a readable DICOM file: " + problem);
    gdcm::Scanner one;
    one.AddTag(kSeriesUid);
    if (!one.Scan({path}) || !one.IsKey(path.c_str())) fail_input(path, "not a DICOM image file");
    const std::string own = trimmed(one.GetValue(path.c_str(), kSeriesUid));
    if (!uid.empty() && uid != own)
      fail(Status::usage, path + ": this file belongs to series " + own + ", not " + uid);
    uid = own;
    const fs::path dir =
        fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path();
    for (const auto& e : fs::directory_iterator(dir, ec))
      if (e.is_regular_file(ec)) files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
  }
  return read_dicom_series(files, path, uid);
}

}  // namespace adamesh::detail
