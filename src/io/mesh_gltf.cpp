// glTF 2.0 writer (Khronos glTF 2.0 specification): binary `.glb` (one file: JSON chunk + BIN
// chunk) or `.gltf` JSON with its buffer in a `.bin` file next to it. One mesh, one primitive
// (TRIANGLES): POSITION (float VEC3, with min/max), NORMAL (float VEC3, unit), uint32 indices.
// Coordinates are written as they are — the mesh's world frame and units, no axis change
// (docs/FORMATS.md, "glTF").
//
// Compression: EXT_meshopt_compression (KhronosGroup/glTF extensions/2.0/Vendor/
// EXT_meshopt_compression), as gltfpack writes it: the compressed streams live in buffer 0 (the
// GLB BIN chunk or the .bin file); every bufferView points into buffer 1, a fallback buffer with
// no data (`"fallback": true`), and carries the compressed location in its extension object.
// Vertex streams use meshopt's vertex codec (mode ATTRIBUTES, byte-exact), indices its index
// codec version 1 (mode TRIANGLES); the extension is listed in extensionsRequired because no
// uncompressed copy is stored. Decoded vertex data are the same bytes as without compression;
// the index codec may rotate the corners of a triangle (winding and triangle order kept).
#include <meshoptimizer.h>

#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>

#include "adamesh/atomic_file.h"
#include "io/mesh_formats.h"

