// DICOM series input: series are written here with GDCM (gdcm::ImageWriter, CT Image Storage)
// from real volumes placed in several orientations, in shuffled file order, and read back with
// read_volume(directory): dims, spacing, origin, direction and every sample must match the
// source, uncompressed and in four lossless compressed transfer syntaxes. Rescale
// slope/intercept, several series in one directory, gantry tilt, uneven spacing and the CLI are
// covered too.
#include <gdcmAttribute.h>
#include <gdcmImage.h>
#include <gdcmImageChangeTransferSyntax.h>
#include <gdcmImageReader.h>
#include <gdcmImageWriter.h>
#include <gdcmReader.h>
#include <gdcmTrace.h>
#include <gdcmUIDGenerator.h>
#include <gdcmWriter.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>

#include "adamesh/error.h"
#include "adamesh/io.h"
#include "testing.h"

using namespace adamesh;
using adamesh::testutil::run_cli;
using adamesh::testutil::TempDir;
namespace fs = std::filesystem;

namespace {

struct SeriesOptions {
  double slope = 1, intercept = 0;  ///< stored = (value - intercept) / slope
  bool unsigned16 = false;          ///< store uint16 instead of int16
  Vec3 tilt{};                      ///< added to ImagePositionPatient per slice (gantry tilt)
  std::string series_uid;           ///< generated when empty
  std::string description = "test series";
  int skip_slice = -1;  ///< leave this slice out (uneven spacing)
  unsigned seed = 1;    ///< file order
  /// Pixel data encoding; TS_END: as ImageWriter writes it (uncompressed).
  gdcm::TransferSyntax::TSType syntax = gdcm::TransferSyntax::TS_END;
};

/// Writes `v` (direction right-handed, unit columns) as one CT file per k-slice in `dir`.
std::string write_series(const Volume& v, const std::string& dir, const SeriesOptions& o = {}) {
  gdcm::Trace::WarningOff();
  fs::create_directories(dir);
  gdcm::UIDGenerator uids;
  const std::string series = o.series_uid.empty() ? uids.Generate() : o.series_uid;
  const std::string study = uids.Generate();
  const auto& d = v.grid.dims;
  std::vector<int> order(static_cast<std::size_t>(d[2]));
  for (int k = 0; k < d[2]; ++k) order[static_cast<std::size_t>(k)] = k;
  std::shuffle(order.begin(), order.end(), std::mt19937(o.seed));
  const Mat3& m = v.grid.direction;
  const Vec3 r = m * Vec3{1, 0, 0}, c = m * Vec3{0, 1, 0};
  for (std::size_t n = 0; n < order.size(); ++n) {
    const int k = order[n];
    if (k == o.skip_slice) continue;
    gdcm::ImageWriter w;
    gdcm::Image& img = w.GetImage();
    img.SetNumberOfDimensions(2);
    img.SetDimension(0, static_cast<unsigned>(d[0]));
    img.SetDimension(1, static_cast<unsigned>(d[1]));
    img.SetPixelFormat(o.unsigned16 ? gdcm::PixelFormat::UINT16 : gdcm::PixelFormat::INT16);
    img.SetPhotometricInterpretation(gdcm::PhotometricInterpretation::MONOCHROME2);
    const Vec3 p = v.grid.to_world({0, 0, double(k)}) + o.tilt * double(k);
    const double origin[3] = {p.x, p.y, p.z};
    const double cosines[6] = {r.x, r.y, r.z, c.x, c.y, c.z};
    const double spacing[3] = {v.grid.spacing.x, v.grid.spacing.y, v.grid.spacing.z};
    img.SetOrigin(origin);
    img.SetDirectionCosines(cosines);
    img.SetSpacing(spacing);
    img.SetSlope(o.slope);
    img.SetIntercept(o.intercept);
    std::vector<std::int16_t> s16;
    std::vector<std::uint16_t> u16;
    for (std::int64_t j = 0; j < d[1]; ++j)
      for (std::int64_t i = 0; i < d[0]; ++i) {
        const double stored = std::round((v.at(i, j, k) - o.intercept) / o.slope);
        if (o.unsigned16)
          u16.push_back(static_cast<std::uint16_t>(stored));
        else
          s16.push_back(static_cast<std::int16_t>(stored));
      }
    gdcm::DataElement pixels(gdcm::Tag(0x7fe0, 0x0010));
    if (o.unsigned16)
      pixels.SetByteValue(reinterpret_cast<const char*>(u16.data()),
                          static_cast<std::uint32_t>(2 * u16.size()));
    else
      pixels.SetByteValue(reinterpret_cast<const char*>(s16.data()),
                          static_cast<std::uint32_t>(2 * s16.size()));
    img.SetDataElement(pixels);
    gdcm::DataSet& ds = w.GetFile().GetDataSet();
    auto put = [&](std::uint16_t g, std::uint16_t e, const std::string& value, gdcm::VR vr) {
      gdcm::DataElement de(gdcm::Tag(g, e));
      de.SetVR(vr);
      std::string val = value;
      if (val.size() % 2) val.push_back(vr == gdcm::VR::UI ? '\0' : ' ');
      de.SetByteValue(val.data(), static_cast<std::uint32_t>(val.size()));
      ds.Replace(de);
    };
    put(0x0008, 0x0016, "1.2.840.10008.5.1.4.1.1.2", gdcm::VR::UI);  // CT Image Storage
    put(0x0008, 0x0018, uids.Generate(), gdcm::VR::UI);
    put(0x0008, 0x0060, "CT", gdcm::VR::CS);
    put(0x0008, 0x103e, o.description, gdcm::VR::LO);
    put(0x0020, 0x000d, study, gdcm::VR::UI);
    put(0x0020, 0x000e, series, gdcm::VR::UI);
    put(0x0020, 0x0013, std::to_string(n + 1), gdcm::VR::IS);  // instance numbers in file order
    const std::string name = dir + "/IM" + std::to_string(o.seed) + "_" + std::to_string(1000 + n);
    w.SetFileName(name.c_str());
    if (!w.Write()) throw std::runtime_error("gdcm could not write a slice");
    if (o.syntax != gdcm::TransferSyntax::TS_END) {  // compress the pixel data
      gdcm::ImageReader ir;
      ir.SetFileName(name.c_str());
      if (!ir.Read()) throw std::runtime_error("gdcm could not read a slice back");
      gdcm::ImageChangeTransferSyntax change;
      change.SetTransferSyntax(o.syntax);
      change.SetInput(ir.GetImage());
      if (!change.Change()) throw std::runtime_error("gdcm could not change the transfer syntax");
      gdcm::ImageWriter cw;
      cw.SetFile(ir.GetFile());
      cw.SetImage(change.GetOutput());
      cw.SetFileName(name.c_str());
      if (!cw.Write()) throw std::runtime_error("gdcm could not write a compressed slice");
    }
    // ImageWriter keeps only x, y of a 2-D image's origin: set ImagePositionPatient afterwards.
    gdcm::Reader rd;
    rd.SetFileName(name.c_str());
    if (!rd.Read()) throw std::runtime_error("gdcm could not read a slice back");
    char ipp[128];
    std::snprintf(ipp, sizeof ipp, "%.9g\\%.9g\\%.9g", p.x, p.y, p.z);
    std::string value = ipp;
    if (value.size() % 2) value.push_back(' ');
    gdcm::DataElement pos(gdcm::Tag(0x0020, 0x0032));
    pos.SetVR(gdcm::VR::DS);
    pos.SetByteValue(value.data(), static_cast<std::uint32_t>(value.size()));
    rd.GetFile().GetDataSet().Replace(pos);
    gdcm::Writer wr;
    wr.SetFile(rd.GetFile());
    wr.SetFileName(name.c_str());
    if (!wr.Write()) throw std::runtime_error("gdcm could not rewrite a slice");
  }
  return series;
}

Volume head() { return read_volume(testutil::source_dir() + "/data/ct_headsq/quarter.nhdr"); }

Mat3 rotation(Vec3 axis, double angle) {
  axis = normalized(axis);
  const double c = std::cos(angle), s = std::sin(angle), t = 1 - c;
  const Vec3 x = {t * axis.x * axis.x + c, t * axis.x * axis.y + s * axis.z,
                  t * axis.x * axis.z - s * axis.y};
  const Vec3 y = {t * axis.x * axis.y - s * axis.z, t * axis.y * axis.y + c,
                  t * axis.y * axis.z + s * axis.x};
  const Vec3 z = {t * axis.x * axis.z + s * axis.y, t * axis.y * axis.z - s * axis.x,
                  t * axis.z * axis.z + c};
  return Mat3::from_columns(x, y, z);
}

void expect_same_geometry_and_samples(const Volume& a, const Volume& b) {
  ASSERT_EQ(a.grid.dims, b.grid.dims);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(a.grid.spacing[k], b.grid.spacing[k], 1e-5 * b.grid.spacing[k]) << "spacing " << k;
    EXPECT_NEAR(a.grid.origin[k], b.grid.origin[k], 1e-4) << "origin " << k;
    for (int l = 0; l < 3; ++l)
      EXPECT_NEAR(a.grid.direction.m[k][l], b.grid.direction.m[k][l], 1e-5)
          << "direction " << k << l;
  }
  std::int64_t differ = 0;
  for (std::int64_t i = 0; i < b.grid.num_samples(); ++i) differ += a.at(i) != b.at(i);
  EXPECT_EQ(differ, 0) << "samples differ";
}

}  // namespace

