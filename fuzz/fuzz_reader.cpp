// libFuzzer target for one adamesh reader (docs/FUZZING.md). Built once per format with
// FUZZ_EXT (the file extension that selects the reader) and FUZZ_KIND (0 volume, 1 mesh, 2 .amh,
// 3 DICOM series).
// The input bytes go to a file with that extension (the readers take paths) and are read; the
// only accepted failure is adamesh::Error — a crash, a sanitizer report, a hang or an allocation
// beyond libFuzzer's -malloc_limit_mb is a finding.
//
// The .amh target (FUZZ_KIND 2) re-seals its input before reading it: a .amh file ends with an
// FNV-1a checksum of everything before it and its size must match the header's counts, so
// nearly every raw mutation would stop at the size or checksum check. seal_amh() sets the split
// count to what the bytes hold, pads or trims to the announced size and rewrites the checksum,
// so the mutations reach the body, the validation and the replay. The raw bytes are also read
// with allow_partial (the `--partial` path, where a size mismatch skips the checksum). A custom
// mutator seals most mutants too, so the stored corpus holds consistent files.
//
// The DICOM target (FUZZ_KIND 3) splits its input at kSliceSeparator into slice files in a folder
// of its own and reads the folder as a series (read_volume(dir): GDCM's parser, the meta-header
// walk, geometry, decoding of every transfer syntax GDCM has), then the first slice by name (its
// series from the slice's folder). The seeds are small series of several syntaxes written by
// tests/dicom_test.cpp, their files joined with the separator.
#include <pthread.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <functional>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

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

bool write_scratch(const std::uint8_t* data, std::size_t size) {
  std::FILE* f = std::fopen(scratch_path().c_str(), "wb");
  if (!f) return false;
  if (size > 0) std::fwrite(data, 1, size, f);
  std::fclose(f);
  return true;
}

#if FUZZ_KIND == 2
// The .amh layout (src/refine/amh_io.cpp): a 104-byte header (magic, version, flags, counts
// V0 F0 S at offsets 16, 24, 32), V0 positions (24 bytes), V0 border flags (1), V0 anchors (4,
// when flags bit 0), F0 triangles (12), S splits (32), then the 8-byte checksum. Little-endian.
constexpr std::size_t kAmhHeader = 104, kAmhSplit = 32, kAmhFooter = 8;
constexpr std::size_t kAmhMaxGrowth = 4096;  // never pad a mutant by more than this

std::uint64_t load_u64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
std::uint32_t load_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}
void store_u64(std::uint8_t* p, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

/// Size of `bytes` once sealed (split count fitted to the bytes, footer appended), or 0 when the
/// header's base counts are out of range or would need more than kAmhMaxGrowth bytes of padding:
/// such inputs stay as they are and exercise the header checks.
std::size_t sealed_size(const std::uint8_t* data, std::size_t size) {
  if (size < kAmhHeader) return 0;
  const std::uint64_t v0 = load_u64(data + 16), f0 = load_u64(data + 24);
  if (v0 > 0xffffffffull || f0 > 0xffffffffull) return 0;
  const bool anchors = load_u32(data + 12) & 1u;
  const std::uint64_t fixed = kAmhHeader + v0 * (24 + 1 + (anchors ? 4 : 0)) + f0 * 12;
  if (fixed + kAmhFooter > size + kAmhMaxGrowth) return 0;
  const std::uint64_t splits = size >= fixed + kAmhFooter ? (size - fixed - kAmhFooter) / kAmhSplit : 0;
  return static_cast<std::size_t>(fixed + splits * kAmhSplit + kAmhFooter);
}

/// Seals `bytes` (of which the first `size` are the input) in place to `sealed` bytes: split
/// count, padding or trimming, FNV-1a checksum as write_hierarchy() computes it.
void seal(std::uint8_t* bytes, std::size_t size, std::size_t sealed) {
  if (sealed > size) std::memset(bytes + size, 0, sealed - size);
  const std::uint64_t v0 = load_u64(bytes + 16), f0 = load_u64(bytes + 24);
  const bool anchors = load_u32(bytes + 12) & 1u;
  const std::uint64_t fixed = kAmhHeader + v0 * (24 + 1 + (anchors ? 4 : 0)) + f0 * 12;
  store_u64(bytes + 32, (sealed - kAmhFooter - fixed) / kAmhSplit);
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i + kAmhFooter < sealed; ++i) {
    h ^= bytes[i];
    h *= 1099511628211ull;
  }
  store_u64(bytes + sealed - kAmhFooter, h);
}

