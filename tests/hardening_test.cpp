// Regression tests for issue 17 (hardening): each test rebuilds one recipe of the audit — the
// input that crashed, hung, overflowed or was silently accepted — and asserts the clean outcome:
// one error line naming the file, the documented exit code, no output file.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "adamesh/atomic_file.h"
#include "adamesh/metrics.h"
#include "io/io_util.h"
#include "io_volume_test_util.h"

namespace adamesh {
namespace {

using namespace testutil;
namespace fs = std::filesystem;

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

std::size_t lines(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')); }

/// A 4x4x4 uint8 NRRD whose samples ramp 0..63 (iso 31.5 cuts it), with extra header fields.
std::string small_nrrd(const std::string& fields) {
  std::string d(64, '\0');
  for (int i = 0; i < 64; ++i) d[i] = static_cast<char>(i);
  return "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n" + fields + "\n" + d;
}

// ---------------------------------------------------------------------------------- 1. vti

TEST(Hardening, VtiZlibHeaderWrapAroundIsRejected) {
  // nblocks=3, blocksize=2^63, lastsize=1728 for a 12³ UInt8 volume: (3-1)*2^63 wraps to 0 and
  // the total used to "match", letting inflate write 2^63 bytes into 1728.
  TempDir tmp;
  const std::string data(1728, '\x07');
  const std::string z = compress(data);
  const std::string head = to_bytes(std::vector<std::uint64_t>{3, std::uint64_t(1) << 63, 1728,
                                                               z.size(), z.size(), z.size()});
  const std::string path = tmp.file("wrap.vti");
  write_bytes(path,
              "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" "
              "byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">"
              "<ImageData WholeExtent=\"0 11 0 11 0 11\" Origin=\"0 0 0\" Spacing=\"1 1 1\"><Piece "
              "Extent=\"0 11 0 11 0 11\"><PointData Scalars=\"s\"><DataArray type=\"UInt8\" Name=\"s\" "
              "format=\"binary\">" + b64(head) + b64(z + z + z) +
              "</DataArray></PointData></Piece></ImageData></VTKFile>\n");
  expect_read_error(path, Status::invalid_input, {"corrupt compression header"});
  for (const char* cmd : {"info", "mc --iso 3 -o OUT", "extract --iso 3 --base OUT"}) {
    std::string c = cmd;
    c.replace(c.find(' ') == std::string::npos ? c.size() : c.find(' '), 0, " " + path);
    if (const auto at = c.find("OUT"); at != std::string::npos) c.replace(at, 3, tmp.file("o.ply"));
    const auto r = run_cli(c);
    EXPECT_EQ(r.exit_code, 2) << c << ": " << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
  }
  EXPECT_FALSE(fs::exists(tmp.file("o.ply")));
  // A single block larger than the extent is legal (VTK writes 32 KiB blocks for small arrays).
  const std::string one = to_bytes(std::vector<std::uint64_t>{1, 32768, 1728, z.size()});
  write_bytes(path,
              "<?xml version=\"1.0\"?>\n<VTKFile type=\"ImageData\" version=\"1.0\" "
              "byte_order=\"LittleEndian\" header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">"
              "<ImageData WholeExtent=\"0 11 0 11 0 11\"><Piece Extent=\"0 11 0 11 0 11\"><PointData>"
              "<DataArray type=\"UInt8\" Name=\"s\" format=\"binary\">" + b64(one) + b64(z) +
              "</DataArray></PointData></Piece></ImageData></VTKFile>\n");
  EXPECT_EQ(read_volume(path).at(0), 7.0);
}

// -------------------------------------------------------------------- 2. data-file patterns

TEST(Hardening, DataFilePatternArithmeticCannotOverflow) {
  using detail::format_file_pattern;
  EXPECT_EQ(format_file_pattern("s%d.raw", std::numeric_limits<std::int64_t>::min(), "h"),
            "s-9223372036854775808.raw");
  EXPECT_EQ(format_file_pattern("s%05d.raw", -42, "h"), "s-0042.raw");
  const auto names = detail::expand_file_pattern("s%d", 9223372036854775805, 9223372036854775807, 2, "h", "f");
  ASSERT_EQ(names.size(), 2u);
  EXPECT_EQ(names[1], "s9223372036854775807");
  EXPECT_EQ(detail::expand_file_pattern("s%d", 5, -5, -5, "h", "f").size(), 3u);
  EXPECT_THROW(detail::expand_file_pattern("s%d", 0, std::numeric_limits<std::int64_t>::min(), -1, "h", "f"), Error);
  EXPECT_THROW(detail::expand_file_pattern("s%d", std::numeric_limits<std::int64_t>::min(),
                                           std::numeric_limits<std::int64_t>::max(), 1, "h", "f"), Error);
  EXPECT_THROW(detail::expand_file_pattern("s%d", 0, 10, 0, "h", "f"), Error);
  EXPECT_THROW(detail::expand_file_pattern("s%d", 0, 10, -1, "h", "f"), Error);
}

TEST(Hardening, DataFilePatternsFailCleanly) {
  TempDir tmp;
  // Each range used to SIGFPE (INT64_MIN / -1), loop forever (i += step overflowing past hi)
  // or overflow hi - lo; now: a clean error (too many files / a missing data file).
  const char* ranges[] = {"0 -9223372036854775808 -1", "9223372036854775806 9223372036854775807 2",
                          "-9223372036854775808 9223372036854775807 1",
                          "9223372036854775807 -9223372036854775808 -3"};
  for (const char* range : ranges) {
    const std::string nhdr = tmp.file("p.nhdr");
    write_bytes(nhdr, "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n"
                      "data file: s%d.raw " + std::string(range) + "\n");
    expect_read_error(nhdr, Status::invalid_input, {});
    const std::string mhd = tmp.file("p.mhd");
    write_bytes(mhd, "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementDataFile = s%d.raw " +
                         std::string(range) + "\n");
    expect_read_error(mhd, Status::invalid_input, {});
    const auto r = run_cli("info " + nhdr);
    EXPECT_EQ(r.exit_code, 2) << range << ": " << r.err;
  }
}

// ------------------------------------------------------------ 3. world coordinates too large

TEST(Hardening, WorldCoordinatesBeyondFloatRangeAreRejected) {
  TempDir tmp;
  const std::string big_spacing = tmp.file("spacing.nrrd"), big_origin = tmp.file("origin.nrrd"),
                    tiny = tmp.file("tiny.nrrd");
  write_bytes(big_spacing, small_nrrd("spacings: 1e39 1e39 1e39\n"));
  write_bytes(big_origin, small_nrrd("space dimension: 3\nspace origin: (1e39,1e39,1e39)\n"));
  write_bytes(tiny, small_nrrd("spacings: 1e-30 1e-30 1e-30\n"));
  expect_read_error(big_spacing, Status::invalid_input, {"voxel edge"});
  expect_read_error(big_origin, Status::invalid_input, {"world coordinates"});
  expect_read_error(tiny, Status::invalid_input, {"voxel edge"});
  for (const std::string& f : {big_spacing, big_origin}) {
    for (const std::string& cmd : {"extract " + f + " --iso 31.5 --base " + tmp.file("b.ply"),
                                  "mc " + f + " --iso 31.5 -o " + tmp.file("m.ply")}) {
      const auto r = run_cli(cmd);
      EXPECT_EQ(r.exit_code, 2) << cmd << ": " << r.err;
      EXPECT_EQ(lines(r.err), 1u) << r.err;
    }
  }
  EXPECT_FALSE(fs::exists(tmp.file("b.ply")));
  EXPECT_FALSE(fs::exists(tmp.file("m.ply")));
  // Within range: large but finite coordinates still mesh, and every coordinate is finite.
  const std::string ok = tmp.file("ok.nrrd");
  write_bytes(ok, small_nrrd("spacings: 1e15 1e15 1e15\n"));
  ASSERT_EQ(run_cli("mc " + ok + " --iso 31.5 --quiet -o " + tmp.file("ok.ply")).exit_code, 0);
  const Mesh m = read_mesh(tmp.file("ok.ply"));
  ASSERT_GT(m.num_triangles(), 0u);
  for (float c : m.positions) ASSERT_TRUE(std::isfinite(c));
  // Implicit inputs: --bounds beyond the range is a command-line error.
  EXPECT_EQ(run_cli("mc shape:sphere --bounds -1e39,-1,-1,1e39,1,1 -o " + tmp.file("s.ply")).exit_code, 1);
}

// ------------------------------------------------------------------------ 4. quadratic stats

TEST(Hardening, StatsOnARepeatedTriangleIsFast) {
  // One triangle repeated 160,000 times: three edges of valence 160,000. The boundary walk
  // used to scan each edge's sides once per side (50 s); now a binary search.
  TempDir tmp;
  const std::string path = tmp.file("rep.obj");
  std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  for (int i = 0; i < 160000; ++i) obj += "f 1 2 3\n";
  write_bytes(path, obj);
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = run_cli("stats " + path + " --json");
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(s, 20.0);  // ~0.3 s now; the quadratic scan took 50 s
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["nonmanifold_edges"], 3);
  EXPECT_EQ(j["duplicate_triangles"], 159999);
}

TEST(Hardening, SelfIntersectionCountIsBoundedOnPiledTriangles) {
  // A fan of 100,000 slivers over one spot: every pair overlaps. The count gives up (null)
  // instead of testing 5·10⁹ pairs.
  TempDir tmp;
  const std::string path = tmp.file("fan.obj");
  std::string obj = "v 0 0 0\n";
  for (int i = 0; i <= 100000; ++i) obj += "v 1 " + std::to_string(i * 1e-6) + " 0\n";
  for (int i = 0; i < 100000; ++i)
    obj += "f 1 " + std::to_string(i + 2) + " " + std::to_string(i + 3) + "\n";
  write_bytes(path, obj);
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = run_cli("stats " + path + " --json");
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(s, 20.0);  // ~0.2 s
  EXPECT_TRUE(nlohmann::json::parse(r.out)["self_intersecting_pairs"].is_null());
}

// ----------------------------------------------------------------------------- 5. outputs

/// A pid that existed and has exited (reaped), so no process has it (pids are not reused soon).
pid_t dead_pid() {
  const pid_t p = fork();
  if (p == 0) _exit(0);
  int status = 0;
  waitpid(p, &status, 0);
  return p;
}

TEST(Hardening, OutputTargetsMustBeRegularFiles) {
  TempDir tmp;
  const std::string victim = tmp.file("victim.txt");
  write_bytes(victim, "keep me");
  // A symlink at the target: refused (exit 4), the link's target untouched.
  fs::create_symlink(victim, tmp.file("link.ply"));
  auto r = run_cli("mc shape:sphere --res 16 -o " + tmp.file("link.ply"));
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("symbolic link"), std::string::npos) << r.err;
  EXPECT_EQ(read_bytes(victim), "keep me");
  EXPECT_TRUE(fs::is_symlink(tmp.file("link.ply")));
  // A directory, a device: refused before any work.
  fs::create_directory(tmp.file("dir.ply"));
  r = run_cli("mc shape:sphere --res 16 -o " + tmp.file("dir.ply"));
  EXPECT_EQ(r.exit_code, 4) << r.err;
  r = run_cli("extract shape:sphere --res 16 --base " + tmp.file("b.ply") + " --report /dev/null");
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("device"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp.file("b.ply")));  // checked before the base mesh was written
  struct stat st {};
  ASSERT_EQ(stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  // The library refuses too.
  EXPECT_THROW(write_file_atomically(tmp.file("link.ply"), [](std::ostream& o) { o << "x"; }), Error);
  EXPECT_EQ(read_bytes(victim), "keep me");
}

TEST(Hardening, TemporaryFilesAreExclusiveAndStaleOnesRemoved) {
  TempDir tmp;
  const std::string target = tmp.file("out.txt");
  const std::string prefix = tmp.file(temporary_file_prefix("out.txt"));
  // A link planted under every name this process could pick first: never followed.
  const std::string victim = tmp.file("victim.txt");
  write_bytes(victim, "keep me");
  for (int n = 0; n < 8; ++n)
    fs::create_symlink(victim, prefix + std::to_string(getpid()) + "-" + std::to_string(n));
  // A stale temporary of a dead process, and one of a live process (this one's parent).
  const std::string stale = prefix + std::to_string(dead_pid()) + "-0";
  const std::string live = prefix + std::to_string(getppid()) + "-0";
  write_bytes(stale, "half");
  write_bytes(live, "in progress");
  write_file_atomically(target, [](std::ostream& o) { o << "new"; });
  EXPECT_EQ(read_bytes(target), "new");
  EXPECT_EQ(read_bytes(victim), "keep me");
  EXPECT_FALSE(fs::exists(stale));
  EXPECT_TRUE(fs::exists(live));
  // No temporary of ours is left behind, after success or after a failing writer.
  EXPECT_THROW(write_file_atomically(target, [](std::ostream&) { throw Error(Status::internal, "x"); }), Error);
  EXPECT_EQ(read_bytes(target), "new");
  std::size_t ours = 0;
  for (const auto& e : fs::directory_iterator(tmp.path()))
    if (e.path().filename().string().find(temporary_file_prefix("out.txt") + std::to_string(getpid())) == 0 &&
        !fs::is_symlink(e.symlink_status()))
      ++ours;
  EXPECT_EQ(ours, 0u);
}

TEST(Hardening, EveryOutputIsCheckedBeforeAnyWork) {
  TempDir tmp;
  // A missing --hierarchy folder: found at once, nothing else written.
  const auto t0 = std::chrono::steady_clock::now();
  auto r = run_cli("extract shape:torus --res 96 --base " + tmp.file("b.ply") + " -o " +
                   tmp.file("m.ply") + " --hierarchy " + tmp.file("no/such/h.amh"));
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("--hierarchy"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_LT(s, 2.0);
  EXPECT_FALSE(fs::exists(tmp.file("b.ply")));
  EXPECT_FALSE(fs::exists(tmp.file("m.ply")));
  // Unknown extensions and one file named twice are command-line errors.
  r = run_cli("extract shape:torus --res 32 --base " + tmp.file("b.xyz"));
  EXPECT_EQ(r.exit_code, 3) << r.err;  // an unsupported format (gltf_test: the same code)
  EXPECT_NE(r.err.find("b.xyz"), std::string::npos) << r.err;
  r = run_cli("extract shape:torus --res 32 --hierarchy " + tmp.file("h.bin"));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  r = run_cli("extract shape:torus --res 32 --base " + tmp.file("b.ply") + " -o " + tmp.file("./b.ply"));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("same file"), std::string::npos) << r.err;
  r = run_cli("level " + tmp.file("missing.amh") + " --all -o " + tmp.file("x.unknown"));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  if (geteuid() != 0) {  // root writes anywhere
    fs::create_directory(tmp.file("ro"));
    fs::permissions(tmp.file("ro"), fs::perms::owner_read | fs::perms::owner_exec);
    r = run_cli("mc shape:sphere --res 16 -o " + tmp.file("ro/x.ply"));
    EXPECT_EQ(r.exit_code, 4) << r.err;
    EXPECT_NE(r.err.find("not writable"), std::string::npos) << r.err;
  }
}

// ----------------------------------------------------------------------- 6. silent acceptance

TEST(Hardening, HugeVtkLookupTableIsRejected) {
  TempDir tmp;
  const std::string path = tmp.file("lut.vtk");
  // 2^62 entries: 4*n wrapped to 0 and the table was "skipped" without reading anything.
  write_bytes(path, "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n"
                    "POINT_DATA 8\nLOOKUP_TABLE t 4611686018427387904\n"
                    "SCALARS s int\nLOOKUP_TABLE default\n1 2 3 4 5 6 7 8\n");
  expect_read_error(path, Status::invalid_input, {"LOOKUP_TABLE"});
}

TEST(Hardening, RandomBytesNamedObjAreNotAMesh) {
  TempDir tmp;
  std::string junk;
  std::uint32_t x = 12345;
  for (int i = 0; i < 4096; ++i) {
    x = x * 1664525u + 1013904223u;
    junk += static_cast<char>(x >> 24);
  }
  write_bytes(tmp.file("junk.obj"), junk);
  expect_error([&] { (void)read_mesh(tmp.file("junk.obj")); }, Status::invalid_input,
               tmp.file("junk.obj"), {"not a text OBJ file"});
  const auto r = run_cli("stats " + tmp.file("junk.obj"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  // A real (empty or commented) OBJ is still fine.
  write_bytes(tmp.file("empty.obj"), "# nothing\r\n\tg x\n");
  EXPECT_EQ(read_mesh(tmp.file("empty.obj")).num_triangles(), 0u);
}

TEST(Hardening, DataFilesMustLieBesideTheHeader) {
  TempDir tmp;
  fs::create_directory(tmp.file("sub"));
  std::string d(64, '\x05');
  write_bytes(tmp.file("sub/data.raw"), d);
  write_bytes(tmp.file("outside.raw"), d);
  const std::string hdr = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: raw\ndata file: ";
  write_bytes(tmp.file("sub/ok.nhdr"), hdr + "./data.raw\n");
  EXPECT_EQ(read_volume(tmp.file("sub/ok.nhdr")).at(0), 5.0);
  for (const std::string& name : std::vector<std::string>{"/etc/passwd", "../outside.raw", "x/../../outside.raw", tmp.file("outside.raw")}) {
    write_bytes(tmp.file("sub/bad.nhdr"), hdr + name + "\n");
    expect_read_error(tmp.file("sub/bad.nhdr"), Status::invalid_input, {"outside the header's folder"});
    write_bytes(tmp.file("sub/bad.mhd"), "NDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\nElementDataFile = " + name + "\n");
    expect_read_error(tmp.file("sub/bad.mhd"), Status::invalid_input, {"outside the header's folder"});
  }
}

// ------------------------------------------------------------------------------ 7. messages

TEST(Hardening, ControlBytesInMessagesAreEscaped) {
  TempDir tmp;
  const std::string path = tmp.file("esc.nrrd");
  write_bytes(path, "NRRD0004\ntype: \x1b[2J\x1b]0;pwned\x07uint8\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n" +
                        std::string(64, '\0'));
  const auto r = run_cli("info " + path);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_EQ(r.err.find('\x1b'), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\x07'), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("\\x1b[2J"), std::string::npos) << r.err;
  // Bytes above 0x7f: a stray 0x9b (CSI on 8-bit terminals), a C1 control in UTF-8 (U+009B) and
  // invalid UTF-8 are escaped; UTF-8 text stays as it is (found by fuzz_metaimage: raw 0xff bytes
  // of a header were echoed).
  const std::string utf = tmp.file("utf.nrrd");
  write_bytes(utf, "NRRD0004\ntype: \x9b" "2J\xc2\x9b" "2J\xff\xfe caf\xc3\xa9 \xe2\x84\x83\ndimension: 3\n"
                   "sizes: 4 4 4\nencoding: raw\n\n" + std::string(64, '\0'));
  const auto u = run_cli("info " + utf);
  EXPECT_EQ(u.exit_code, 2) << u.err;
  EXPECT_NE(u.err.find("\\x9b2J\\xc2\\x9b2J\\xff\\xfe caf\xc3\xa9 \xe2\x84\x83"), std::string::npos) << u.err;
}

TEST(Hardening, CommandLineMessages) {
  TempDir tmp;
  // A non-finite --iso is a command-line error naming the option.
  for (const char* v : {"nan", "inf", "-inf"}) {
    const auto r = run_cli(std::string("mc shape:sphere --res 16 --iso ") + v + " -o " + tmp.file("s.ply"));
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("--iso"), std::string::npos) << r.err;
  }
  // No doubled prefix.
  auto r = run_cli("mc shape:sphere --res 16");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.err.rfind("adamesh mc: ", 0), 0u) << r.err;
  EXPECT_EQ(r.err.find("adamesh: adamesh"), std::string::npos) << r.err;
  // mc with the iso-value outside the range fails like extract (it wrote an empty mesh).
  r = run_cli("mc shape:sphere --res 16 --iso 100 -o " + tmp.file("s.ply"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("outside the value range"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(tmp.file("s.ply")));
  // No half-written progress line before an error (stderr is not a terminal here): only whole
  // "stage done T s" lines of finished stages, then the error line.
  r = run_cli("extract shape:sphere --res 16 --iso 100 --base " + tmp.file("b.ply"));
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_FALSE(r.err.empty());
  EXPECT_EQ(r.err.back(), '\n');
  std::istringstream err(r.err);
  std::vector<std::string> err_lines;
  for (std::string l; std::getline(err, l);) err_lines.push_back(l);
  ASSERT_FALSE(err_lines.empty());
  EXPECT_EQ(err_lines.back().rfind("adamesh: ", 0), 0u) << r.err;
  EXPECT_NE(err_lines.back().find("outside the value range"), std::string::npos) << r.err;
  for (std::size_t i = 0; i + 1 < err_lines.size(); ++i)
    EXPECT_NE(err_lines[i].find(" done "), std::string::npos) << "partial line: " << r.err;
}

TEST(Hardening, AllNanVolumeInfo) {
  TempDir tmp;
  const std::string path = tmp.file("nan.nrrd");
  std::vector<float> v(64, std::numeric_limits<float>::quiet_NaN());
  write_bytes(path, "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 4 4\nendian: little\nencoding: raw\n\n" +
                        to_bytes(v));
  auto r = run_cli("info " + path);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("percentiles    none (no finite samples)"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("1%: 0"), std::string::npos) << r.out;
  r = run_cli("info " + path + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const auto& [k, p] : j["percentiles"].items()) EXPECT_TRUE(p.is_null()) << k;
  r = run_cli("mc " + path + " --iso 0 -o " + tmp.file("x.ply"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
}

// ------------------------------------------------------------- outputs of `view`, `-o -` stdout

TEST(Hardening, ViewOutputIsCheckedBeforeAnyWork) {
  // `view` goes through the same checks as the other commands, before reading its input or
  // looking for the viewer bundle (so these hold in builds without the npm packages too).
  TempDir tmp;
  const std::string victim = tmp.file("victim.txt");
  write_bytes(victim, "keep me");
  fs::create_symlink(victim, tmp.file("link.html"));
  const std::string missing = tmp.file("missing.amh");  // would be exit 2 if it were read first
  auto r = run_cli("view " + missing + " -o " + tmp.file("link.html"));
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("symbolic link"), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_EQ(read_bytes(victim), "keep me");
  EXPECT_TRUE(fs::is_symlink(tmp.file("link.html")));
  fs::create_directory(tmp.file("dir.html"));
  r = run_cli("view " + missing + " -o " + tmp.file("dir.html"));
  EXPECT_EQ(r.exit_code, 4) << r.err;
  r = run_cli("view " + missing + " -o " + tmp.file("no/such/v.html"));
  EXPECT_EQ(r.exit_code, 4) << r.err;
  EXPECT_NE(r.err.find("does not exist"), std::string::npos) << r.err;
  r = run_cli("view " + missing + " -o /dev/null.html");  // a folder that cannot be written
  if (geteuid() != 0) EXPECT_EQ(r.exit_code, 4) << r.err;
  r = run_cli("view " + missing + " -o " + tmp.file("v.png"));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("HTML"), std::string::npos) << r.err;
  r = run_cli("view " + missing + " -o -");  // no page to standard output
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(r.out.empty());
  if (geteuid() != 0) {
    fs::create_directory(tmp.file("ro"));
    fs::permissions(tmp.file("ro"), fs::perms::owner_read | fs::perms::owner_exec);
    r = run_cli("view " + missing + " -o " + tmp.file("ro/v.html"));
    EXPECT_EQ(r.exit_code, 4) << r.err;
    EXPECT_NE(r.err.find("not writable"), std::string::npos) << r.err;
  }
  // A good name gets past the checks: the missing input (2) or a build without viewer (3).
  r = run_cli("view " + missing + " -o " + tmp.file("v.html"));
  EXPECT_TRUE(r.exit_code == 2 || r.exit_code == 3) << r.err;
  EXPECT_FALSE(fs::exists(tmp.file("v.html")));
}

/// Runs a shell command line (stdout and stderr redirected by the caller) and returns its exit
/// status; 128 + N when the shell reports signal N.
int shell(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(Hardening, MeshToStandardOutputIsTheFileBytes) {
  TempDir tmp;
  const std::string sphere = "mc shape:sphere --res 16";
  // Every streamable format: `-o - --format F` gives exactly the bytes of `-o file.F`, and the
  // summary goes to stderr.
  for (const std::string f : {"ply", "obj", "off", "stl", "glb"}) {
    const std::string file = tmp.file("s." + f);
    ASSERT_EQ(run_cli(sphere + " --quiet -o " + file).exit_code, 0);
    const auto r = run_cli(sphere + " -o - --format " + f);
    EXPECT_EQ(r.exit_code, 0) << f << ": " << r.err;
    EXPECT_EQ(r.out, read_bytes(file)) << f;
    EXPECT_NE(r.err.find("mc: "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("wrote standard output"), std::string::npos) << r.err;
  }
  {
    const auto r = run_cli(sphere + " -o - --format ply --ascii --quiet");
    ASSERT_EQ(run_cli(sphere + " --quiet --ascii -o " + tmp.file("a.ply")).exit_code, 0);
    EXPECT_EQ(r.out, read_bytes(tmp.file("a.ply")));
    EXPECT_TRUE(r.err.empty()) << r.err;
  }
  // Through a pipe, as a user would: `... -o - --format ply | head -c N` is a valid PLY, the
  // same bytes as the file.
  const std::string ply = read_bytes(tmp.file("s.ply"));
  auto r = run_cli(sphere + " -o - --format ply 2>" + tmp.file("err") + " | head -c " +
                   std::to_string(ply.size() + 100));
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out, ply);
  write_bytes(tmp.file("piped.ply"), r.out);
  const Mesh m = read_mesh(tmp.file("piped.ply"));
  EXPECT_EQ(m.num_triangles(), read_mesh(tmp.file("s.ply")).num_triangles());
  EXPECT_GT(m.num_triangles(), 0u);
  // extract and level: the same, with the progress and summary lines on stderr only.
  ASSERT_EQ(run_cli("extract shape:torus --res 32 --levels 1 --quiet -o " + tmp.file("t.ply") +
                    " --hierarchy " + tmp.file("t.amh")).exit_code, 0);
  r = run_cli("extract shape:torus --res 32 --levels 1 -o - --format ply --report " +
              tmp.file("t.json"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, read_bytes(tmp.file("t.ply")));
  EXPECT_NE(r.err.find("base mesh"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(tmp.file("t.json")));
  ASSERT_EQ(run_cli("level " + tmp.file("t.amh") + " --all --quiet -o " + tmp.file("l.obj")).exit_code, 0);
  r = run_cli("level " + tmp.file("t.amh") + " --all -o - --format obj");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, read_bytes(tmp.file("l.obj")));
  EXPECT_NE(r.err.find("triangles"), std::string::npos) << r.err;
}

TEST(Hardening, MeshToStandardOutputErrors) {
  TempDir tmp;
  const std::string sphere = "mc shape:sphere --res 16";
  // Command-line errors (1): no --format, an unknown one, --format disagreeing with a file's
  // extension, "-" for an output other than the mesh of -o.
  auto r = run_cli(sphere + " -o -");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("--format"), std::string::npos) << r.err;
  EXPECT_TRUE(r.out.empty());
  EXPECT_EQ(run_cli(sphere + " -o - --format xyz").exit_code, 1);
  EXPECT_EQ(run_cli(sphere + " -o " + tmp.file("x.obj") + " --format ply").exit_code, 1);
  EXPECT_FALSE(fs::exists(tmp.file("x.obj")));
  EXPECT_EQ(run_cli("extract shape:torus --res 32 --base -").exit_code, 1);
  EXPECT_EQ(run_cli("extract shape:torus --res 32 -o " + tmp.file("t.ply") + " --hierarchy -").exit_code, 1);
  EXPECT_EQ(run_cli("extract shape:torus --res 32 --base " + tmp.file("b.ply") + " --format ply").exit_code, 1);
  EXPECT_FALSE(fs::exists(tmp.file("b.ply")));
  // Unsupported (3): glTF is two files; compression needs glb.
  EXPECT_EQ(run_cli(sphere + " -o - --format gltf").exit_code, 3);
  EXPECT_EQ(run_cli(sphere + " -o - --format ply --compress").exit_code, 3);
  // Output errors (4): standard output closed or read-only (found before any work), a full
  // device (found at the write). Nothing is written to standard output on any error.
  const std::string cli = std::string("'") + ADAMESH_CLI + "' ";
  const std::string err = tmp.file("err");
  EXPECT_EQ(shell(cli + sphere + " -o - --format ply >&- 2>" + err), 4);
  EXPECT_NE(read_bytes(err).find("not open for writing"), std::string::npos) << read_bytes(err);
  EXPECT_EQ(shell(cli + sphere + " -o - --format ply 1</dev/null 2>" + err), 4);
  EXPECT_EQ(lines(read_bytes(err)), 1u) << read_bytes(err);
  EXPECT_EQ(shell(cli + sphere + " -o - --format ply >/dev/full 2>" + err), 4);
  EXPECT_NE(read_bytes(err).find("standard output: No space left"), std::string::npos)
      << read_bytes(err);
  EXPECT_EQ(lines(read_bytes(err)), 1u) << read_bytes(err);
  r = run_cli(sphere + " --iso 100 -o - --format ply");  // bad input (2): nothing on stdout
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(r.out.empty());
  r = run_cli("level " + tmp.file("missing.amh") + " --all -o - --format ply");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(r.out.empty());
  // Binary formats are not written to a terminal (`script` gives the command a pty).
  if (shell("command -v script >/dev/null 2>&1") == 0) {
    EXPECT_EQ(shell("script -qec \"" + cli + sphere + " -o - --format ply\" /dev/null >" + err +
                    " 2>&1"), 4) << read_bytes(err);
    EXPECT_NE(read_bytes(err).find("terminal"), std::string::npos) << read_bytes(err);
  }
}

// ------------------------------------------------------------------ found by fuzzing (issue 17)

TEST(Hardening, DicomPreambleWithACutShortMetaHeaderIsAnError) {
  // fuzz_metaimage, fuzz_slc, fuzz_nrrd: any bytes with "DICM" at offset 128 went to GDCM, whose
  // assertions (kept in Debian's build) aborted on a meta header cut short (gdcmReader.cxx:385)
  // or an element running past the end (gdcmFileMetaInformation.cxx:436): exit 134 from `info`.
  TempDir tmp;
  const std::string prefixes[] = {std::string(128, '\0'),
                                  "NRRD0004\n" + std::string(119, '\xc7'),
                                  "NDims = 3\nElementDataFile = x\n" + std::string(98, '\xff'),
                                  "Hiz" + std::string(125, '\xff')};
  const std::string tails[] = {"", "\x0b\x0b", std::string("\x02\x00", 2),
                               std::string("\x02\x00\x10\x00UI\x04\x00", 8),
                               std::string("\x02\x00\x10\x00OB\x00\x00\xff\xff\xff\x7f", 12)};
  int n = 0;
  for (const std::string ext : {".mha", ".nrrd", ".slc", ".nii", ".vtk", ".vti", ".mrc", ".dcm", ""})
    for (const auto& prefix : prefixes)
      for (const auto& tail : tails) {
        ASSERT_EQ(prefix.size(), 128u);
        const std::string path = tmp.file("f" + std::to_string(n++) + ext);
        write_bytes(path, prefix + "DICM" + tail);
        EXPECT_THROW((void)read_volume(path), Error) << path;
      }
  // The command line: one error line, exit 2, for a named slice and for its folder.
  fs::create_directory(tmp.file("series"));
  write_bytes(tmp.file("series/s.dcm"), std::string(128, '\0') + "DICM" + std::string("\x02\x00", 2));
  auto r = run_cli("info " + tmp.file("series/s.dcm"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("not a readable DICOM file"), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  r = run_cli("info " + tmp.file("series"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  // A .mha with the magic is read as MetaImage (its own error), not as DICOM.
  write_bytes(tmp.file("m.mha"), prefixes[2] + "DICM\x0b\x0b");
  r = run_cli("info " + tmp.file("m.mha"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.find("DICOM"), std::string::npos) << r.err;
}

TEST(Hardening, DicomLengthsBeyondTheFileAreErrorsNotAllocations) {
  // fuzz_dicom, first minute: a 9 KB slice whose element declared 2.6 GB made GDCM allocate the
  // value before reading it (gdcm::ByteValue::SetLength; libFuzzer's malloc limit caught it).
  // Every element, item and fragment length is now checked against the file (and against what
  // encloses it) before GDCM sees the file; each variant is one clean error naming the problem.
  TempDir tmp;
  auto le16 = [](unsigned v) { return std::string{char(v & 0xff), char(v >> 8)}; };
  auto le32 = [&](std::uint32_t v) { return le16(v & 0xffff) + le16(v >> 16); };
  auto tag = [&](unsigned g, unsigned e) { return le16(g) + le16(e); };
  auto meta = [&](const std::string& ts) {  // preamble, DICM, (0002,0010) transfer syntax
    std::string uid = ts;
    if (uid.size() % 2) uid.push_back('\0');
    return std::string(128, '\0') + "DICM" + tag(2, 0x10) + "UI" + le16(unsigned(uid.size())) + uid;
  };
  const std::string implicit = meta("1.2.840.10008.1.2"), explicit_le = meta("1.2.840.10008.1.2.1");
  const std::string ct = tag(8, 0x60) + le32(2) + "CT";
  const std::uint32_t huge = 0x9c000000u, undefined = 0xffffffffu;
  const std::pair<std::string, std::string> cases[] = {
      {"implicit element", implicit + ct + tag(0x10, 0x10) + le32(huge) + "Doe^John"},
      {"explicit OB", explicit_le + tag(0x10, 0x10) + "PN" + le16(4) + "Doe " + tag(0x7fe0, 0x10) +
                          "OB" + le16(0) + le32(huge) + std::string(64, 'x')},
      {"item inside a sequence",
       implicit + ct + tag(8, 0x1140) + le32(undefined) + tag(0xfffe, 0xe000) + le32(undefined) +
           tag(8, 0x1150) + le32(huge) + "1.2.3"},
      {"sequence of defined length", implicit + ct + tag(8, 0x1140) + le32(24) +
                                         tag(0xfffe, 0xe000) + le32(16) + tag(8, 0x1150) +
                                         le32(huge) + std::string(8, '1')},
      {"fragment", explicit_le + tag(0x7fe0, 0x10) + "OB" + le16(0) + le32(undefined) +
                       tag(0xfffe, 0xe000) + le32(0) + tag(0xfffe, 0xe000) + le32(huge) + "ab"},
      // fuzz_dicom: an unknown VR ("CS" → "MS") is read by GDCM with a 4-byte length.
      {"unknown VR", explicit_le + tag(0x28, 0x4) + "MS" + le16(12) + "MONOCHROME2 " +
                         tag(0x28, 0x10) + "US" + le16(2) + le16(32)},
      // A UN value holding implicit VR items, as GDCM re-reads a UN its dictionary calls SQ.
      {"UN sequence", explicit_le + tag(8, 0x1140) + "UN" + le16(0) + le32(16) +
                          tag(0xfffe, 0xe000) + le32(8) + tag(8, 0x1150) + le32(huge)},
      // fuzz_dicom: GDCM's assertion on SamplesPerPixel (gdcmPixelFormat.h:94) aborted.
      {"samples per pixel", explicit_le + tag(0x28, 0x2) + "US" + le16(2) + le16(2)},
      // fuzz_dicom's second finding: the sequence delimitation's length read as a fragment's.
      {"delimitation", explicit_le + tag(0x7fe0, 0x10) + "OB" + le16(0) + le32(undefined) +
                           tag(0xfffe, 0xe000) + le32(0) + tag(0xfffe, 0xe000) + le32(2) + "ab" +
                           tag(0xfffe, 0xe0dd) + le32(0xffff0000u)},
  };
  for (const auto& [name, bytes] : cases) {
    const std::string path = tmp.file("slice.dcm");
    write_bytes(path, bytes);
    try {
      (void)read_volume(path);
      ADD_FAILURE() << name << ": read";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("not a readable DICOM file"), std::string::npos)
          << name << ": " << e.what();
      const std::string what = e.what();
      EXPECT_TRUE(what.find("declares") != std::string::npos ||
                  what.find("delimitation with a length") != std::string::npos ||
                  what.find("unknown VR 'MS'") != std::string::npos ||
                  what.find("SamplesPerPixel (0028,0002) is 2") != std::string::npos)
          << name << ": " << what;
    }
  }
  // Sequences nested 40 deep: refused before GDCM's recursion.
  std::string deep = implicit + ct;
  for (int i = 0; i < 40; ++i)
    deep += tag(8, 0x1140) + le32(undefined) + tag(0xfffe, 0xe000) + le32(undefined);
  write_bytes(tmp.file("deep.dcm"), deep);
  EXPECT_THROW((void)read_volume(tmp.file("deep.dcm")), Error);
  // On the command line, for the slice and for its folder: one line naming the file, exit 2.
  fs::create_directory(tmp.file("series"));
  write_bytes(tmp.file("series/IM1"), cases[0].second);
  for (const std::string arg : {tmp.file("series/IM1"), tmp.file("series")}) {
    const auto r = run_cli("info " + arg);
    EXPECT_EQ(r.exit_code, 2) << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find("IM1: not a readable DICOM file: element (0010,0010) declares"),
              std::string::npos)
        << r.err;
  }
}

}  // namespace
}  // namespace adamesh
