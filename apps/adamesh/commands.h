// The adamesh subcommands. Each lives in its own cmd_<name>.cpp and returns the exit code;
// errors are thrown as adamesh::Error and turned into one line on stderr by main().
#pragma once

#include <string>
#include <vector>

namespace adamesh::cli {

using Argv = std::vector<std::string>;

struct Command {
  const char* name;
  const char* summary;
  int (*run)(const Argv& args);
};

int cmd_extract(const Argv& args);
int cmd_level(const Argv& args);
int cmd_mc(const Argv& args);
int cmd_stats(const Argv& args);
int cmd_info(const Argv& args);
int cmd_view(const Argv& args);
int cmd_version(const Argv& args);

/// All registered commands (main.cpp).
const std::vector<Command>& commands();

}  // namespace adamesh::cli