void read_amh(bool allow_partial) {
  adamesh::HierarchyReadOptions options;
  options.allow_partial = allow_partial;
  try {
    const adamesh::Hierarchy h = adamesh::read_hierarchy(scratch_path(), options);
    (void)adamesh::extract_all(h);  // a validated hierarchy must replay
  } catch (const adamesh::Error&) {
  }
}
#endif

}  // namespace

#if FUZZ_KIND == 2
extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

// Mutate, then seal 7 mutants in 8 (the eighth stays raw: size and checksum errors, --partial).
extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size,
                                               std::size_t max_size, unsigned int seed) {
  size = LLVMFuzzerMutate(data, size, max_size);
  if (seed % 8 == 0) return size;
  const std::size_t sealed = sealed_size(data, size);
  if (sealed == 0 || sealed > max_size) return size;
  seal(data, size, sealed);
  return sealed;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::size_t sealed = sealed_size(data, size);
  std::vector<std::uint8_t> copy(data, data + size);
  if (sealed != 0) {
    copy.resize(std::max(size, sealed));
    seal(copy.data(), size, sealed);
    copy.resize(sealed);
  }
  if (!write_scratch(copy.data(), copy.size())) return 0;
  read_amh(false);  // the sealed file: body, validation, replay
  if (copy.size() != size || (size > 0 && std::memcmp(copy.data(), data, size) != 0)) {
    if (!write_scratch(data, size)) return 0;
    read_amh(true);  // the raw bytes as `level --partial` reads them
  }
  return 0;
}
#elif FUZZ_KIND == 3
namespace adamesh::detail {
std::uint64_t dicom_child_failures() noexcept;  // src/io/dicom.cpp (internal)
}  // namespace adamesh::detail

// Must match kFuzzSliceSeparator in tests/dicom_test.cpp (which writes the seeds).
constexpr char kSliceSeparator[] = "\n--adamesh-fuzz-next-slice--\n";

// The DICOM reader runs GDCM in a child process (src/io/dicom.cpp) and turns the child's death
// into an Error, so neither a crash of GDCM nor one of adamesh's own code in the child would
// stop the fuzzer. The child's stderr (the sanitizer report) goes to a log here: a report whose
// top frame is in GDCM or a codec library (or a GDCM assertion) is third-party — the input is
// kept in build/fuzz/third-party/dicom/ and fuzzing goes on; any other death of the child is a
// finding (trap, so libFuzzer saves the input), with the report copied to stderr.
extern "C" void __sanitizer_set_death_callback(void (*callback)(void));
extern "C" void __sanitizer_print_stack_trace();

// In the reader's child, libFuzzer's crash handlers and death callback would save the input as a
// finding of their own: a fatal signal instead prints the stack (for the triage) and kills the
// child with that signal, and a sanitizer report ends the child without libFuzzer's callback.
void child_fatal_signal(int sig) {
  __sanitizer_print_stack_trace();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}
void after_fork_in_child() {
  __sanitizer_set_death_callback(nullptr);
  for (const int sig : {SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL}) std::signal(sig, child_fatal_signal);
}

const std::string& child_log() {
  static const std::string path = [] {
    const std::string p = std::string(scratch_path()) + ".child-stderr";
    setenv("ADAMESH_DICOM_CHILD_STDERR", p.c_str(), 1);
    pthread_atfork(nullptr, nullptr, after_fork_in_child);
    return p;
  }();
  return path;
}