namespace adamesh::detail::meshfmt {

namespace {

using nlohmann::json;

constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;
constexpr int kFloat = 5126;
constexpr int kUnsignedInt = 5125;
constexpr const char* kMeshopt = "EXT_meshopt_compression";

/// Unit vertex normals: the mesh's own, normalised, where they are usable; otherwise (no normals,
/// or a zero / non-finite one) the area-weighted sum of the vertex's face normals; (0, 0, 1) for
/// a vertex without a non-degenerate face (glTF requires unit normals on every vertex).
std::vector<float> unit_normals(const Mesh& m) {
  const std::size_t nv = m.num_vertices();
  std::vector<float> n(3 * nv, 0.0f);
  std::vector<char> ok(nv, 0);
  bool need_faces = false;
  for (std::size_t v = 0; v < nv; ++v) {
    if (m.normals.empty()) {
      need_faces = true;
      break;
    }
    const double x = m.normals[3 * v], y = m.normals[3 * v + 1], z = m.normals[3 * v + 2];
    const double len = std::sqrt(x * x + y * y + z * z);
    if (std::isfinite(len) && len > 1e-20) {
      n[3 * v] = static_cast<float>(x / len);
      n[3 * v + 1] = static_cast<float>(y / len);
      n[3 * v + 2] = static_cast<float>(z / len);
      ok[v] = 1;
    } else {
      need_faces = true;
    }
  }
  if (!need_faces) return n;
  std::vector<double> acc(3 * nv, 0.0);
  for (std::size_t t = 0; t < m.num_triangles(); ++t) {
    const std::uint32_t* tri = &m.triangles[3 * t];
    const Vec3 fn = cross(m.vertex(tri[1]) - m.vertex(tri[0]), m.vertex(tri[2]) - m.vertex(tri[0]));
    for (int k = 0; k < 3; ++k) {
      acc[3 * tri[k]] += fn.x;
      acc[3 * tri[k] + 1] += fn.y;
      acc[3 * tri[k] + 2] += fn.z;
    }
  }
  for (std::size_t v = 0; v < nv; ++v) {
    if (ok[v]) continue;
    const double x = acc[3 * v], y = acc[3 * v + 1], z = acc[3 * v + 2];
    const double len = std::sqrt(x * x + y * y + z * z);
    const bool usable = std::isfinite(len) && len > 0;
    n[3 * v] = usable ? static_cast<float>(x / len) : 0.0f;
    n[3 * v + 1] = usable ? static_cast<float>(y / len) : 0.0f;
    n[3 * v + 2] = usable ? static_cast<float>(z / len) : 1.0f;
  }
  return n;
}

void pad4(std::string& s, char fill) {
  while (s.size() % 4) s.push_back(fill);
}

void append(std::string& s, const void* p, std::size_t n) {
  s.append(static_cast<const char*>(p), n);
}

/// URI of a file name (RFC 3986: unreserved characters kept, the rest percent-encoded).
std::string uri_of(const std::string& name) {
  std::string out;
  char buf[4];
  for (unsigned char c : name) {
    if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') {
      out.push_back(static_cast<char>(c));
    } else {
      std::snprintf(buf, sizeof buf, "%%%02X", c);
      out += buf;
    }
  }
  return out;
}

/// The glTF JSON and its binary buffer. `bin_uri` empty: the buffer is the GLB BIN chunk.
struct GltfParts {
  std::string json;
  std::string bin;
};

GltfParts build_gltf(const Mesh& m, const MeshWriteOptions& opt, const std::string& bin_uri) {
  const std::size_t nv = m.num_vertices(), nt = m.num_triangles();
  json doc;
  doc["asset"] = {{"version", "2.0"}, {"generator", "adamesh"}};
  doc["scene"] = 0;
  GltfParts parts;
  if (nt == 0) {  // accessors need count >= 1: an empty scene
    doc["scenes"] = json::array({json::object()});
    parts.json = doc.dump();
    return parts;
  }
  const bool normals = opt.write_normals;
  const std::vector<float> nrm = normals ? unit_normals(m) : std::vector<float>();

  // Uncompressed layout: positions, normals, indices (all 4-byte aligned).
  struct View {
    const void* data;
    std::size_t bytes, stride, count;
    int target;
  };
  std::vector<View> views;
  views.push_back({m.positions.data(), 12 * nv, 12, nv, kArrayBuffer});
  if (normals) views.push_back({nrm.data(), 12 * nv, 12, nv, kArrayBuffer});
  views.push_back({m.triangles.data(), 4 * 3 * nt, 4, 3 * nt, kElementArrayBuffer});

  json buffer_views = json::array();
  std::size_t offset = 0;
  if (!opt.compress) {
    for (const View& v : views) {
      json bv = {
          {"buffer", 0}, {"byteOffset", offset}, {"byteLength", v.bytes}, {"target", v.target}};
      if (v.target == kArrayBuffer) bv["byteStride"] = v.stride;
      buffer_views.push_back(bv);
      append(parts.bin, v.data, v.bytes);
      offset += v.bytes;
    }
    json buf = {{"byteLength", parts.bin.size()}};
    if (!bin_uri.empty()) buf["uri"] = bin_uri;
    doc["buffers"] = json::array({buf});
  } else {
    meshopt_encodeVertexVersion(0);  // the versions EXT_meshopt_compression specifies
    meshopt_encodeIndexVersion(1);
    for (const View& v : views) {
      std::vector<unsigned char> enc;
      std::size_t size = 0;
      if (v.target == kArrayBuffer) {
        enc.resize(meshopt_encodeVertexBufferBound(v.count, v.stride));
        size = meshopt_encodeVertexBuffer(enc.data(), enc.size(), v.data, v.count, v.stride);
      } else {
        enc.resize(meshopt_encodeIndexBufferBound(v.count, nv));
        size = meshopt_encodeIndexBuffer(enc.data(), enc.size(),
                                         static_cast<const unsigned int*>(v.data), v.count);
      }
      if (size == 0) fail(Status::internal, "meshoptimizer could not encode a glTF buffer view");
      const std::size_t at = parts.bin.size();
      append(parts.bin, enc.data(), size);
      pad4(parts.bin, '\0');
      json ext = {
          {"buffer", 0},        {"byteOffset", at},
          {"byteLength", size}, {"byteStride", v.stride},
          {"count", v.count},   {"mode", v.target == kArrayBuffer ? "ATTRIBUTES" : "TRIANGLES"}};
      json bv = {{"buffer", 1},
                 {"byteOffset", offset},
                 {"byteLength", v.bytes},
                 {"target", v.target},
                 {"extensions", {{kMeshopt, ext}}}};
      if (v.target == kArrayBuffer) bv["byteStride"] = v.stride;
      buffer_views.push_back(bv);
      offset += v.bytes;
    }
    json buf = {{"byteLength", parts.bin.size()}};
    if (!bin_uri.empty()) buf["uri"] = bin_uri;
    json fallback = {{"byteLength", offset}, {"extensions", {{kMeshopt, {{"fallback", true}}}}}};
    doc["buffers"] = json::array({buf, fallback});
    doc["extensionsUsed"] = json::array({kMeshopt});
    doc["extensionsRequired"] = json::array({kMeshopt});
  }
  doc["bufferViews"] = buffer_views;

  // Bounds of the positions (the specification requires min/max on POSITION).
  std::array<float, 3> lo{}, hi{};
  lo.fill(std::numeric_limits<float>::infinity());
  hi.fill(-std::numeric_limits<float>::infinity());
  for (std::size_t v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], m.positions[3 * v + k]);
      hi[k] = std::max(hi[k], m.positions[3 * v + k]);
    }
  json accessors = json::array();
  accessors.push_back({{"bufferView", 0},
                       {"componentType", kFloat},
                       {"count", nv},
                       {"type", "VEC3"},
                       {"min", lo},
                       {"max", hi}});
  json attributes = {{"POSITION", 0}};
  if (normals) {
    accessors.push_back(
        {{"bufferView", 1}, {"componentType", kFloat}, {"count", nv}, {"type", "VEC3"}});
    attributes["NORMAL"] = 1;
  }
  accessors.push_back({{"bufferView", normals ? 2 : 1},
                       {"componentType", kUnsignedInt},
                       {"count", 3 * nt},
                       {"type", "SCALAR"}});
  doc["accessors"] = accessors;
  doc["meshes"] = json::array(
      {{{"primitives",
         json::array({{{"attributes", attributes}, {"indices", normals ? 2 : 1}, {"mode", 4}}})}}});
  doc["nodes"] = json::array({{{"mesh", 0}}});
  doc["scenes"] = json::array({{{"nodes", json::array({0})}}});
  parts.json = doc.dump();
  return parts;
}

}  // namespace

