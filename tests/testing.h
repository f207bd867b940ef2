// Helpers shared by the tests: where the data is, running the CLI, temporary directories.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace adamesh::testutil {

/// ../shared/data next to the repository, or "" when it is absent.
inline std::string shared_data_dir() {
  std::error_code ec;
  const std::filesystem::path p = ADAMESH_SHARED_DATA_DIR;
  if (std::filesystem::is_regular_file(p / "manifest.json", ec)) return p.string();
  return {};
}

#define ADAMESH_REQUIRE_SHARED_DATA(dir)                                                      \
  const std::string dir = ::adamesh::testutil::shared_data_dir();                             \
  if (dir.empty()) GTEST_SKIP() << "../shared/data is absent (" ADAMESH_SHARED_DATA_DIR      \
                                   "): test needs the shared datasets"

inline std::string source_dir() { return ADAMESH_SOURCE_DIR; }

/// A fresh temporary directory removed at destruction.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "adamesh-test-XXXXXX").string();
    if (!mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

struct CliResult {
  int exit_code = -1;
  std::string out;  ///< stdout
  std::string err;  ///< stderr
};

/// Runs `adamesh ARGS` through the shell (ARGS is shell syntax) and captures both streams.
inline CliResult run_cli(const std::string& args) {
  TempDir tmp;
  const std::string out = tmp.file("out"), err = tmp.file("err");
  const std::string cmd =
      std::string("'") + ADAMESH_CLI + "' " + args + " >'" + out + "' 2>'" + err + "'";
  const int status = std::system(cmd.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  auto slurp = [](const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

inline void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream o(path, std::ios::binary);
  o << bytes;
}

inline std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace adamesh::testutil
