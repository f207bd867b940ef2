// Checks every output a command will write before it computes anything, and the iso-value
// against the input's range (README.md, "Errors and output files"). Shared by the subcommands;
// no library logic lives here.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "adamesh/input.h"

namespace adamesh::cli {

class Args;

enum class OutputKind { mesh, hierarchy, report };

/// One output of a command: the option that names it ("-o", "--base", ...) and what it holds.
struct OutputSpec {
  std::string option;
  OutputKind kind;
};

/// For each given option of `outputs`: the file name has a known extension (meshes: whatever
/// write_mesh() supports, else unsupported (3); hierarchies: .amh, else usage (1)), no two options
/// name the same file (usage), and the target can be written (check_output_target: absent or a
/// regular file, in an existing writable folder; else output_failed (4), with
/// "adamesh COMMAND: OPTION PATH: ..." messages).
void check_outputs(const std::string& command, const Args& args,
                   const std::vector<OutputSpec>& outputs);

/// Throws invalid_input (2) "<spec>: iso-value V is outside the value range [min, max]: the
/// surface would be empty" unless some finite sample lies on each side of iso (the same rule for
/// every command that extracts a surface).
void check_iso_in_range(const Input& in, double iso);

/// `message` on one line: control characters (including line breaks) and DEL become \n, \t or
/// \xNN, so a header's bytes cannot move the cursor or inject lines into the terminal.
std::string one_line(const std::string& message);

}  // namespace adamesh::cli
