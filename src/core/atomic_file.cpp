#include "adamesh/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "adamesh/error.h"

namespace adamesh {

namespace {

std::string temp_name_for(const std::string& path) {
  static std::atomic<unsigned> counter{0};
  return path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

[[noreturn]] void fail_output(const std::string& path, const std::string& what) {
  fail(Status::output_failed, path + ": " + what);
}

}  // namespace

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary) {
  namespace fs = std::filesystem;
  if (path.empty()) fail(Status::output_failed, "empty output path");
  std::error_code ec;
  if (fs::is_directory(path, ec)) fail_output(path, "is a directory");
  const fs::path parent = fs::path(path).parent_path();
  if (!parent.empty() && !fs::is_directory(parent, ec))
    fail_output(path, "directory " + parent.string() + " does not exist");

  const std::string tmp = temp_name_for(path);
  struct Cleanup {
    const std::string& name;
    bool armed = true;
    ~Cleanup() {
      if (armed) std::remove(name.c_str());
    }
  } cleanup{tmp};

  {
    std::ofstream out(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
    if (!out) fail_output(path, std::string("cannot create file: ") + std::strerror(errno));
    write(out);
    out.flush();
    if (!out) fail_output(path, "write failed (disk full or I/O error)");
    out.close();
    if (out.fail()) fail_output(path, "closing the file failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    fail_output(path, std::string("cannot rename temporary file: ") + std::strerror(errno));
  cleanup.armed = false;
}

}  // namespace adamesh
