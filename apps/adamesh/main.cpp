// adamesh command-line tool: a thin layer that parses options and calls the library.
#include <cstdio>
#include <exception>
#include <iostream>
#include <new>

#include "adamesh/error.h"
#include "commands.h"
#include "outputs.h"

namespace adamesh::cli {

const std::vector<Command>& commands() {
  static const std::vector<Command> table = {
      {"info", "describe an input: grid, value statistics, suggested iso-value", cmd_info},
      {"extract", "extract the base mesh (and refined meshes) of an iso-surface", cmd_extract},
      {"level", "cut a mesh from a refinement hierarchy (.amh) without the volume", cmd_level},
      {"mc", "marching cubes mesh of an iso-surface (reference, manifold)", cmd_mc},
      {"stats", "topology, quality and error report of a mesh", cmd_stats},
      {"view", "self-contained HTML viewer of a hierarchy (.amh) or mesh, with a level slider", cmd_view},
      {"version", "print the version", cmd_version},
  };
  return table;
}

int cmd_version(const Argv&) {
  std::cout << "adamesh " << ADAMESH_VERSION << "\n";
  return 0;
}

namespace {

void print_help() {
  std::cout << "adamesh — adaptive multiresolution iso-surface meshes\n\n"
               "usage: adamesh COMMAND [options]   (adamesh COMMAND --help for details)\n\n"
               "commands:\n";
  for (const auto& c : commands()) {
    std::string name = c.name;
    name.resize(10, ' ');
    std::cout << "  " << name << c.summary << "\n";
  }
  std::cout << "\ninputs: a volume file (.nrrd .nhdr .mhd .mha .nii .nii.gz .vtk .vti .slc .mrc "
               ".map .raw), a DICOM series directory, shape:NAME or expr:'EXPR'\n";
}

}  // namespace
}  // namespace adamesh::cli

int main(int argc, char** argv) {
  using namespace adamesh;
  using namespace adamesh::cli;
  std::ios::sync_with_stdio(false);
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    print_help();
    return argc < 2 ? 1 : 0;
  }
  if (std::string(argv[1]) == "--version") return cmd_version({});
  const std::string name = argv[1];
  Argv rest(argv + 2, argv + argc);
  for (const auto& c : commands()) {
    if (name != c.name) continue;
    try {
      return c.run(rest);
    } catch (const Error& e) {
      std::cout.flush();
      // One line, control bytes escaped; messages that already start with "adamesh CMD:" keep
      // that prefix alone (no "adamesh: adamesh mc: ...").
      const std::string what = e.what();
      const bool prefixed = what.rfind("adamesh ", 0) == 0;
      std::cerr << (prefixed ? "" : "adamesh: ") << one_line(what) << "\n";
      return static_cast<int>(e.status());
    } catch (const std::bad_alloc&) {
      std::cout.flush();
      std::cerr << "adamesh: out of memory\n";
      return static_cast<int>(Status::internal);
    } catch (const std::exception& e) {
      std::cout.flush();
      std::cerr << "adamesh: internal error: " << one_line(e.what()) << "\n";
      return static_cast<int>(Status::internal);
    }
  }
  std::cerr << "adamesh: unknown command '" << name << "' (see adamesh --help)\n";
  return static_cast<int>(Status::usage);
}
