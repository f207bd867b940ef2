#include "outputs.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>

#include "adamesh/atomic_file.h"
#include "adamesh/error.h"
#include "adamesh/io.h"
#include "adamesh/stats.h"
#include "args.h"

namespace adamesh::cli {

namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace

void check_outputs(const std::string& command, const Args& args,
                   const std::vector<OutputSpec>& outputs) {
  std::vector<std::pair<std::string, std::string>> seen;  // (normalised path, option)
  for (const auto& o : outputs) {
    const auto path = args.get(o.option);
    if (!path) continue;
    const std::string where = "adamesh " + command + ": " + o.option + " " + *path;
    if (path->empty()) fail(Status::usage, "adamesh " + command + ": " + o.option + " needs a file name");
    if (is_stdout(*path)) {
      if (!o.may_stream)
        fail(Status::usage, where + ": standard output takes only the mesh of -o (mc, extract, "
                                    "level); name a file");
      const int flags = fcntl(STDOUT_FILENO, F_GETFL);
      if (flags == -1 || (flags & O_ACCMODE) == O_RDONLY)
        fail(Status::output_failed, where + ": standard output is not open for writing");
      continue;  // its format is checked by mesh_output_options (--format)
    }
    if (o.kind == OutputKind::page) {
      const std::string ext = lower_extension(*path);
      if (ext != ".html" && ext != ".htm")
        fail(Status::unsupported, where + ": adamesh view writes an HTML page (use the extension .html)");
    }
    if (o.kind == OutputKind::mesh) (void)mesh_format_for_writing(*path);  // unsupported (3)
    if (o.kind == OutputKind::hierarchy && lower_extension(*path) != ".amh")
      fail(Status::usage, where + ": a hierarchy file needs the extension .amh");
    const std::string key = std::filesystem::absolute(*path).lexically_normal().string();
    for (const auto& [other, option] : seen)
      if (other == key)
        fail(Status::usage, where + ": the same file is already given to " + option);
    seen.emplace_back(key, o.option);
    try {
      check_output_target(*path);
    } catch (const Error& e) {
      fail(e.status(), "adamesh " + command + ": " + o.option + " " + e.what());
    }
  }
}

namespace {

/// --format NAME: the formats a command can write to one file or stream.
MeshFormat parse_format(const Args& args, const std::string& name) {
  if (name == "ply") return MeshFormat::ply;
  if (name == "obj") return MeshFormat::obj;
  if (name == "off") return MeshFormat::off;
  if (name == "stl") return MeshFormat::stl;
  if (name == "glb") return MeshFormat::glb;
  if (name == "gltf") return MeshFormat::gltf;
  fail(Status::usage, "adamesh " + args.command() + ": --format must be ply, obj, off, stl or glb, got '" +
                          name + "'");
}

}  // namespace

MeshWriteOptions mesh_output_options(const Args& args, const std::string& option) {
  const std::string path = args.get(option).value();
  const std::string cmd = "adamesh " + args.command() + ": ";
  MeshWriteOptions wo;
  wo.ascii = args.has("--ascii");
  wo.compress = args.has("--compress");
  const std::optional<std::string> format = option == "-o" ? args.get("--format") : std::nullopt;
  if (format) wo.format = parse_format(args, *format);
  if (is_stdout(path)) {
    if (!format)
      fail(Status::usage, cmd + option + " - writes the mesh to standard output: name its format "
                                         "with --format ply|obj|off|stl|glb");
    if (wo.format == MeshFormat::gltf)
      fail(Status::unsupported, cmd + option + " -: glTF (.gltf) is two files; standard output "
                                               "takes --format glb");
    try {
      (void)mesh_format_for_writing("-", wo);  // --compress with a format that cannot hold it
    } catch (const Error& e) {
      fail(e.status(), cmd + option + " " + e.what());
    }
    const bool binary = (wo.format == MeshFormat::ply && !wo.ascii) ||
                        wo.format == MeshFormat::stl || wo.format == MeshFormat::glb;
    if (binary && isatty(STDOUT_FILENO))
      fail(Status::output_failed, cmd + option + " -: standard output is a terminal; redirect it "
                                                 "to a file or a pipe (binary " + *format + ")");
    return wo;
  }
  if (format && mesh_format_from_path(path) != wo.format)
    fail(Status::usage, cmd + "--format " + *format + " does not match " + option + " " + path +
                            " (a file's format comes from its extension; --format names the "
                            "format of -o -, standard output)");
  (void)mesh_format_for_writing(path, wo);
  return wo;
}

void write_mesh_output(const Mesh& mesh, const std::string& path, const MeshWriteOptions& options) {
  if (!is_stdout(path)) {
    write_mesh(mesh, path, options);
    return;
  }
  std::ostringstream buffer;
  write_mesh_to_stream(mesh, buffer, options, "standard output");
  const std::string bytes = std::move(buffer).str();
  std::cout.flush();
  std::fflush(stdout);
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(STDOUT_FILENO, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      fail(Status::output_failed, std::string("standard output: ") +
                                      (n < 0 ? std::strerror(errno) : "write returned 0") +
                                      " after " + std::to_string(done) + " of " +
                                      std::to_string(bytes.size()) + " bytes");
    done += static_cast<std::size_t>(n);
  }
}

void check_iso_in_range(const Input& in, double iso) {
  const VolumeStats st = compute_stats(*in.volume);
  // A surface needs samples on both sides: some ≤ iso < some, or some < iso ≤ some.
  if (!(iso > st.min && iso <= st.max) && !(iso >= st.min && iso < st.max)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "iso-value %g is outside the value range [%g, %g]", iso, st.min,
                  st.max);
    fail_input(in.spec, std::string(buf) + (st.finite == 0 ? " (no finite samples)" : "") +
                            ": the surface would be empty");
  }
}

namespace {

/// Length of the well-formed UTF-8 sequence at s[i] that is not a C1 control (U+0080..U+009F,
/// which 8-bit terminals take as escape sequences, e.g. 0x9b = CSI), or 0.
std::size_t printable_utf8(const std::string& s, std::size_t i) {
  const auto at = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = at(i);
  const std::size_t n = c >= 0xc2 && c <= 0xdf ? 2 : c >= 0xe0 && c <= 0xef ? 3 : c >= 0xf0 && c <= 0xf4 ? 4 : 0;
  if (n == 0 || i + n > s.size()) return 0;
  for (std::size_t k = 1; k < n; ++k)
    if (at(i + k) < 0x80 || at(i + k) > 0xbf) return 0;
  if (c == 0xc2 && at(i + 1) <= 0x9f) return 0;  // C1 control
  return n;
}

}  // namespace

std::string one_line(const std::string& message) {
  std::string out;
  out.reserve(message.size());
  for (std::size_t i = 0; i < message.size(); ++i) {
    const char ch = message[i];
    const auto c = static_cast<unsigned char>(ch);
    if (c >= 0x80) {  // UTF-8 text is kept; stray bytes and C1 controls are escaped
      if (const std::size_t n = printable_utf8(message, i)) {
        out.append(message, i, n);
        i += n - 1;
      } else {
        char hex[8];
        std::snprintf(hex, sizeof hex, "\\x%02x", c);
        out += hex;
      }
      continue;
    }
    if (c == '\n') out += "\\n";
    else if (c == '\t') out += "\\t";
    else if (c == '\r') out += "\\r";
    else if (c < 0x20 || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    } else {
      out += ch;
    }
  }
  return out;
}

}  // namespace adamesh::cli
