// Mesh readers and writers: exact round trips in every format, hand-written files with quads,
// negative indices and unknown properties, every kind of bad input, and atomic writes.
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>

#include "adamesh/error.h"
#include "adamesh/io.h"
#include "testing.h"

using namespace adamesh;
using adamesh::testutil::read_bytes;
using adamesh::testutil::TempDir;
using adamesh::testutil::write_bytes;

namespace {

/// A wavy n×n grid with coordinates that have no short decimal form, normals and two attributes.
Mesh wavy_grid(int n, bool with_extras = true) {
  Mesh m;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double x = i / 3.0, y = j / 7.0;
      m.add_vertex({x, y, 0.1 * std::sin(x * 1.7) * std::cos(y * 2.3) + 1e-3 / (1 + i + j)});
    }
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const auto v = static_cast<std::uint32_t>(j * n + i), nn = static_cast<std::uint32_t>(n);
      m.add_triangle(v, v + 1, v + nn + 1);
      m.add_triangle(v, v + nn + 1, v + nn);
    }
  if (with_extras) {
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
      const Vec3 d = normalized(Vec3{0.1 * std::sin(double(v)), 0.2, 1.0});
      m.normals.insert(m.normals.end(), {float(d.x), float(d.y), float(d.z)});
    }
    VertexAttribute level{"level", {}, {}}, weight{"weight", {}, {}};
    for (std::size_t v = 0; v < m.num_vertices(); ++v) {
      level.i32.push_back(static_cast<std::int32_t>(v % 5) - 2);
      weight.f32.push_back(static_cast<float>(std::sqrt(double(v) + 0.5)));
    }
    m.attributes = {level, weight};
  }
  return m;
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

