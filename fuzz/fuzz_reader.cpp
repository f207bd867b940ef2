// libFuzzer target for one adamesh reader (docs/FUZZING.md). Built once per format with
// FUZZ_EXT (the file extension that selects the reader) and FUZZ_KIND (0 volume, 1 mesh, 2 .amh).
// The input bytes go to a file with that extension (the readers take paths) and are read; the
// only accepted failure is adamesh::Error — a crash, a sanitizer report, a hang or an allocation
// beyond libFuzzer's -malloc_limit_mb is a finding.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "adamesh/error.h"
#include "adamesh/io.h"
#if FUZZ_KIND == 2
#include "adamesh/refine.h"
#endif

namespace {

const std::string& scratch_path() {
  static const std::string path = [] {
    const char* dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
    return std::string(dir) + "/adamesh-fuzz-" + std::to_string(getpid()) + FUZZ_EXT;
  }();
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = scratch_path();
  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    if (size > 0) std::fwrite(data, 1, size, f);
    std::fclose(f);
  } else {
    return 0;
  }
  try {
#if FUZZ_KIND == 0
    const adamesh::Volume v = adamesh::read_volume(path);
    // Touch the first and last samples: the buffer must hold what the grid announces.
    if (v.grid.num_samples() > 0) (void)(v.at(0) + v.at(v.grid.num_samples() - 1));
#elif FUZZ_KIND == 1
    const adamesh::Mesh m = adamesh::read_mesh(path);
    for (const std::uint32_t i : m.triangles)
      if (i >= m.num_vertices()) __builtin_trap();  // the reader must reject bad indices
#else
    const adamesh::Hierarchy h = adamesh::read_hierarchy(path);
    (void)adamesh::extract_all(h);  // a validated hierarchy must replay
#endif
  } catch (const adamesh::Error&) {
    // A clean, typed rejection: what a malformed input should get.
  }
  return 0;
}
