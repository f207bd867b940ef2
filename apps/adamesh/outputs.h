// Checks every output a command will write before it computes anything, and the iso-value
// against the input's range (README.md, "Errors and output files"). Shared by the subcommands;
// no library logic lives here.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "adamesh/input.h"
#include "adamesh/io.h"
#include "adamesh/mesh.h"

namespace adamesh::cli {

class Args;

enum class OutputKind { mesh, hierarchy, report, page };

/// One output of a command: the option that names it ("-o", "--base", ...) and what it holds.
/// `may_stream`: the name "-" means standard output (the mesh -o of mc, extract and level).
struct OutputSpec {
  std::string option;
  OutputKind kind;
  bool may_stream = false;
};

/// The output name that means standard output.
inline bool is_stdout(const std::string& path) { return path == "-"; }

/// For each given option of `outputs`: the file name has a known extension (meshes: whatever
/// write_mesh() supports, else unsupported (3); hierarchies: .amh, else usage (1); pages: .html or
/// .htm, else unsupported (3)), no two options name the same file (usage), and the target can be
/// written (check_output_target: absent or a regular file, in an existing writable folder; else
/// output_failed (4), with "adamesh COMMAND: OPTION PATH: ..." messages). "-" is standard output
/// where the spec allows it (usage (1) elsewhere); it must be open for writing (else 4).
void check_outputs(const std::string& command, const Args& args,
                   const std::vector<OutputSpec>& outputs);

/// Mesh writing options for the output named by `option` ("-o", "--base"), from --ascii,
/// --compress and, for -o, --format; commands call it for every mesh output before any
/// computing, so a bad name fails at once. A file's format comes from its extension (--format,
/// when given, must agree: usage (1)); "-" (standard output) needs --format ply|obj|off|stl|glb
/// (usage (1) without it, unsupported (3) for gltf, which is two files) and refuses a terminal
/// for the binary formats (binary PLY, STL, GLB: output_failed (4)).
MeshWriteOptions mesh_output_options(const Args& args, const std::string& option);

/// write_mesh() for a file; for "-" the whole mesh is formatted in memory first and then written
/// to standard output, so an error found while formatting writes nothing there. A failing write
/// (closed pipe with SIGPIPE ignored, full disk) is output_failed (4).
void write_mesh_output(const Mesh& mesh, const std::string& path, const MeshWriteOptions& options);

/// Throws invalid_input (2) "<spec>: iso-value V is outside the value range [min, max]: the
/// surface would be empty" unless some finite sample lies on each side of iso (the same rule for
/// every command that extracts a surface).
void check_iso_in_range(const Input& in, double iso);

/// `message` on one line: control characters (including line breaks), DEL, C1 controls and bytes
/// that are not well-formed UTF-8 become \n, \t or \xNN, so a header's bytes cannot move the
/// cursor or inject lines into the terminal; UTF-8 text (file names, units) is kept.
std::string one_line(const std::string& message);

}  // namespace adamesh::cli