/// Runs f, expects Error(status) whose message contains `needle`.
template <class F>
void expect_error(F&& f, Status status, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no error; expected one containing '" << needle << "'";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), status) << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

std::size_t files_in(const std::filesystem::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

}  // namespace

TEST(MeshIo, PlyBinaryRoundTripIsBitExactWithNormalsAndAttributes) {
  TempDir tmp;
  const Mesh m = wavy_grid(9);
  write_mesh(m, tmp.file("a.ply"));
  EXPECT_NE(read_bytes(tmp.file("a.ply")).find("format binary_little_endian 1.0"), std::string::npos);
  const Mesh r = read_mesh(tmp.file("a.ply"));
  EXPECT_TRUE(same_bits(r.positions, m.positions));
  EXPECT_EQ(r.triangles, m.triangles);
  EXPECT_TRUE(same_bits(r.normals, m.normals));
  ASSERT_EQ(r.attributes.size(), 2u);
  ASSERT_NE(r.attribute("level"), nullptr);
  EXPECT_TRUE(r.attribute("level")->is_integer());
  EXPECT_EQ(r.attribute("level")->i32, m.attributes[0].i32);
  ASSERT_NE(r.attribute("weight"), nullptr);
  EXPECT_FALSE(r.attribute("weight")->is_integer());
  EXPECT_TRUE(same_bits(r.attribute("weight")->f32, m.attributes[1].f32));
}

TEST(MeshIo, PlyAsciiRoundTripIsExactToo) {
  TempDir tmp;
  const Mesh m = wavy_grid(7);
  MeshWriteOptions o;
  o.ascii = true;
  write_mesh(m, tmp.file("a.ply"), o);
  write_mesh(m, tmp.file("b.ply"));
  const std::string text = read_bytes(tmp.file("a.ply"));
  EXPECT_NE(text.find("format ascii 1.0"), std::string::npos);
  EXPECT_NE(text.find("property int level"), std::string::npos);
  EXPECT_NE(text.find("property float weight"), std::string::npos);
  EXPECT_NE(text.find("property list uchar int vertex_indices"), std::string::npos);
  const Mesh a = read_mesh(tmp.file("a.ply")), b = read_mesh(tmp.file("b.ply"));
  EXPECT_TRUE(same_bits(a.positions, m.positions));
  EXPECT_TRUE(same_bits(a.positions, b.positions));
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_TRUE(same_bits(a.normals, b.normals));
  EXPECT_EQ(a.attribute("level")->i32, b.attribute("level")->i32);
  EXPECT_TRUE(same_bits(a.attribute("weight")->f32, b.attribute("weight")->f32));
}

TEST(MeshIo, WriteOptionsDropNormalsAndAttributes) {
  TempDir tmp;
  MeshWriteOptions o;
  o.write_normals = false;
  o.write_attributes = false;
  write_mesh(wavy_grid(4), tmp.file("a.ply"), o);
  const Mesh r = read_mesh(tmp.file("a.ply"));
  EXPECT_TRUE(r.normals.empty());
  EXPECT_TRUE(r.attributes.empty());
  EXPECT_EQ(r.num_triangles(), 18u);
}

TEST(MeshIo, ObjRoundTripWithAndWithoutNormals) {
  TempDir tmp;
  const Mesh m = wavy_grid(6);
  write_mesh(m, tmp.file("a.obj"));
  const std::string text = read_bytes(tmp.file("a.obj"));
  EXPECT_NE(text.find("\nvn "), std::string::npos);
  EXPECT_NE(text.find("f 1//1 2//2 8//8\n"), std::string::npos);
  const Mesh r = read_mesh(tmp.file("a.obj"));
  EXPECT_TRUE(same_bits(r.positions, m.positions));
  EXPECT_EQ(r.triangles, m.triangles);
  EXPECT_TRUE(same_bits(r.normals, m.normals));
  MeshWriteOptions o;
  o.write_normals = false;
  write_mesh(m, tmp.file("b.obj"), o);
  EXPECT_NE(read_bytes(tmp.file("b.obj")).find("f 1 2 8\n"), std::string::npos);
  const Mesh s = read_mesh(tmp.file("b.obj"));
  EXPECT_TRUE(s.normals.empty());
  EXPECT_EQ(s.triangles, m.triangles);
}

TEST(MeshIo, OffRoundTripWithAndWithoutNormals) {
  TempDir tmp;
  const Mesh m = wavy_grid(5);
  write_mesh(m, tmp.file("a.off"));
  EXPECT_EQ(read_bytes(tmp.file("a.off")).substr(0, 5), "NOFF\n");
  const Mesh r = read_mesh(tmp.file("a.off"));
  EXPECT_TRUE(same_bits(r.positions, m.positions));
  EXPECT_EQ(r.triangles, m.triangles);
  EXPECT_TRUE(same_bits(r.normals, m.normals));
  Mesh plain = m;
  plain.normals.clear();
  write_mesh(plain, tmp.file("b.off"));
  EXPECT_EQ(read_bytes(tmp.file("b.off")).substr(0, 4), "OFF\n");
  const Mesh s = read_mesh(tmp.file("b.off"));
  EXPECT_TRUE(same_bits(s.positions, m.positions));
  EXPECT_TRUE(s.normals.empty());
}

TEST(MeshIo, StlRoundTripIsBitExactAndWeldsVertices) {
  TempDir tmp;
  const Mesh m = wavy_grid(8, false);
  write_mesh(m, tmp.file("a.stl"));
  const std::string bytes = read_bytes(tmp.file("a.stl"));
  ASSERT_EQ(bytes.size(), 84 + 50 * m.num_triangles());
  // The facet normal is the unit normal of the triangle.
  float n[3];
  std::memcpy(n, bytes.data() + 84, 12);
  const Vec3 a = m.vertex(m.triangles[0]), b = m.vertex(m.triangles[1]), c = m.vertex(m.triangles[2]);
  const Vec3 expect = normalized(cross(b - a, c - a));
  EXPECT_NEAR(n[0], expect.x, 1e-6);
  EXPECT_NEAR(n[2], expect.z, 1e-6);
  const Mesh r = read_mesh(tmp.file("a.stl"));
  EXPECT_EQ(r.num_vertices(), m.num_vertices());  // all positions distinct: welded back exactly
  ASSERT_EQ(r.num_triangles(), m.num_triangles());
  for (std::size_t i = 0; i < m.triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const float x = m.positions[3 * m.triangles[i] + k], y = r.positions[3 * r.triangles[i] + k];
      EXPECT_EQ(std::memcmp(&x, &y, 4), 0) << "corner " << i;
    }
}

TEST(MeshIo, AsciiStlIsRead) {
  TempDir tmp;
  write_bytes(tmp.file("a.stl"),
              "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
              "   vertex 0 1 0\n  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n"
              "   vertex 1 0 0\n   vertex 1 1 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid t\n");
  const Mesh r = read_mesh(tmp.file("a.stl"));
  EXPECT_EQ(r.num_vertices(), 4u);
  EXPECT_EQ(r.triangles, (std::vector<std::uint32_t>{0, 1, 2, 1, 3, 2}));
}

TEST(MeshIo, HandWrittenAsciiPlyWithQuadsUnknownPropertiesAndElements) {
  TempDir tmp;
  write_bytes(tmp.file("q.ply"),
              "ply\r\nformat ascii 1.0\r\ncomment hand written\r\nobj_info test\r\n"
              "element vertex 5\r\nproperty double x\r\nproperty double y\r\nproperty float z\r\n"
              "property uchar red\r\nproperty list uchar float junk\r\nproperty float quality\r\n"
              "element face 2\r\nproperty uchar flags\r\nproperty list uint short vertex_indices\r\n"
              "element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\nend_header\r\n"
              "0 0 0 255 2 1.5 2.5 0.25\r\n1 0 0 128 0 0.5\r\n1 1 0 0 1 9 0.75\r\n0 1 0 1 0 1\r\n"
              "0.5 0.5 1 2 0 -3e2\r\n7 4 0 1 2 3\r\n0 3 1 2 4\r\n0 1\r\n");
  const Mesh r = read_mesh(tmp.file("q.ply"));
  ASSERT_EQ(r.num_vertices(), 5u);
  EXPECT_EQ(r.vertex(4).z, 1.0);
  EXPECT_EQ(r.vertex(2).x, 1.0);
  // Quad fan-triangulated, then the triangle.
  EXPECT_EQ(r.triangles, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 1, 2, 4}));
  ASSERT_EQ(r.attributes.size(), 2u);
  EXPECT_EQ(r.attribute("red")->i32, (std::vector<std::int32_t>{255, 128, 0, 1, 2}));
  EXPECT_EQ(r.attribute("quality")->f32, (std::vector<float>{0.25f, 0.5f, 0.75f, 1.0f, -300.0f}));
  EXPECT_TRUE(r.normals.empty());
}

