// write_mesh / read_mesh: format choice (extension, then magic bytes), the checks every writer
// relies on, whole-file reading with size checks, and the atomic write.
#include <bit>
#include <filesystem>
#include <fstream>
#include <set>

#include "adamesh/atomic_file.h"
#include "io/io_util.h"
#include "io/mesh_formats.h"

namespace adamesh {

namespace fmt = detail::meshfmt;

static_assert(std::endian::native == std::endian::little,
              "the binary mesh writers assume a little-endian host");

namespace {

MeshFormat format_from_extension(const std::string& path) {
  const std::string ext = detail::lower_extension(path);
  if (ext == ".ply") return MeshFormat::ply;
  if (ext == ".obj") return MeshFormat::obj;
  if (ext == ".off") return MeshFormat::off;
  if (ext == ".stl") return MeshFormat::stl;
  if (ext == ".glb") return MeshFormat::glb;
  if (ext == ".gltf") return MeshFormat::gltf;
  return MeshFormat::automatic;
}

[[noreturn]] void bad_output(const std::string& path, const std::string& what) {
  fail(Status::output_failed, path + ": " + what);
}

/// Everything the writers assume about the mesh; an inconsistent mesh is refused before any
/// file is created.
void check_mesh_for_writing(const Mesh& m, const std::string& path, const MeshWriteOptions& opt) {
  if (m.positions.size() % 3 != 0) bad_output(path, "invalid mesh: positions.size() is not a multiple of 3");
  if (m.triangles.size() % 3 != 0) bad_output(path, "invalid mesh: triangles.size() is not a multiple of 3");
  const std::size_t nv = m.num_vertices();
  if (nv > 0xffffffffu) bad_output(path, "invalid mesh: more than 2^32-1 vertices");
  for (std::size_t i = 0; i < m.triangles.size(); ++i)
    if (m.triangles[i] >= nv)
      bad_output(path, "invalid mesh: triangle " + std::to_string(i / 3) + " refers to vertex " +
                           std::to_string(m.triangles[i]) + " but the mesh has " +
                           std::to_string(nv) + " vertices");
  if (!m.normals.empty() && m.normals.size() != m.positions.size())
    bad_output(path, "invalid mesh: normals.size() != positions.size()");
  if (!opt.write_attributes) return;
  std::set<std::string> names = {"x", "y", "z", "nx", "ny", "nz"};
  for (const auto& a : m.attributes) {
    if (!a.f32.empty() && !a.i32.empty())
      bad_output(path, "invalid mesh: attribute '" + a.name + "' holds both float and int values");
    if (a.size() != nv)
      bad_output(path, "invalid mesh: attribute '" + a.name + "' has " + std::to_string(a.size()) +
                           " values for " + std::to_string(nv) + " vertices");
    if (a.name.empty()) bad_output(path, "invalid mesh: attribute with an empty name");
    for (char c : a.name)
      if (fmt::is_space(c) || static_cast<unsigned char>(c) < 32)
        bad_output(path, "invalid mesh: attribute name '" + a.name + "' contains white space");
    if (!names.insert(a.name).second)
      bad_output(path, "invalid mesh: attribute name '" + a.name +
                           "' repeats or collides with x/y/z/nx/ny/nz");
  }
}

/// Whole file into memory. Missing or unreadable files are invalid input.
std::string read_whole_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) fmt::bad_mesh(path, "no such file");
  if (fs::is_directory(path, ec)) fmt::bad_mesh(path, "is a directory");
  const auto size = fs::file_size(path, ec);
  if (ec) fmt::bad_mesh(path, "cannot read the file size: " + ec.message());
  std::ifstream in(path, std::ios::binary);
  if (!in) fmt::bad_mesh(path, "cannot open the file");
  std::string data;
  data.resize(static_cast<std::size_t>(size));
  in.read(data.data(), static_cast<std::streamsize>(size));
  if (static_cast<std::uintmax_t>(in.gcount()) != size) fmt::bad_mesh(path, "read error");
  return data;
}

