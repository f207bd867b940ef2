// glTF 2.0 / GLB writer: the file structure is parsed back (GLB header and chunks, JSON
// accessors and buffer views) and the binary data compared with the mesh; EXT_meshopt_compression
// streams are decoded with meshoptimizer's decoders and must give the uncompressed bytes. The CLI
// refuses unknown output extensions before reading the input. The Khronos validator runs on CLI
// outputs in the ctest `gltf_validator` (tests/CMakeLists.txt).
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "adamesh/error.h"
#include "adamesh/io.h"
#include "testing.h"

using namespace adamesh;
using adamesh::testutil::read_bytes;
using adamesh::testutil::run_cli;
using adamesh::testutil::TempDir;
using nlohmann::json;

namespace {

/// A closed octahedron scaled and moved off the origin, without normals.
Mesh octahedron() {
  Mesh m;
  const double c[3] = {10.5, -3.25, 7.0};
  for (int a = 0; a < 3; ++a)
    for (int s : {1, -1}) {
      double p[3] = {c[0], c[1], c[2]};
      p[a] += s * (1.0 + 0.5 * a);
      m.add_vertex({p[0], p[1], p[2]});
    }
  // Vertices: 0 +x, 1 -x, 2 +y, 3 -y, 4 +z, 5 -z; counter-clockwise from outside.
  const std::uint32_t f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                 {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (auto& t : f) m.add_triangle(t[0], t[1], t[2]);
  return m;
}

/// A wavy grid with normals of varying length (the writer must normalise them).
Mesh grid(int n) {
  Mesh m;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.add_vertex({i / 3.0, j / 7.0, 0.1 * std::sin(i * 0.9) * std::cos(j * 1.3)});
      m.normals.insert(m.normals.end(), {0.0f, 0.5f * (1 + i), 2.0f});
    }
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const auto v = static_cast<std::uint32_t>(j * n + i), nn = static_cast<std::uint32_t>(n);
      m.add_triangle(v, v + 1, v + nn + 1);
      m.add_triangle(v, v + nn + 1, v + nn);
    }
  return m;
}

std::uint32_t u32(const std::string& s, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, s.data() + at, 4);
  return v;
}

struct Parsed {
  json doc;
  std::string bin;  // buffer 0
};

Parsed parse_glb(const std::string& bytes) {
  Parsed p;
  EXPECT_GE(bytes.size(), 20u);
  EXPECT_EQ(u32(bytes, 0), 0x46546C67u);
  EXPECT_EQ(u32(bytes, 4), 2u);
  EXPECT_EQ(u32(bytes, 8), bytes.size());
  const std::uint32_t jlen = u32(bytes, 12);
  EXPECT_EQ(u32(bytes, 16), 0x4E4F534Au);
  EXPECT_EQ(jlen % 4, 0u);
  p.doc = json::parse(bytes.substr(20, jlen));
  const std::size_t at = 20 + jlen;
  if (at < bytes.size()) {
    const std::uint32_t blen = u32(bytes, at);
    EXPECT_EQ(u32(bytes, at + 4), 0x004E4942u);
    EXPECT_EQ(blen % 4, 0u);
    EXPECT_EQ(at + 8 + blen, bytes.size());
    p.bin = bytes.substr(at + 8, blen);
  }
  return p;
}

/// The bytes of buffer view `i`, decoded when it is meshopt-compressed.
std::string view_bytes(const Parsed& p, int i) {
  const json& bv = p.doc["bufferViews"][i];
  if (bv.contains("extensions")) {
    const json& e = bv["extensions"]["EXT_meshopt_compression"];
    EXPECT_EQ(e["buffer"].get<int>(), 0);
    const std::size_t count = e["count"], stride = e["byteStride"];
    const std::string src =
        p.bin.substr(e["byteOffset"].get<std::size_t>(), e["byteLength"].get<std::size_t>());
    std::string out(count * stride, '\0');
    const auto* in = reinterpret_cast<const unsigned char*>(src.data());
    int rc = -1;
    if (e["mode"] == "ATTRIBUTES")
      rc = meshopt_decodeVertexBuffer(out.data(), count, stride, in, src.size());
    else if (e["mode"] == "TRIANGLES")
      rc = meshopt_decodeIndexBuffer(out.data(), count, stride, in, src.size());
    EXPECT_EQ(rc, 0) << "meshopt decoding of view " << i;
    EXPECT_EQ(out.size(), bv["byteLength"].get<std::size_t>());
    return out;
  }
  return p.bin.substr(bv["byteOffset"].get<std::size_t>(), bv["byteLength"].get<std::size_t>());
}