TEST(Dicom, SeriesInSeveralOrientationsReadsBackWithTheSourceGeometry) {
  TempDir tmp;
  const Mat3 frames[] = {
      Mat3::from_columns({1, 0, 0}, {0, 1, 0}, {0, 0, 1}),    // axial
      Mat3::from_columns({0, 1, 0}, {0, 0, -1}, {-1, 0, 0}),  // sagittal
      Mat3::from_columns({1, 0, 0}, {0, 0, -1}, {0, 1, 0}),   // coronal
      rotation({0.3, -0.5, 0.8}, 0.7),                        // oblique
  };
  int n = 0;
  for (const Mat3& m : frames) {
    Volume src = head();
    src.grid.direction = m;
    src.grid.origin = {-120.25, 33.5, 17.125 * n};
    const std::string dir = tmp.file("s" + std::to_string(n));
    write_series(src, dir, {.seed = 7u + static_cast<unsigned>(n)});
    const Volume got = read_volume(dir);
    SCOPED_TRACE("frame " + std::to_string(n));
    EXPECT_EQ(got.format, "DICOM");
    EXPECT_EQ(got.type, ScalarType::i16);
    expect_same_geometry_and_samples(got, src);
    ++n;
  }
}

TEST(Dicom, CompressedTransferSyntaxes) {
  TempDir tmp;
  Volume src = head();
  src.grid.direction = rotation({1, 0, 1}, 0.3);
  src.grid.origin = {5, -7, 11};
  using TS = gdcm::TransferSyntax;
  for (const auto& [name, ts] : {std::pair<std::string, TS::TSType>{"rle", TS::RLELossless},
                                 {"jpeg_lossless", TS::JPEGLosslessProcess14_1},
                                 {"jpegls", TS::JPEGLSLossless},
                                 {"j2k", TS::JPEG2000Lossless}}) {
    SCOPED_TRACE(name);
    write_series(src, tmp.file(name), {.intercept = -1024, .unsigned16 = true, .syntax = ts});
    // The files really are encapsulated in that syntax.
    gdcm::Reader rd;
    const std::string any = fs::directory_iterator(tmp.file(name))->path().string();
    rd.SetFileName(any.c_str());
    ASSERT_TRUE(rd.Read());
    EXPECT_EQ(rd.GetFile().GetHeader().GetDataSetTransferSyntax(), ts);
    expect_same_geometry_and_samples(read_volume(tmp.file(name)), src);
  }
}