void write_glb(const Mesh& mesh, std::ostream& os, const MeshWriteOptions& options) {
  GltfParts parts = build_gltf(mesh, options, "");
  pad4(parts.json, ' ');
  pad4(parts.bin, '\0');
  const std::size_t total =
      12 + 8 + parts.json.size() + (parts.bin.empty() ? 0 : 8 + parts.bin.size());
  if (total > 0xffffffffu)
    fail(Status::unsupported, "mesh too large for a GLB file (4 GiB limit); write .gltf instead");
  OutBuffer out(os);
  out.binary<std::uint32_t>(0x46546C67u);  // "glTF"
  out.binary<std::uint32_t>(2);
  out.binary<std::uint32_t>(static_cast<std::uint32_t>(total));
  out.binary<std::uint32_t>(static_cast<std::uint32_t>(parts.json.size()));
  out.binary<std::uint32_t>(0x4E4F534Au);  // "JSON"
  out.text(parts.json);
  if (!parts.bin.empty()) {
    out.binary<std::uint32_t>(static_cast<std::uint32_t>(parts.bin.size()));
    out.binary<std::uint32_t>(0x004E4942u);  // "BIN\0"
    out.bytes(parts.bin.data(), parts.bin.size());
  }
  out.drain();
}

std::string gltf_bin_path(const std::string& path) {
  return std::filesystem::path(path).replace_extension(".bin").string();
}

void write_gltf(const Mesh& mesh, const std::string& path, const MeshWriteOptions& options) {
  const std::string bin_path = gltf_bin_path(path);
  const std::string bin_name = std::filesystem::path(bin_path).filename().string();
  const GltfParts parts = build_gltf(mesh, options, uri_of(bin_name));
  if (!parts.bin.empty())
    write_file_atomically(bin_path, [&](std::ostream& os) {
      os.write(parts.bin.data(), static_cast<std::streamsize>(parts.bin.size()));
    });
  try {
    write_file_atomically(path, [&](std::ostream& os) {
      os.write(parts.json.data(), static_cast<std::streamsize>(parts.json.size()));
    });
  } catch (...) {
    if (!parts.bin.empty()) std::remove(bin_path.c_str());  // no .bin without its .gltf
    throw;
  }
}

}  // namespace adamesh::detail::meshfmt