/// Checks the document against the mesh: accessors, bounds, positions, indices, unit normals.
void check_against(const Parsed& p, const Mesh& m, bool compressed) {
  const json& d = p.doc;
  EXPECT_EQ(d["asset"]["version"], "2.0");
  const json& prim = d["meshes"][0]["primitives"][0];
  EXPECT_EQ(prim["mode"], 4);
  const json& pos = d["accessors"][prim["attributes"]["POSITION"].get<int>()];
  const json& nrm = d["accessors"][prim["attributes"]["NORMAL"].get<int>()];
  const json& idx = d["accessors"][prim["indices"].get<int>()];
  EXPECT_EQ(pos["count"], m.num_vertices());
  EXPECT_EQ(pos["componentType"], 5126);
  EXPECT_EQ(pos["type"], "VEC3");
  EXPECT_EQ(nrm["count"], m.num_vertices());
  EXPECT_EQ(idx["count"], m.triangles.size());
  EXPECT_EQ(idx["componentType"], 5125);
  const Box b = m.bounds();
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(pos["min"][k].get<float>(), static_cast<float>(b.lo[k]));
    EXPECT_EQ(pos["max"][k].get<float>(), static_cast<float>(b.hi[k]));
  }
  const std::string pb = view_bytes(p, pos["bufferView"]);
  ASSERT_EQ(pb.size(), 4 * m.positions.size());
  EXPECT_EQ(std::memcmp(pb.data(), m.positions.data(), pb.size()), 0) << "positions differ";
  const std::string ib = view_bytes(p, idx["bufferView"]);
  ASSERT_EQ(ib.size(), 4 * m.triangles.size());
  std::vector<std::uint32_t> tri(m.triangles.size());
  std::memcpy(tri.data(), ib.data(), ib.size());
  if (compressed) {
    // meshopt's index codec may rotate a triangle's corners (winding kept): compare each
    // triangle from its smallest index on.
    auto canon = [](std::vector<std::uint32_t>& t) {
      for (std::size_t i = 0; i < t.size(); i += 3)
        while (t[i] > t[i + 1] || t[i] > t[i + 2]) std::rotate(&t[i], &t[i + 1], &t[i + 3]);
    };
    std::vector<std::uint32_t> want = m.triangles;
    canon(want);
    canon(tri);
    EXPECT_EQ(tri, want) << "triangles differ";
  } else {
    EXPECT_EQ(tri, m.triangles) << "indices differ";
  }
  const std::string nb = view_bytes(p, nrm["bufferView"]);
  ASSERT_EQ(nb.size(), 4 * m.positions.size());
  std::vector<float> n(m.positions.size());
  std::memcpy(n.data(), nb.data(), nb.size());
  for (std::size_t v = 0; v < m.num_vertices(); ++v) {
    const double len =
        std::sqrt(n[3 * v] * n[3 * v] + n[3 * v + 1] * n[3 * v + 1] + n[3 * v + 2] * n[3 * v + 2]);
    EXPECT_NEAR(len, 1.0, 1e-6) << "vertex " << v;
    if (!m.normals.empty()) {  // same direction as the mesh's normal
      const double dot = (n[3 * v] * m.normals[3 * v] + n[3 * v + 1] * m.normals[3 * v + 1] +
                          n[3 * v + 2] * m.normals[3 * v + 2]);
      const double ml = std::sqrt(m.normals[3 * v] * m.normals[3 * v] +
                                  m.normals[3 * v + 1] * m.normals[3 * v + 1] +
                                  m.normals[3 * v + 2] * m.normals[3 * v + 2]);
      EXPECT_NEAR(dot / ml, 1.0, 1e-6);
    }
  }
  const bool has_ext = d.contains("extensionsRequired");
  EXPECT_EQ(has_ext, compressed);
  if (compressed) {
    EXPECT_EQ(d["extensionsRequired"][0], "EXT_meshopt_compression");
    EXPECT_EQ(d["extensionsUsed"][0], "EXT_meshopt_compression");
    ASSERT_EQ(d["buffers"].size(), 2u);
    EXPECT_TRUE(d["buffers"][1]["extensions"]["EXT_meshopt_compression"]["fallback"].get<bool>());
    EXPECT_FALSE(d["buffers"][1].contains("uri"));
    for (const json& bv : d["bufferViews"]) {
      EXPECT_EQ(bv["buffer"], 1);
      EXPECT_EQ(bv["extensions"]["EXT_meshopt_compression"]["byteOffset"].get<std::size_t>() % 4,
                0u);
    }
  }
}

}  // namespace

TEST(Gltf, GlbRoundTripsPositionsIndicesAndUnitNormals) {
  TempDir tmp;
  for (const Mesh& m : {octahedron(), grid(9)}) {
    write_mesh(m, tmp.file("m.glb"));
    const Parsed p = parse_glb(read_bytes(tmp.file("m.glb")));
    check_against(p, m, false);
    EXPECT_EQ(p.doc["buffers"][0]["byteLength"].get<std::size_t>(), p.bin.size());
    EXPECT_FALSE(p.doc["buffers"][0].contains("uri"));
  }
}