// The fuzz_dicom target (fuzz/fuzz_reader.cpp) reads its input as slice files joined by this
// separator; the same string is there.
constexpr char kFuzzSliceSeparator[] = "\n--adamesh-fuzz-next-slice--\n";

TEST(Dicom, SmallSeriesInEverySyntaxReadBack) {
  // Small series (32×32 pixels: GDCM's JPEG 2000 encoder crashes on much smaller images; 3
  // slices, oblique) in every transfer syntax the reader decodes, read back exactly.
  // fuzz/make_seeds.sh sets ADAMESH_FUZZ_SEEDS: each series' files, joined by
  // kFuzzSliceSeparator, become a seed of fuzz_dicom (docs/FUZZING.md).
  TempDir tmp;
  Grid g;
  g.dims = {32, 32, 3};
  g.spacing = {0.7, 0.8, 2.5};
  g.origin = {-3, 4, 10};
  g.direction = rotation({0.2, 1, 0.4}, 0.5);
  Volume src = allocate_volume(g, ScalarType::i16, "seed");
  for (std::int64_t i = 0; i < g.num_samples(); ++i)
    src.samples<std::int16_t>()[i] = static_cast<std::int16_t>((i * 37) % 300 - 40);
  const char* corpus = std::getenv("ADAMESH_FUZZ_SEEDS");
  using TS = gdcm::TransferSyntax;
  for (const auto& [name, ts] : {std::pair<std::string, TS::TSType>{"raw", TS::TS_END},
                                 {"rle", TS::RLELossless},
                                 {"jpeg_lossless", TS::JPEGLosslessProcess14_1},
                                 {"jpegls", TS::JPEGLSLossless},
                                 {"j2k", TS::JPEG2000Lossless}}) {
    SCOPED_TRACE(name);
    const std::string dir = tmp.file(name);
    write_series(src, dir, {.description = "seed", .syntax = ts});
    expect_same_geometry_and_samples(read_volume(dir), src);
    if (corpus == nullptr) continue;
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
    std::string joined;
    for (const std::string& f : files) {
      if (!joined.empty()) joined += kFuzzSliceSeparator;
      joined += testutil::read_bytes(f);
    }
    const fs::path out = fs::path(corpus) / "dicom";
    fs::create_directories(out);
    std::FILE* f = std::fopen((out / ("seed_" + name + ".bin")).c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(joined.data(), 1, joined.size(), f);
    std::fclose(f);
  }
}

TEST(Dicom, SharedVolumeObliqueSeries) {
  ADAMESH_REQUIRE_SHARED_DATA(data);
  TempDir tmp;
  Volume src = read_volume(data + "/mri_headmr/HeadMRVolume.mhd");  // uint8, 4 mm voxels
  src.grid.direction = rotation({1, 1, 0}, -0.4);
  src.grid.origin = {90, -125.5, 60};
  write_series(src, tmp.file("mr"));
  const Volume got = read_volume(tmp.file("mr"));
  EXPECT_EQ(got.type, ScalarType::u8);  // int16 stored, values 0..255: the smallest type
  expect_same_geometry_and_samples(got, src);
  EXPECT_EQ(volume_format_for(tmp.file("mr")), "DICOM");
}

TEST(Dicom, RescaleSlopeAndInterceptAreApplied) {
  TempDir tmp;
  const Volume src = head();
  write_series(src, tmp.file("u"), {.intercept = -1024, .unsigned16 = true});
  const Volume u = read_volume(tmp.file("u"));
  EXPECT_EQ(u.type, ScalarType::i16);  // uint16 stored − 1024: int16 range
  expect_same_geometry_and_samples(u, src);

  write_series(src, tmp.file("f"), {.slope = 0.5, .intercept = -3});
  const Volume f = read_volume(tmp.file("f"));
  EXPECT_EQ(f.type, ScalarType::f32);
  expect_same_geometry_and_samples(f, src);  // head values are integers: exact at slope 0.5
}

TEST(Dicom, SeveralSeriesAreListedAndOneCanBeChosen) {
  TempDir tmp;
  Volume a = head();
  const std::string dir = tmp.file("two");
  const std::string ua = write_series(a, dir, {.description = "first"});
  Volume b = head();
  b.grid.origin = {0, 0, 500};
  const std::string ub = write_series(b, dir, {.description = "second", .seed = 3});
  try {
    read_volume(dir);
    ADD_FAILURE() << "two series read without a choice";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::usage);
    const std::string msg = e.what();
    EXPECT_NE(msg.find("2 DICOM series; choose one with --series UID"), std::string::npos) << msg;
    EXPECT_NE(msg.find(ua), std::string::npos) << msg;
    EXPECT_NE(msg.find(ub), std::string::npos) << msg;
    EXPECT_NE(msg.find("'second'"), std::string::npos) << msg;
  }
  RawOptions ro;
  ro.dicom_series = ub;
  expect_same_geometry_and_samples(read_volume(dir, ro), b);
  // One slice named: its own series.
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path().string());
  const Volume chosen = read_dicom_series(files, ua);
  expect_same_geometry_and_samples(chosen, a);
  const auto r = run_cli("info '" + dir + "'");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("--series"), std::string::npos) << r.err;
  // One line, the series separated by "; " (it used to hold newlines, printed escaped as \n).
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.find("\\n"), std::string::npos) << r.err;
  for (const char* d : {"first", "second"})
    EXPECT_NE(r.err.find(" (CT, " + std::to_string(a.grid.dims[2]) + " files, '" + d + "')"),
              std::string::npos)
        << r.err;
  EXPECT_NE(r.err.find("'); 1."), std::string::npos) << r.err;
  const auto r2 = run_cli("info '" + dir + "' --series " + ua);
  EXPECT_EQ(r2.exit_code, 0) << r2.err;
  EXPECT_NE(r2.out.find("DICOM"), std::string::npos) << r2.out;
}