/// Format from the first bytes, for files without a known extension.
MeshFormat sniff_format(std::string_view data) {
  if (data.substr(0, 3) == "ply") return MeshFormat::ply;
  std::string_view rest = data;
  const std::string_view first = fmt::next_token(rest);
  if (first.size() >= 3 && first.substr(first.size() - 3) == "OFF") return MeshFormat::off;
  if (first == "solid") return MeshFormat::stl;
  if (data.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, data.data() + 80, 4);
    if (84 + 50ull * n == data.size()) return MeshFormat::stl;
  }
  if (first == "v" || first == "#" || first == "o" || first == "g" || first == "mtllib" ||
      first == "vn" || first == "vt" || first == "f")
    return MeshFormat::obj;
  return MeshFormat::automatic;
}

}  // namespace

MeshFormat mesh_format_from_path(const std::string& path) { return format_from_extension(path); }

MeshFormat mesh_format_for_writing(const std::string& path, const MeshWriteOptions& options) {
  MeshFormat format = options.format;
  if (format == MeshFormat::automatic) format = format_from_extension(path);
  if (format == MeshFormat::automatic)
    fail(Status::unsupported, path +
                                  ": unknown mesh format (use the extension .ply, .obj, .off, "
                                  ".stl, .glb or .gltf)");
  if (options.compress && format != MeshFormat::glb && format != MeshFormat::gltf)
    fail(Status::unsupported, path + ": compression is for glTF only (use .glb or .gltf)");
  return format;
}

namespace {

/// The one-stream formats (not gltf, which is two files).
void write_single_stream(const Mesh& mesh, MeshFormat format, std::ostream& os,
                         const MeshWriteOptions& options) {
  switch (format) {
    case MeshFormat::ply: fmt::write_ply(mesh, os, options); break;
    case MeshFormat::obj: fmt::write_obj(mesh, os, options); break;
    case MeshFormat::off: fmt::write_off(mesh, os, options); break;
    case MeshFormat::stl: fmt::write_stl(mesh, os); break;
    case MeshFormat::glb: fmt::write_glb(mesh, os, options); break;
    case MeshFormat::gltf:
    case MeshFormat::automatic: break;
  }
}

}  // namespace

void write_mesh(const Mesh& mesh, const std::string& path, const MeshWriteOptions& options) {
  const MeshFormat format = mesh_format_for_writing(path, options);
  check_mesh_for_writing(mesh, path, options);
  if (format == MeshFormat::gltf) {
    fmt::write_gltf(mesh, path, options);
    return;
  }
  // Text formats are written in binary mode too: "\n" line ends on every platform.
  write_file_atomically(path,
                        [&](std::ostream& os) { write_single_stream(mesh, format, os, options); });
}

void write_mesh_to_stream(const Mesh& mesh, std::ostream& os, const MeshWriteOptions& options,
                          const std::string& name) {
  if (options.format == MeshFormat::automatic)
    fail(Status::usage, name + ": a stream has no extension: name the mesh format");
  if (options.format == MeshFormat::gltf)
    fail(Status::unsupported,
         name + ": glTF (.gltf) is two files; a stream takes GLB (one binary file)");
  (void)mesh_format_for_writing(name, options);  // --compress with a format that cannot hold it
  check_mesh_for_writing(mesh, name, options);
  write_single_stream(mesh, options.format, os, options);
  if (!os) bad_output(name, "write error");
}

Mesh read_mesh(const std::string& path) {
  const std::string data = read_whole_file(path);
  MeshFormat format = format_from_extension(path);
  if (format == MeshFormat::automatic) format = sniff_format(data);
  switch (format) {
    case MeshFormat::ply: return fmt::read_ply(path, data);
    case MeshFormat::obj: return fmt::read_obj(path, data);
    case MeshFormat::off: return fmt::read_off(path, data);
    case MeshFormat::stl: return fmt::read_stl(path, data);
    case MeshFormat::glb:
    case MeshFormat::gltf:
      fail(Status::unsupported, path + ": glTF meshes are written, not read (use PLY, OBJ, OFF or STL)");
    case MeshFormat::automatic: break;
  }
  fail(Status::unsupported, path + ": unknown mesh format (expected PLY, OBJ, OFF or STL)");
}

}  // namespace adamesh