TEST(Gltf, FaceNormalsWhenTheMeshHasNone) {
  TempDir tmp;
  const Mesh m = octahedron();  // vertex 0 is +x: its normal is +x by symmetry of its faces
  write_mesh(m, tmp.file("o.glb"));
  const Parsed p = parse_glb(read_bytes(tmp.file("o.glb")));
  const std::string nb = view_bytes(p, 1);
  float n0[3];
  std::memcpy(n0, nb.data(), 12);
  EXPECT_GT(n0[0], 0.9f);  // the scaled octahedron's faces tilt it a little, not its sign
}

TEST(Gltf, MeshoptCompressionDecodesToTheSameBytes) {
  TempDir tmp;
  const Mesh m = grid(40);
  MeshWriteOptions wo;
  wo.compress = true;
  write_mesh(m, tmp.file("c.glb"), wo);
  write_mesh(m, tmp.file("u.glb"));
  const std::string c = read_bytes(tmp.file("c.glb"));
  check_against(parse_glb(c), m, true);
  EXPECT_LT(c.size(), read_bytes(tmp.file("u.glb")).size() * 3 / 4)
      << "compression did not compress";
}

TEST(Gltf, GltfWritesItsBinNextToIt) {
  TempDir tmp;
  const Mesh m = grid(5);
  for (bool compress : {false, true}) {
    MeshWriteOptions wo;
    wo.compress = compress;
    write_mesh(m, tmp.file("my mesh.gltf"), wo);
    Parsed p;
    p.doc = json::parse(read_bytes(tmp.file("my mesh.gltf")));
    EXPECT_EQ(p.doc["buffers"][0]["uri"], "my%20mesh.bin");
    p.bin = read_bytes(tmp.file("my mesh.bin"));
    EXPECT_EQ(p.doc["buffers"][0]["byteLength"].get<std::size_t>(), p.bin.size());
    check_against(p, m, compress);
  }
}

TEST(Gltf, EmptyMeshIsAnEmptyScene) {
  TempDir tmp;
  write_mesh(Mesh{}, tmp.file("e.glb"));
  const Parsed p = parse_glb(read_bytes(tmp.file("e.glb")));
  EXPECT_FALSE(p.doc.contains("meshes"));
  EXPECT_TRUE(p.bin.empty());
}

TEST(Gltf, FormatIsCheckedUpFront) {
  EXPECT_EQ(mesh_format_for_writing("a/b.GLB"), MeshFormat::glb);
  EXPECT_EQ(mesh_format_for_writing("b.gltf"), MeshFormat::gltf);
  MeshWriteOptions wo;
  wo.compress = true;
  try {
    mesh_format_for_writing("x.ply", wo);
    ADD_FAILURE() << "compression accepted for PLY";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::unsupported);
  }
  try {
    mesh_format_for_writing("x.vrml");
    ADD_FAILURE() << "unknown extension accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.status(), Status::unsupported);
    EXPECT_NE(std::string(e.what()).find("x.vrml: unknown mesh format"), std::string::npos);
  }
}

TEST(GltfCli, UnknownExtensionFailsBeforeReadingTheInput) {
  TempDir tmp;
  // The input does not exist: a command that reads before checking its outputs would say so.
  for (const std::string cmd :
       {"extract missing.nrrd --iso 1 -o " + tmp.file("x.vrml"),
        "extract missing.nrrd --iso 1 --base " + tmp.file("b.xyz") + " -o " + tmp.file("x.ply"),
        "mc missing.nrrd --iso 1 -o " + tmp.file("x.wrl"),
        "level missing.amh --all -o " + tmp.file("x.3ds"),
        "mc missing.nrrd --iso 1 --compress -o " + tmp.file("x.ply")}) {
    const auto r = run_cli(cmd);
    EXPECT_EQ(r.exit_code, 3) << cmd << "\n" << r.err;
    EXPECT_EQ(r.err.find("missing"), std::string::npos) << cmd << ": " << r.err;
    EXPECT_TRUE(std::filesystem::is_empty(tmp.path())) << cmd;
  }
}

TEST(GltfCli, ExtractAndLevelWriteGlb) {
  TempDir tmp;
  const std::string head = testutil::source_dir() + "/data/ct_headsq/quarter.nhdr";
  const std::string extract = "extract '" + head + "' --iso 500.5 --quiet --triangles 3000 ";
  auto r = run_cli(extract + "-o " + tmp.file("h.glb") + " --hierarchy " + tmp.file("h.amh"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli(extract + "-o " + tmp.file("h.ply"));  // deterministic: the same mesh
  ASSERT_EQ(r.exit_code, 0) << r.err;
  check_against(parse_glb(read_bytes(tmp.file("h.glb"))), read_mesh(tmp.file("h.ply")), false);
  r = run_cli("level " + tmp.file("h.amh") + " --all --quiet -o " + tmp.file("l.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Mesh ref = read_mesh(tmp.file("l.ply"));
  r = run_cli("level " + tmp.file("h.amh") + " --all --quiet --compress -o " + tmp.file("c.glb"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  check_against(parse_glb(read_bytes(tmp.file("c.glb"))), ref, true);
}