TEST(Dicom, GantryTiltAndUnevenSpacingAreRefused) {
  TempDir tmp;
  const Volume src = head();
  write_series(src, tmp.file("tilt"), {.tilt = {0, 0.4, 0}});
  write_series(src, tmp.file("gap"), {.skip_slice = 40});
  for (const auto& [name, what] : {std::pair<std::string, std::string>{"tilt", "gantry tilt"},
                                   {"gap", "uneven slice spacing"}}) {
    try {
      read_volume(tmp.file(name));
      ADD_FAILURE() << name << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::unsupported) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }
}

TEST(Dicom, TrailingPaddingIsAccepted) {
  // The structure walk (dicom.cpp) refuses what GDCM would misread, but not a tail of zeros or
  // a few stray bytes after the last element, which some writers leave and GDCM reads past.
  TempDir tmp;
  const Volume src = head();
  for (const std::string& tail : {std::string(64, '\0'), std::string("\x01\x02\x03", 3)}) {
    const std::string dir = tmp.file("pad" + std::to_string(tail.size()));
    write_series(src, dir);
    for (const auto& e : fs::directory_iterator(dir))
      testutil::write_bytes(e.path().string(), testutil::read_bytes(e.path().string()) + tail);
    expect_same_geometry_and_samples(read_volume(dir), src);
  }
}