TEST(MeshIo, HandWrittenBigEndianPly) {
  TempDir tmp;
  std::string s =
      "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nproperty short s\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n";
  auto be32 = [&](std::uint32_t v) {
    for (int k = 3; k >= 0; --k) s.push_back(static_cast<char>((v >> (8 * k)) & 0xff));
  };
  auto bef = [&](float f) {
    std::uint32_t u;
    std::memcpy(&u, &f, 4);
    be32(u);
  };
  const float p[4][3] = {{0, 0, 0}, {1.1f, 0, 0}, {1.1f, 2.2f, 0}, {0, 2.2f, -3.3f}};
  for (int v = 0; v < 4; ++v) {
    for (float c : p[v]) bef(c);
    s.push_back(static_cast<char>(0xff));  // short -2
    s.push_back(static_cast<char>(0xfe));
  }
  s.push_back(4);
  for (std::uint32_t i : {3u, 2u, 1u, 0u}) be32(i);
  write_bytes(tmp.file("be.ply"), s);
  const Mesh r = read_mesh(tmp.file("be.ply"));
  ASSERT_EQ(r.num_vertices(), 4u);
  EXPECT_EQ(r.positions[3 * 3 + 2], -3.3f);
  EXPECT_EQ(r.positions[3 * 1], 1.1f);
  EXPECT_EQ(r.triangles, (std::vector<std::uint32_t>{3, 2, 1, 3, 1, 0}));
  EXPECT_EQ(r.attribute("s")->i32, (std::vector<std::int32_t>{-2, -2, -2, -2}));
}

