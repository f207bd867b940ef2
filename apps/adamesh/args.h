// Minimal command-line parsing for the adamesh subcommands: declared options, clear errors.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "adamesh/input.h"
#include "adamesh/io.h"

namespace adamesh::cli {

struct OptionSpec {
  std::string name;   ///< "--iso", "-o"
  bool takes_value;   ///< false: a flag
  std::string help;   ///< one line for --help
};

/// Parses argv against a list of option specs. Unknown options and missing values throw
/// Error(Status::usage, ...). Options may be given as `--name value` or `--name=value`.
class Args {
 public:
  Args(const std::string& command, const std::vector<std::string>& argv,
       const std::vector<OptionSpec>& specs);

  bool has(const std::string& name) const { return values_.count(name) != 0; }
  std::optional<std::string> get(const std::string& name) const;
  std::string get_or(const std::string& name, const std::string& fallback) const;
  std::optional<double> get_double(const std::string& name) const;
  std::optional<std::int64_t> get_int(const std::string& name) const;
  /// "a,b,c" with exactly n numbers.
  std::optional<std::vector<double>> get_doubles(const std::string& name, std::size_t n) const;

  const std::vector<std::string>& positionals() const { return positionals_; }
  /// Throws a usage error unless there are between min and max positional arguments.
  void expect_positionals(std::size_t min, std::size_t max, const std::string& what) const;
  bool help_requested() const { return help_; }
  std::string usage(const std::string& synopsis) const;
  const std::string& command() const { return command_; }

 private:
  std::string command_;
  std::vector<OptionSpec> specs_;
  std::map<std::string, std::string> values_;
  std::vector<std::string> positionals_;
  bool help_ = false;
};

/// Options shared by every command that reads an INPUT (raw, implicit, NaN handling, inside flip).
std::vector<OptionSpec> input_option_specs();
InputOptions input_options_from(const Args& args);

/// --compress (glTF/GLB: EXT_meshopt_compression), for the commands that write meshes.
OptionSpec compress_option_spec();

}  // namespace adamesh::cli