TEST(Dicom, ACrashInsideGdcmIsAnErrorNamingTheSlice) {
  // GDCM 3.0.21 divides by zero (SIGFPE) on an RLE fragment whose header announces 0 segments;
  // fuzz_dicom also found an out-of-bounds read in its JPEG 2000 header parser. The DICOM read
  // runs in a child process (dicom.cpp, isolated()), so such a file is one error line naming the
  // slice, exit 2 — not a dead process — and the decoders' stderr chatter is not shown.
  TempDir tmp;
  Volume src = head();
  const std::string dir = tmp.file("rle");
  write_series(src, dir, {.syntax = gdcm::TransferSyntax::RLELossless});
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  const std::string bad = files[files.size() / 2];
  const std::string original = testutil::read_bytes(bad);
  std::string bytes = original;
  const std::string pixel_data("\xe0\x7f\x10\x00OB\x00\x00\xff\xff\xff\xff", 12);
  std::size_t p = bytes.find(pixel_data);
  ASSERT_NE(p, std::string::npos);
  p += pixel_data.size();
  auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  p += 8 + u32(p + 4);  // the basic offset table item
  ASSERT_EQ(u32(p), 0xe000fffeu);
  std::memset(bytes.data() + p + 8, 0, 4);  // the RLE header: number of segments 0
  testutil::write_bytes(bad, bytes);
  try {
    (void)read_volume(dir);
    ADD_FAILURE() << "read";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::invalid_input);
    EXPECT_EQ(std::string(e.what()),
              bad + ": GDCM crashed reading this DICOM data (SIGFPE, an arithmetic fault): a "
                    "corrupt file or an encoding GDCM mishandles");
  }
  const auto r = run_cli("info '" + dir + "'");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("GDCM crashed"), std::string::npos) << r.err;
  // The slice restored, the series reads in the same process after its child crashed.
  testutil::write_bytes(bad, original);
  EXPECT_EQ(read_volume(dir).grid.dims, src.grid.dims);
}

TEST(Dicom, BadDirectories) {
  TempDir tmp;
  fs::create_directories(tmp.file("empty"));
  fs::create_directories(tmp.file("junk"));
  testutil::write_bytes(tmp.file("junk/a.txt"), "not dicom");
  for (const char* d : {"empty", "junk"}) {
    try {
      read_volume(tmp.file(d));
      ADD_FAILURE() << d << " accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::invalid_input) << e.what();
      EXPECT_NE(std::string(e.what()).find("no DICOM image files"), std::string::npos) << e.what();
    }
  }
}

TEST(DicomCli, MarchingCubesOnTheSeriesEqualsTheSourceVolume) {
  TempDir tmp;
  Volume src = head();  // identity frame, origin 0: the same grid as quarter.nhdr
  write_series(src, tmp.file("ct"), {.intercept = -1024, .unsigned16 = true});
  const std::string nhdr = testutil::source_dir() + "/data/ct_headsq/quarter.nhdr";
  auto a = run_cli("mc '" + nhdr + "' --iso 500.5 -o " + tmp.file("a.ply"));
  auto b = run_cli("mc " + tmp.file("ct") + " --iso 500.5 -o " + tmp.file("b.ply"));
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_EQ(testutil::read_bytes(tmp.file("a.ply")), testutil::read_bytes(tmp.file("b.ply")));
  // One slice of the series names the whole series.
  const std::string slice = fs::directory_iterator(tmp.file("ct"))->path().string();
  auto c = run_cli("info '" + slice + "'");
  EXPECT_EQ(c.exit_code, 0) << c.err;
  EXPECT_NE(c.out.find("64 x 64 x 93"), std::string::npos) << c.out;
}