void triage_child_crash(const std::uint8_t* data, std::size_t size) {
  std::string log;
  if (std::FILE* f = std::fopen(child_log().c_str(), "rb")) {
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) log.append(buf, n);
    std::fclose(f);
  }
  // GDCM's own assertion (Debian keeps them): "...gdcm<File>.cxx:N: ... Assertion ... failed."
  bool third_party = false;
  for (std::size_t at = log.find("Assertion"); at != std::string::npos;
       at = log.find("Assertion", at + 1)) {
    const std::size_t line = log.rfind('\n', at) + 1;  // npos + 1 = 0 on the first line
    third_party |= log.substr(line, at - line).find("gdcm") != std::string::npos;
  }
  // Otherwise the first frame of the first stack that is not the sanitizer's, libFuzzer's or
  // libc's signal/abort machinery.
  if (!third_party) {
    for (std::size_t at = log.find("    #"); at != std::string::npos; at = log.find("    #", at + 1)) {
      const std::string frame = log.substr(at, log.find('\n', at) - at);
      bool runtime = false;
      for (const char* r : {"__sanitizer", "fuzzer::", "__asan", "__ubsan", "libc.so", "abort",
                            "raise", "__assert", "gsignal", "pthread_kill", "child_fatal_signal"})
        runtime |= frame.find(r) != std::string::npos;
      if (runtime) continue;
      for (const char* lib : {"libgdcm", "libopenjp2", "libCharLS", "libjpeg", "gdcm::"})
        third_party |= frame.find(lib) != std::string::npos;
      break;
    }
  }
  if (!third_party) {
    std::fprintf(stderr, "fuzz_dicom: the reader's child died outside GDCM; its stderr:\n%s\n",
                 log.c_str());
    __builtin_trap();
  }
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path keep = "build/fuzz/third-party/dicom";
  fs::create_directories(keep, ec);
  const std::size_t h = std::hash<std::string_view>{}(
      std::string_view(reinterpret_cast<const char*>(data), size));
  const std::string name = (keep / ("gdcm-" + std::to_string(h))).string();
  if (std::FILE* f = std::fopen(name.c_str(), "wb")) {
    std::fwrite(data, 1, size, f);
    std::fclose(f);
  }
  if (std::FILE* f = std::fopen((name + ".log").c_str(), "wb")) {
    std::fwrite(log.data(), 1, log.size(), f);
    std::fclose(f);
  }
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace fs = std::filesystem;
  static const fs::path dir = fs::path(scratch_path()).replace_extension(".dir");
  (void)child_log();  // sets ADAMESH_DICOM_CHILD_STDERR
  std::error_code ec;
  fs::remove_all(dir, ec);
  fs::create_directories(dir, ec);
  if (ec) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const std::string_view sep(kSliceSeparator, sizeof kSliceSeparator - 1);
  std::size_t start = 0;
  int n = 0;
  std::string first;
  while (n < 16) {  // at most 16 slices: a long input stays one big slice at the end
    const std::size_t end = bytes.find(sep, start);
    const std::string_view part = bytes.substr(start, end == bytes.npos ? bytes.npos : end - start);
    const std::string name = (dir / ("IM" + std::to_string(100 + n) + ".dcm")).string();
    if (std::FILE* f = std::fopen(name.c_str(), "wb")) {
      if (!part.empty()) std::fwrite(part.data(), 1, part.size(), f);
      std::fclose(f);
    }
    if (n == 0) first = name;
    ++n;
    if (end == bytes.npos) break;
    start = end + sep.size();
  }
  for (const std::string& path : {dir.string(), first}) {
    // Whether the reader's child died is counted by the reader: the message cannot tell (the
    // several-series message quotes descriptions, which the fuzzer filled with "ended without a
    // result" once).
    const std::uint64_t failures = adamesh::detail::dicom_child_failures();
    try {
      const adamesh::Volume v = adamesh::read_volume(path);
      if (v.grid.num_samples() > 0) (void)(v.at(0) + v.at(v.grid.num_samples() - 1));
    } catch (const adamesh::Error&) {
    }
    if (adamesh::detail::dicom_child_failures() != failures) triage_child_crash(data, size);
  }
  return 0;
}
#else
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string& path = scratch_path();
  if (!write_scratch(data, size)) return 0;
  try {
#if FUZZ_KIND == 0
    const adamesh::Volume v = adamesh::read_volume(path);
    // Touch the first and last samples: the buffer must hold what the grid announces.
    if (v.grid.num_samples() > 0) (void)(v.at(0) + v.at(v.grid.num_samples() - 1));
#elif FUZZ_KIND == 1
    const adamesh::Mesh m = adamesh::read_mesh(path);
    for (const std::uint32_t i : m.triangles)
      if (i >= m.num_vertices()) __builtin_trap();  // the reader must reject bad indices
#endif
  } catch (const adamesh::Error&) {
    // A clean, typed rejection: what a malformed input should get.
  }
  return 0;
}
#endif