TEST(MeshIo, HandWrittenObjWithQuadsSlashFormsAndNegativeIndices) {
  TempDir tmp;
  write_bytes(tmp.file("q.obj"),
              "# comment\nmtllib x.mtl\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0 0.5 0.5 0.5\n"
              "vt 0 0\nvn 0 0 1\ng group\ns off\nusemtl m\nf 1/1/1 2/1/1 3/1/1 4/1/1\n"
              "v 0.5 0.5 1\nf -4//1 -3//1 -1//1\nf 5/1 4/1 1/1\nl 1 2\n");
  const Mesh r = read_mesh(tmp.file("q.obj"));
  ASSERT_EQ(r.num_vertices(), 5u);
  EXPECT_EQ(r.triangles, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 1, 2, 4, 4, 3, 0}));
  EXPECT_TRUE(r.normals.empty());  // vn indices do not match the v indices
}

TEST(MeshIo, HandWrittenOffWithCommentsColoursAndQuads) {
  TempDir tmp;
  write_bytes(tmp.file("q.off"),
              "COFF # coloured\n# counts next\n\n5 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n"
              "1 1 0 0 0 255 255\n0 1 0 9 9 9 9\n0.5 0.5 1 1 1 1 1\n4 0 1 2 3 0.1 0.2 0.3\n"
              "3 1 2 4\n");
  const Mesh r = read_mesh(tmp.file("q.off"));
  ASSERT_EQ(r.num_vertices(), 5u);
  EXPECT_EQ(r.triangles, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 1, 2, 4}));
  // Counts on the header line work too.
  write_bytes(tmp.file("h.off"), "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(read_mesh(tmp.file("h.off")).num_triangles(), 1u);
}

