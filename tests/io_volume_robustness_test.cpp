// Robustness: small valid files of every format, truncated at every length and with bytes
// overwritten at many positions, must either load or fail with adamesh::Error and a one-line
// "<path>: ..." message — never another exception, a crash or a hang.
#include <cstdlib>
#include <map>
#include <random>

#include "io_volume_test_util.h"

namespace adamesh {
namespace {

using namespace testutil;

std::string b64(const std::string& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < in.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, in.size() - i);
    unsigned v = 0;
    for (std::size_t k = 0; k < 3; ++k) v = v << 8 | (k < n ? (unsigned char)in[i + k] : 0u);
    out += t[v >> 18];
    out += t[(v >> 12) & 63];
    out += n > 1 ? t[(v >> 6) & 63] : '=';
    out += n > 2 ? t[v & 63] : '=';
  }
  return out;
}

struct Seed {
  std::string name, bytes;
};

std::vector<Seed> seeds() {
  const std::string d = to_bytes(ramp<std::uint8_t>(64, 0, 37));  // 4x4x4 uint8
  const std::string s16 = to_bytes(ramp<std::int16_t>(32, -500, 41), true);  // 4x4x2 int16 BE
  std::vector<Seed> out;
  out.push_back({"a.nrrd", "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nspace directions: (1,0,0) (0,2,0) (0,0,3)\n"
                           "space origin: (1,2,3)\nencoding: raw\n\n" + d});
  out.push_back({"g.nrrd", "NRRD0004\ntype: short\ndimension: 3\nsizes: 4 4 2\nendian: big\nencoding: gzip\n\n" + gzip(s16)});
  out.push_back({"t.nrrd", "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nencoding: text\n\n1 2 3 4.5 -1e3 7 8 9\n"});
  out.push_back({"l.mha", "ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementSpacing = 1 1 2\n"
                          "TransformMatrix = 0 1 0 1 0 0 0 0 1\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n" + d});
  out.push_back({"z.mha", "NDims = 3\nDimSize = 4 4 2\nCompressedData = True\nElementType = MET_SHORT\n"
                          "ElementByteOrderMSB = True\nElementDataFile = LOCAL\n" + compress(s16)});
  out.push_back({"a.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
                          "SPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA 8\nVECTORS v float\n1 2 3 1 2 3 1 2 3 1 2 3 "
                          "1 2 3 1 2 3 1 2 3 1 2 3\nSCALARS s int\nLOOKUP_TABLE default\n1 2 3 4 5 6 7 8\n"});
  out.push_back({"b.vtk", "# vtk DataFile Version 3.0\nx\nBINARY\nDATASET STRUCTURED_POINTS\nDIMENSIONS 4 4 2\n"
                          "SPACING 1 1 1\nORIGIN 0 0 0\nPOINT_DATA 32\nSCALARS s short\nLOOKUP_TABLE default\n" + s16});
  const std::string z = compress(d.substr(0, 40)), z2 = compress(d.substr(40));
  const std::string zhead = to_bytes(std::vector<std::uint32_t>{2, 40, 24, std::uint32_t(z.size()), std::uint32_t(z2.size())});
  out.push_back({"z.vti", "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" "
                          "compressor=\"vtkZLibDataCompressor\"><ImageData WholeExtent=\"0 3 0 3 0 3\" Origin=\"0 0 0\" "
                          "Spacing=\"1 1 1\"><Piece Extent=\"0 3 0 3 0 3\"><PointData Scalars=\"s\"><DataArray type=\"UInt8\" "
                          "Name=\"s\" format=\"binary\">" + b64(zhead) + b64(z + z2) +
                          "</DataArray></PointData></Piece></ImageData></VTKFile>\n"});
  out.push_back({"r.vti", "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\">"
                          "<ImageData WholeExtent=\"0 3 0 3 0 3\" Direction=\"0 1 0 1 0 0 0 0 1\"><Piece Extent=\"0 3 0 3 0 3\">"
                          "<PointData><DataArray type=\"UInt8\" Name=\"s\" format=\"appended\" offset=\"0\"/></PointData>"
                          "</Piece></ImageData><AppendedData encoding=\"raw\">_" + pod_bytes<std::uint32_t>(64) + d +
                          "</AppendedData></VTKFile>\n"});
  std::string slc = "11111\n4 4 2 8\n1 1 1\n1 6 0 1\n2 1 X" + std::string(6, 'i');
  for (int k = 0; k < 2; ++k) slc += "8 X" + std::string("\x84\x01\x02\x03\x04\x0c\x07\x00", 8);  // 4 literal, 12 × 7
  out.push_back({"s.slc", slc});
  std::string mrc;
  const std::int32_t words[24] = {4, 4, 4, 2, 0, 0, 0, 4, 4, 4};
  for (int i = 0; i < 10; ++i) mrc += pod_bytes(words[i]);
  for (float f : {8.f, 8.f, 8.f, 90.f, 90.f, 90.f}) mrc += pod_bytes(f);
  for (std::int32_t m : {2, 3, 1}) mrc += pod_bytes(m);
  mrc.resize(208, '\0');
  mrc += std::string("MAP \x44\x44\x00\x00", 8);
  mrc.resize(1024, '\0');
  out.push_back({"m.mrc", mrc + to_bytes(ramp<float>(64, -3, 0.25))});
  std::string nii(352, '\0');
  const std::int32_t hdr = 348;
  std::memcpy(nii.data(), &hdr, 4);
  const std::int16_t dim[8] = {3, 4, 4, 4, 1, 1, 1, 1};
  std::memcpy(nii.data() + 40, dim, sizeof dim);
  const std::int16_t dt[2] = {2, 8};  // uint8
  std::memcpy(nii.data() + 70, dt, sizeof dt);
  const float pix[8] = {1, 1, 2, 3, 1, 1, 1, 1};
  std::memcpy(nii.data() + 76, pix, sizeof pix);
  const float vox = 352;
  std::memcpy(nii.data() + 108, &vox, 4);
  const std::int16_t codes[2] = {0, 1};
  std::memcpy(nii.data() + 252, codes, sizeof codes);
  const float srow[12] = {0, 2, 0, 5, 1, 0, 0, 6, 0, 0, 3, 7};
  std::memcpy(nii.data() + 280, srow, sizeof srow);
  std::memcpy(nii.data() + 344, "n+1\0", 4);
  out.push_back({"n.nii", nii + d});
  out.push_back({"n.nii.gz", gzip(nii + d)});
  return out;
}