TEST(MeshIo, BadInputIsReportedWithThePath) {
  TempDir tmp;
  auto bad = [&](const std::string& name, const std::string& content, const std::string& needle) {
    const std::string path = tmp.file(name);
    write_bytes(path, content);
    expect_error([&] { read_mesh(path); }, Status::invalid_input, needle);
    expect_error([&] { read_mesh(path); }, Status::invalid_input, path + ": ");
  };
  const std::string ply_head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                               "property float y\nproperty float z\nelement face 1\n"
                               "property list uchar int vertex_indices\nend_header\n";
  bad("missing.ply", "", "");  // exists but empty: no header
  std::filesystem::remove(tmp.file("missing.ply"));
  expect_error([&] { read_mesh(tmp.file("missing.ply")); }, Status::invalid_input, "no such file");
  bad("notply.ply", "hello\n", "not a PLY file");
  bad("noend.ply", "ply\nformat ascii 1.0\nelement vertex 0\n", "end_header");
  bad("badfmt.ply", "ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown format");
  bad("badtype.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
      "unknown property type");
  bad("noxyz.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n",
      "lacks x, y or z");
  bad("short.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n", "truncated");           // face missing
  bad("fewer.ply", ply_head + "0 0 0\n1 0 0\n3 0 1 2\n", "element 'face' row 0");  // wrong count
  bad("range.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "out of range");
  bad("neg.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", "out of range");
  bad("two.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "at least 3");
  bad("nan.ply", ply_head + "0 nan 0\n1 0 0\n0 1 0\n3 0 1 2\n", "non-finite");
  bad("word.ply", ply_head + "0 zero 0\n1 0 0\n0 1 0\n3 0 1 2\n", "bad number 'zero'");
  // Absurd counts are refused before allocating anything.
  bad("absurd.ply",
      "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n0123456789ab",
      "absurd counts");
  // Binary truncated in the middle of the faces.
  {
    Mesh m = wavy_grid(4, false);
    write_mesh(m, tmp.file("full.ply"));
    const std::string full = read_bytes(tmp.file("full.ply"));
    bad("cut.ply", full.substr(0, full.size() - 7), "truncated data in element 'face' row 17");
  }
  // OBJ
  bad("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4: vertex index 4 out of range");
  bad("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "bad vertex index '0'");
  bad("negrange.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", "bad vertex index '-4'");
  bad("shortv.obj", "v 0 0\n", "line 1: expected 3 numbers");
  bad("twof.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "at least 3");
  bad("nrange.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n", "normal index 2");
  // OFF
  bad("magic.off", "FOO\n3 1 0\n", "not an OFF file");
  bad("counts.off", "OFF\n3 x 0\n", "expected 'NV NF NE'");
  bad("absurd.off", "OFF\n100000000 1 0\n0 0 0\n", "do not fit");
  bad("trunc.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n1 1 1\n# padding comment\n",
      "truncated: expected 1 faces");
  bad("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n", "line 6: vertex index 5 out of range");
  bad("fewidx.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "fewer indices");
  // STL
  bad("cut.stl", std::string(84, '\0').replace(80, 1, "\x02") + std::string(60, 'x'), "needs 184 bytes");
  bad("cutascii.stl", "solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0 0\n", "truncated");
  // Unsupported variants
  write_bytes(tmp.file("bin.off"), "OFF BINARY\n");
  expect_error([&] { read_mesh(tmp.file("bin.off")); }, Status::unsupported, "binary OFF");
  write_bytes(tmp.file("unknown.xyz"), "whatever\n");
  expect_error([&] { read_mesh(tmp.file("unknown.xyz")); }, Status::unsupported, "unknown mesh format");
}

TEST(MeshIo, FormatIsSniffedWithoutExtension) {
  TempDir tmp;
  const Mesh m = wavy_grid(3, false);
  write_mesh(m, tmp.file("a.ply"));
  std::filesystem::rename(tmp.file("a.ply"), tmp.file("a.mesh"));
  EXPECT_EQ(read_mesh(tmp.file("a.mesh")).triangles, m.triangles);
  MeshWriteOptions o;
  o.format = MeshFormat::off;
  write_mesh(m, tmp.file("b.data"), o);
  EXPECT_EQ(read_mesh(tmp.file("b.data")).triangles, m.triangles);
}

TEST(MeshIo, FailedWritesLeaveNoFile) {
  TempDir tmp;
  const Mesh m = wavy_grid(3);
  const std::string missing_dir = tmp.file("no/such/dir/out.ply");
  expect_error([&] { write_mesh(m, missing_dir); }, Status::output_failed, missing_dir + ": ");
  EXPECT_FALSE(std::filesystem::exists(tmp.file("no")));
  std::filesystem::create_directory(tmp.file("d.ply"));
  expect_error([&] { write_mesh(m, tmp.file("d.ply")); }, Status::output_failed, "is a directory");
  EXPECT_TRUE(std::filesystem::is_directory(tmp.file("d.ply")));
  EXPECT_EQ(files_in(tmp.path()), 1u);  // only the directory: no temporary left over
  // Unknown extension and invalid meshes are refused before any file is created.
  expect_error([&] { write_mesh(m, tmp.file("x.abc")); }, Status::unsupported, "unknown mesh format");
  Mesh broken = m;
  broken.triangles.back() = 99;
  expect_error([&] { write_mesh(broken, tmp.file("b.ply")); }, Status::output_failed,
               "refers to vertex 99");
  Mesh badattr = m;
  badattr.attributes[0].name = "nx";
  expect_error([&] { write_mesh(badattr, tmp.file("c.ply")); }, Status::output_failed, "collides");
  badattr.attributes[0].name = "a b";
  expect_error([&] { write_mesh(badattr, tmp.file("c.ply")); }, Status::output_failed, "white space");
  badattr = m;
  badattr.attributes[1].f32.pop_back();
  expect_error([&] { write_mesh(badattr, tmp.file("c.ply")); }, Status::output_failed, "values for");
  EXPECT_EQ(files_in(tmp.path()), 1u);
  // An existing file is replaced only by a complete new one.
  write_mesh(m, tmp.file("ok.obj"));
  expect_error([&] { write_mesh(broken, tmp.file("ok.obj")); }, Status::output_failed, "refers");
  EXPECT_EQ(read_mesh(tmp.file("ok.obj")).triangles, m.triangles);
}

TEST(MeshIo, LargeBinaryPlyIsFast) {
  // 1000×1000 grid: 2M triangles. Writes well under a second on the project's 2-core machine.
  TempDir tmp;
  const Mesh m = wavy_grid(1001, false);
  ASSERT_EQ(m.num_triangles(), 2'000'000u);
  const auto t0 = std::chrono::steady_clock::now();
  write_mesh(m, tmp.file("big.ply"));
  const auto t1 = std::chrono::steady_clock::now();
  const Mesh r = read_mesh(tmp.file("big.ply"));
  const auto t2 = std::chrono::steady_clock::now();
  const double w = std::chrono::duration<double>(t1 - t0).count();
  const double rd = std::chrono::duration<double>(t2 - t1).count();
  std::printf("2M-triangle binary PLY: write %.3f s, read %.3f s\n", w, rd);
  EXPECT_TRUE(same_bits(r.positions, m.positions));
  EXPECT_EQ(r.triangles, m.triangles);
  EXPECT_LT(w, 5.0);  // generous: shared CI machines; the expected time is ~0.1 s
}

TEST(MeshIo, DamagedFilesFailCleanly) {
  // Every truncation and random byte edits of small files in each format: read_mesh either
  // returns a mesh with valid indices or throws adamesh::Error; nothing else (run under ASan in
  // the debug preset).
  TempDir tmp;
  Mesh m = wavy_grid(3);
  std::mt19937 rng(5);
  for (const char* name : {"a.ply", "b.obj", "c.off", "d.stl"}) {
    MeshWriteOptions o;
    write_mesh(m, tmp.file(name), o);
    const std::string good = read_bytes(tmp.file(name));
    std::vector<std::string> variants;
    for (std::size_t n = 0; n < good.size(); ++n) variants.push_back(good.substr(0, n));
    for (int k = 0; k < 300; ++k) {
      std::string s = good;
      for (int e = 0; e < 1 + k % 4; ++e)
        s[rng() % s.size()] = static_cast<char>(k % 3 == 0 ? "0123456789 -\n"[rng() % 13] : rng() % 256);
      variants.push_back(s);
    }
    if (std::string(name) == "a.ply") {  // the ASCII variant too
      o.ascii = true;
      write_mesh(m, tmp.file("e.ply"), o);
      const std::string text = read_bytes(tmp.file("e.ply"));
      for (std::size_t n = 0; n < text.size(); n += 3) variants.push_back(text.substr(0, n));
    }
    const std::string path = tmp.file(std::string("x_") + name);
    for (const std::string& v : variants) {
      write_bytes(path, v);
      try {
        const Mesh r = read_mesh(path);
        for (auto i : r.triangles) ASSERT_LT(i, r.num_vertices()) << name;
        ASSERT_EQ(r.positions.size() % 3, 0u);
        for (float x : r.positions) ASSERT_TRUE(std::isfinite(x)) << name;
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      }
    }
  }
}