// Thousands of tiny rewrites: use memory-backed /dev/shm when there is one (on some disks each
// truncating rewrite takes milliseconds), else the usual temporary directory.
class ScratchDir {
 public:
  ScratchDir() {
    std::error_code ec;
    if (std::filesystem::is_directory("/dev/shm", ec)) {
      std::string tmpl = "/dev/shm/adamesh-robust-XXXXXX";
      if (mkdtemp(tmpl.data())) path_ = tmpl;
    }
    if (path_.empty()) {
      std::string tmpl = (std::filesystem::temp_directory_path() / "adamesh-robust-XXXXXX").string();
      if (!mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
      path_ = tmpl;
    }
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

void expect_clean(const std::string& path, const std::string& what) {
  try {
    (void)read_volume(path);
  } catch (const Error& e) {
    const std::string msg = e.what();
    ASSERT_EQ(msg.rfind(path + ": ", 0), 0u) << what << ": " << msg;
    ASSERT_EQ(msg.find('\n'), std::string::npos) << what << ": " << msg;
    ASSERT_TRUE(e.status() == Status::invalid_input || e.status() == Status::unsupported) << what << ": " << msg;
  } catch (const std::exception& e) {
    FAIL() << what << ": exception other than adamesh::Error: " << e.what();
  }
}

TEST(VolumeRobustness, SeedsAreValid) {
  TempDir tmp;
  // fuzz/make_seeds.sh sets ADAMESH_FUZZ_SEEDS to fuzz/corpus: the seeds become the fuzzers'
  // starting corpus, one folder per reader (docs/FUZZING.md).
  const char* corpus = std::getenv("ADAMESH_FUZZ_SEEDS");
  for (const auto& s : seeds()) {
    const std::string path = tmp.file(s.name);
    write_bytes(path, s.bytes);
    EXPECT_NO_THROW((void)read_volume(path)) << s.name;
    if (corpus == nullptr) continue;
    const std::string ext = s.name.substr(s.name.find('.'));
    const std::map<std::string, std::string> target = {
        {".nrrd", "nrrd"}, {".mha", "metaimage"}, {".nii", "nifti"}, {".vtk", "vtk"},
        {".vti", "vti"},   {".slc", "slc"},       {".mrc", "mrc"}};
    if (!target.count(ext)) continue;
    const std::filesystem::path dir = std::filesystem::path(corpus) / target.at(ext);
    std::filesystem::create_directories(dir);
    write_bytes((dir / ("seed_" + s.name)).string(), s.bytes);
  }
}

TEST(VolumeRobustness, EveryTruncationFailsCleanly) {
  ScratchDir tmp;
  for (const auto& s : seeds()) {
    const std::string path = tmp.file(s.name);
    for (std::size_t len = 0; len < s.bytes.size(); ++len) {
      write_bytes(path, s.bytes.substr(0, len));
      ASSERT_NO_FATAL_FAILURE(expect_clean(path, s.name + " cut to " + std::to_string(len)));
    }
  }
}

TEST(VolumeRobustness, OverwrittenBytesFailCleanlyOrLoad) {
  ScratchDir tmp;
  std::mt19937 rng(12345);
  const char replacements[] = {'\0', '\xff', '9', '-', ' ', '\n', '=', ':', 'X', '%', '(', '<', '_', 'e'};
  for (const auto& s : seeds()) {
    const std::string path = tmp.file(s.name);
    for (int trial = 0; trial < 300; ++trial) {
      std::string b = s.bytes;
      const int edits = 1 + static_cast<int>(rng() % 3);
      for (int e = 0; e < edits; ++e)
        b[rng() % b.size()] = replacements[rng() % sizeof replacements];
      write_bytes(path, b);
      ASSERT_NO_FATAL_FAILURE(expect_clean(path, s.name + " trial " + std::to_string(trial)));
    }
  }
}

}  // namespace
}  // namespace adamesh
