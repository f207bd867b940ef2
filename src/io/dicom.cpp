// DICOM series (PS3.3 C.7.6.2 Image Plane module) read with GDCM: the headers of every file are
// scanned (gdcm::Scanner), the files of one SeriesInstanceUID are sorted by the position of
// ImagePositionPatient along the slice normal (row × column of ImageOrientationPatient), the slice
// spacing comes from those positions (not SliceThickness), and the pixels of each slice are
// decoded by gdcm::ImageReader (any transfer syntax GDCM supports) and rescaled with the slice's
// RescaleSlope / RescaleIntercept. The world frame is DICOM's patient frame (LPS, millimetres):
// direction = [row cosines, column cosines, normal], origin = the first slice's position
// (docs/FORMATS.md, "DICOM"). GDCM headers stay in this file.
#include <gdcmAttribute.h>
#include <gdcmDirectory.h>
#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmScanner.h>
#include <gdcmTag.h>
#include <gdcmTrace.h>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <new>
#include <sstream>
#include <type_traits>
#include <utility>
#include <vector>

#include "adamesh/error.h"
#include "io/volume_readers.h"

namespace adamesh::detail {

namespace {

namespace fs = std::filesystem;

const gdcm::Tag kSeriesUid(0x0020, 0x000e);
const gdcm::Tag kSeriesDescription(0x0008, 0x103e);
const gdcm::Tag kModality(0x0008, 0x0060);
const gdcm::Tag kPosition(0x0020, 0x0032);
const gdcm::Tag kOrientation(0x0020, 0x0037);
const gdcm::Tag kPixelSpacing(0x0028, 0x0030);
const gdcm::Tag kRows(0x0028, 0x0010);
const gdcm::Tag kColumns(0x0028, 0x0011);
const gdcm::Tag kFrames(0x0028, 0x0008);

std::string trimmed(const char* s) {
  std::string v = s ? s : "";
  while (!v.empty() && (v.back() == ' ' || v.back() == '\0')) v.pop_back();
  while (!v.empty() && v.front() == ' ') v.erase(v.begin());
  return v;
}

/// Backslash-separated decimal string (DS) values; empty when any is not a number.
std::vector<double> numbers(const std::string& s) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, '\\')) {
    char* end = nullptr;
    const std::string t = trimmed(item.c_str());
    const double v = std::strtod(t.c_str(), &end);
    if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(v)) return {};
    out.push_back(v);
  }
  return out;
}

struct Slice {
  std::string file;
  Vec3 position;
  double along = 0;  // position · normal
};

bool has_dicom_magic(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  char magic[4] = {};
  const bool ok = std::fseek(f, 128, SEEK_SET) == 0 && std::fread(magic, 1, 4, f) == 4;
  std::fclose(f);
  return ok && std::memcmp(magic, "DICM", 4) == 0;
}

/// Walks a DICOM file's element structure (PS3.5 §7) without keeping any value, to decide
/// whether GDCM may be given the file: GDCM allocates every value at the length the file declares
/// before reading it (gdcm::ByteValue::SetLength), so one corrupt length asks for gigabytes
/// (fuzz_dicom's first finding: 2.6 GB for a 9 KB file), and Debian's GDCM keeps its assertions,
/// which abort the process on a meta header cut short (gdcmReader.cxx:385) or an element running
/// past the end of the file (gdcmFileMetaInformation.cxx:436; found by the volume fuzzers, which
/// reach this reader through the DICM magic).
class StructureWalk {
 public:
  explicit StructureWalk(std::FILE* f) : f_(f) {
    std::fseek(f_, 0, SEEK_END);
    const long size = std::ftell(f_);
    size_ = size > 0 ? static_cast<std::uint64_t>(size) : 0;
  }

  /// "" when every element, item and fragment lies inside the file and inside what encloses it.
  std::string check(bool preamble) {
    std::uint64_t pos = 0;
    if (preamble) {
      pos = 132;  // preamble + "DICM"
      if (std::string p = meta_group(pos); !p.empty()) return p;
    } else {
      // No preamble (a bare data set, as GDCM also reads): explicit VR when bytes 4–5 look like
      // a VR, implicit VR little endian otherwise.
      unsigned char b[6];
      explicit_vr_ = read_at(0, b, 6) && is_vr(b + 4);
    }
    if (deflated_) return "";  // the deflated data set is GDCM's to inflate (not walked)
    return elements(pos, size_, explicit_vr_, 0);
  }

 private:
  static constexpr std::uint32_t kUndefined = 0xffffffffu;
  static constexpr int kMaxDepth = 32;  // nested sequences

  bool read_at(std::uint64_t pos, unsigned char* b, std::size_t n) {
    return pos + n <= size_ && std::fseek(f_, static_cast<long>(pos), SEEK_SET) == 0 &&
           std::fread(b, 1, n, f_) == n;
  }
  unsigned u16(const unsigned char* b) const {
    return big_endian_ ? (b[0] << 8u | b[1]) : (b[0] | b[1] << 8u);
  }
  std::uint32_t u32(const unsigned char* b) const {
    const std::uint32_t le = static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
                             static_cast<std::uint32_t>(b[2]) << 16 |
                             static_cast<std::uint32_t>(b[3]) << 24;
    return big_endian_ ? __builtin_bswap32(le) : le;
  }
  static bool is_vr(const unsigned char* v) {
    return v[0] >= 'A' && v[0] <= 'Z' && v[1] >= 'A' && v[1] <= 'Z';
  }
  /// One of PS3.5's value representations. GDCM reads any other two letters with a 4-byte
  /// length (fuzz_dicom: "CS" turned into "MS" made it allocate 1.3 GB for a 2 KB file).
  static bool known_vr(const unsigned char* v) {
    static const char* const kAll[] = {"AE", "AS", "AT", "CS", "DA", "DS", "DT", "FD", "FL", "IS",
                                       "LO", "LT", "OB", "OD", "OF", "OL", "OV", "OW", "PN", "SH",
                                       "SL", "SQ", "SS", "ST", "SV", "TM", "UC", "UI", "UL", "UN",
                                       "UR", "US", "UT", "UV"};
    for (const char* k : kAll)
      if (v[0] == k[0] && v[1] == k[1]) return true;
    return false;
  }
  static bool long_vr(const unsigned char* v) {
    static const char* const kLong[] = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ",
                                        "SV", "UC", "UN", "UR", "UT", "UV"};
    for (const char* l : kLong)
      if (v[0] == l[0] && v[1] == l[1]) return true;
    return false;
  }
  /// True when [pos, end) is shorter than an element header or holds only zero bytes.
  bool zeros_or_short_tail(std::uint64_t pos, std::uint64_t end) {
    if (end - pos < 8) return true;
    unsigned char b[4096];
    for (std::uint64_t at = pos; at < end;) {
      const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(sizeof b, end - at));
      if (!read_at(at, b, n)) return false;
      for (std::size_t i = 0; i < n; ++i)
        if (b[i] != 0) return false;
      at += n;
    }
    return true;
  }
  static std::string tag_name(unsigned group, unsigned element) {
    char t[16];
    std::snprintf(t, sizeof t, "(%04x,%04x)", group, element);
    return t;
  }

  /// Group 0002: explicit VR little endian, each element inside the file, a data set after it;
  /// notes the data set's transfer syntax.
  std::string meta_group(std::uint64_t& pos) {
    int count = 0;
    for (;;) {
      unsigned char b[12];
      if (!read_at(pos, b, 8)) {
        if (count == 0) return "no File Meta Information after the DICM preamble";
        return pos == size_ ? "no data set after the File Meta Information (file cut short)"
                            : "File Meta Information cut short";
      }
      const unsigned group = b[0] | b[1] << 8u, element = b[2] | b[3] << 8u;
      if (group != 0x0002) {
        if (count == 0) return "no File Meta Information after the DICM preamble";
        big_endian_ = big_endian_data_;  // the meta group itself is always little endian
        return "";
      }
      if (!is_vr(b + 4) || !known_vr(b + 4))
        return "File Meta Information element " + tag_name(group, element) +
               " has no valid explicit VR";
      std::uint64_t header = 8, length = b[6] | b[7] << 8u;
      if (long_vr(b + 4)) {
        if (!read_at(pos, b, 12)) return "File Meta Information cut short";
        header = 12;
        length = u32(b + 8);
      }
      if (pos + header + length > size_)
        return "File Meta Information element " + tag_name(group, element) +
               " runs past the end of the file";
      if (element == 0x0010 && length < 80) {  // Transfer Syntax UID
        char uid[81] = {};
        read_at(pos + header, reinterpret_cast<unsigned char*>(uid), length);
        std::string ts = uid;
        while (!ts.empty() && (ts.back() == ' ' || ts.back() == '\0')) ts.pop_back();
        explicit_vr_ = ts != "1.2.840.10008.1.2";
        big_endian_data_ = ts == "1.2.840.10008.1.2.2";
        deflated_ = ts == "1.2.840.10008.1.2.1.99";
      }
      pos += header + length;
      ++count;
    }
  }

  /// Data elements from `pos` to `end` (or to an item delimitation when `end` is undefined,
  /// where `pos` is left after it).
  std::string elements(std::uint64_t& pos, std::uint64_t end, bool explicit_vr, int depth,
                       bool until_delimiter = false) {
    if (depth > kMaxDepth) return "sequences nested more than " + std::to_string(kMaxDepth) + " deep";
    while (pos < end) {
      // Trailing bytes after the last element of the data set — fewer than an element header,
      // or zeros (padding some writers leave) — are left to GDCM, as it reads them.
      if (depth == 0 && !until_delimiter && zeros_or_short_tail(pos, end)) return "";
      unsigned char b[12];
      if (pos + 8 > end || !read_at(pos, b, 8))
        return "element at byte " + std::to_string(pos) + " cut short";
      const unsigned group = u16(b), element = u16(b + 2);
      const std::string tag = tag_name(group, element);
      if (group == 0xfffe) {  // item tags: no VR in any syntax
        if (element == 0xe00d && until_delimiter) {  // item delimitation
          if (u32(b + 4) != 0)
            return "item delimitation with a length (" + std::to_string(u32(b + 4)) + ")";
          pos += 8;
          return "";
        }
        return "unexpected item tag " + tag + " at byte " + std::to_string(pos);
      }
      std::uint64_t header = 8, length = 0;
      bool sequence = false, implicit_inside = !explicit_vr;
      if (explicit_vr) {
        if (!is_vr(b + 4)) return "element " + tag + " has no explicit VR";
        if (!known_vr(b + 4))
          return "element " + tag + " has an unknown VR '" + std::string(1, char(b[4])) +
                 std::string(1, char(b[5])) + "'";
        if (long_vr(b + 4)) {
          if (pos + 12 > end || !read_at(pos, b, 12)) return "element " + tag + " cut short";
          header = 12;
          length = u32(b + 8);
        } else {
          length = u16(b + 6);
        }
        sequence = b[4] == 'S' && b[5] == 'Q';
        if (b[4] == 'U' && b[5] == 'N' && length == kUndefined) {
          sequence = true;  // PS3.5 §6.2.2: an undefined-length UN is an implicit VR sequence
          implicit_inside = true;
        }
        if (!sequence && length == kUndefined && !(b[4] == 'O' && (b[5] == 'B' || b[5] == 'W')))
          return "element " + tag + " has an undefined length";
        if (b[4] == 'U' && b[5] == 'N' && length != kUndefined && length >= 8) {
          // GDCM re-reads a UN value that its dictionary calls a sequence as implicit VR items:
          // walk it as such when it starts with an item tag.
          unsigned char first[4];
          if (read_at(pos + header, first, 4) && u16(first) == 0xfffe && u16(first + 2) == 0xe000) {
            sequence = true;
            implicit_inside = true;
          }
        }
      } else {
        length = u32(b + 4);
        // Implicit VR: an undefined length means a sequence; a defined-length one is known by
        // its first item tag (GDCM parses what its dictionary calls a sequence).
        sequence = length == kUndefined;
        unsigned char first[4];
        if (!sequence && length >= 8 && read_at(pos + 8, first, 4))
          sequence = u16(first) == 0xfffe && u16(first + 2) == 0xe000;
      }
      pos += header;
      if (length == kUndefined) {
        // A sequence of items, or encapsulated pixel data (fragments), up to (FFFE,E0DD).
        if (std::string p = items(pos, end, sequence ? !implicit_inside : explicit_vr,
                                  sequence, depth + 1);
            !p.empty())
          return p;
        continue;
      }
      if (length > end - pos)
        return "element " + tag + " declares " + std::to_string(length) + " bytes, " +
               std::to_string(end - pos) + " are left";
      if (group == 0x0028 && element == 0x0002 && length == 2) {
        // GDCM asserts SamplesPerPixel ∈ {1, 3, 4} (gdcmPixelFormat.h:94; fuzz_dicom hit it
        // hundreds of times): the process would abort.
        unsigned char v[2];
        if (read_at(pos, v, 2) && u16(v) != 1 && u16(v) != 3 && u16(v) != 4)
          return "SamplesPerPixel (0028,0002) is " + std::to_string(u16(v)) + " (1, 3 or 4)";
      }
      if (sequence) {
        std::uint64_t inner = pos;
        if (std::string p = items(inner, pos + length, explicit_vr && !implicit_inside, true,
                                  depth + 1, true);
            !p.empty())
          return p;
      }
      pos += length;
    }
    if (until_delimiter) return "item without its delimitation";
    return "";
  }

  /// Items from `pos`: of a sequence (data elements inside) or encapsulated pixel data
  /// (fragments). With `bounded`, they fill [pos, end); otherwise they end at (FFFE,E0DD).
  std::string items(std::uint64_t& pos, std::uint64_t end, bool explicit_vr, bool sequence,
                    int depth, bool bounded = false) {
    if (depth > kMaxDepth) return "sequences nested more than " + std::to_string(kMaxDepth) + " deep";
    for (;;) {
      if (bounded && pos == end) return "";
      unsigned char b[8];
      if (pos + 8 > end || !read_at(pos, b, 8))
        return "sequence at byte " + std::to_string(pos) + " cut short";
      const unsigned group = u16(b), element = u16(b + 2);
      const std::uint32_t length = u32(b + 4);
      pos += 8;
      if (group == 0xfffe && element == 0xe0dd) {
        if (bounded) return "sequence delimitation in a sequence of defined length";
        // GDCM reads a delimitation's length as a value's (fuzz_dicom: 0xffff0000 → 4 GB).
        if (length != 0) return "sequence delimitation with a length (" + std::to_string(length) + ")";
        return "";
      }
      if (group != 0xfffe || element != 0xe000)
        return "expected an item, found " + tag_name(group, element);
      if (length == kUndefined) {
        if (!sequence) return "pixel data fragment of undefined length";
        if (std::string p = elements(pos, end, explicit_vr, depth, true); !p.empty()) return p;
        continue;
      }
      if (length > end - pos)
        return "item declares " + std::to_string(length) + " bytes, " +
               std::to_string(end - pos) + " are left";
      if (sequence) {
        std::uint64_t inner = pos;
        if (std::string p = elements(inner, pos + length, explicit_vr, depth); !p.empty())
          return p;
      }
      pos += length;
    }
  }

  std::FILE* f_;
  std::uint64_t size_ = 0;
  bool explicit_vr_ = true, big_endian_ = false, big_endian_data_ = false, deflated_ = false;
};

/// Why GDCM must not be given this file, or "" when it may (StructureWalk).
std::string structure_problem(const std::string& path) {
  const bool preamble = has_dicom_magic(path);
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return "cannot open the file";
  std::string problem = StructureWalk(f).check(preamble);
  std::fclose(f);
  return problem;
}

/// GDCM prints its warnings on stderr; adamesh reports errors itself, on one line.
void quiet_gdcm() {
  gdcm::Trace::WarningOff();
  gdcm::Trace::DebugOff();
  gdcm::Trace::ErrorOff();
}


// ---------------------------------------------------------------------------------------------
// GDCM in a child process. GDCM and the decoders it calls crash on some corrupt files — an
// out-of-bounds read in GDCM's JPEG 2000 header parser (parsej2k_imp, fuzz_dicom 2026-12-02),
// the assertions Debian's build keeps (a process abort), leaks — and print their warnings on
// stderr. The structure walk above keeps GDCM from allocating what a file does not hold, but the
// codecs' internals are beyond such checks. So the whole DICOM read (header scan, decoding,
// conversion) runs in a forked child that sends the volume, or the Error it threw, through a
// pipe; a child killed by a signal becomes one error line naming the file GDCM was working on,
// and the child's stderr goes to /dev/null. Without fork (it failed), the read runs here.
// The child runs only this file's code, GDCM and its codecs: no oneTBB (a forked child has
// none of the parent's worker threads, and a parallel loop there could wait for them forever).

struct SharedNote {
  char file[4096];
};
SharedNote* g_note = nullptr;  // set in the child only
std::atomic<std::uint64_t> g_child_failures{0};

/// Records which file GDCM is about to work on, for the parent's message if the child dies.
void note_gdcm_work(const std::string& what) {
  if (!g_note) return;
  const std::size_t n = std::min(what.size(), sizeof g_note->file - 1);
  std::memcpy(g_note->file, what.data(), n);
  g_note->file[n] = '\0';
}

bool write_all(int fd, const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t w = ::write(fd, p, std::min<std::size_t>(size, 1u << 20));
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    size -= static_cast<std::size_t>(w);
  }
  return true;
}

/// Reads exactly `size` bytes; false at end of file or on an error.
bool read_all(int fd, void* data, std::size_t size) {
  char* p = static_cast<char*>(data);
  while (size > 0) {
    const ssize_t r = ::read(fd, p, std::min<std::size_t>(size, 1u << 20));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    p += r;
    size -= static_cast<std::size_t>(r);
  }
  return true;
}

/// What the child sends first: a volume's geometry and sizes, or an error's status and length.
struct Reply {
  std::int32_t kind = 0;  // 1 volume, 2 Error
  std::int32_t status = 0;
  std::int32_t type = 0;
  std::int32_t pad = 0;
  std::int64_t dims[3] = {0, 0, 0};
  double spacing[3] = {0, 0, 0}, origin[3] = {0, 0, 0}, direction[9] = {};
  std::uint64_t text_bytes = 0;  // format (volume) or message (error)
  std::uint64_t data_bytes = 0;
};

const char* signal_name(int sig) {
  switch (sig) {
    case SIGSEGV: return "SIGSEGV, a memory fault";
    case SIGABRT: return "SIGABRT, a failed assertion";
    case SIGBUS: return "SIGBUS";
    case SIGFPE: return "SIGFPE, an arithmetic fault";
    case SIGILL: return "SIGILL";
    case SIGKILL: return "SIGKILL, killed (out of memory?)";
    default: return "a signal";
  }
}

/// Bytes of the regular files at `path` (a file, or the files of a folder, not recursive).
std::uint64_t input_bytes(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) {
    const auto n = fs::file_size(path, ec);
    return ec ? 0 : n;
  }
  std::uint64_t total = 0;
  for (const auto& e : fs::directory_iterator(path, ec))
    if (e.is_regular_file(ec)) total += e.file_size(ec);
  return total;
}

/// The child's data-segment limit: room for the decoded volume of these files (compressed pixel
/// data expands; 32 × the files, at least 2 GiB) so that an allocation no file of this size can
/// need fails in the child (an error) instead of taking the machine's memory. Not under the
/// sanitizers, whose runtimes reserve terabytes.
void limit_child_memory(std::uint64_t bytes) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  (void)bytes;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || \
    __has_feature(memory_sanitizer)
  (void)bytes;
#else
  const std::uint64_t limit = std::max<std::uint64_t>(std::uint64_t{2} << 30, 32 * bytes);
  const rlimit r{limit, limit};
  ::setrlimit(RLIMIT_DATA, &r);
#endif
#else
  const std::uint64_t limit = std::max<std::uint64_t>(std::uint64_t{2} << 30, 32 * bytes);
  const rlimit r{limit, limit};
  ::setrlimit(RLIMIT_DATA, &r);
#endif
}

template <class Read>
Volume isolated(const std::string& where, std::uint64_t bytes, Read&& read) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return read();
  void* shared = ::mmap(nullptr, sizeof(SharedNote), PROT_READ | PROT_WRITE,
                        MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (shared == MAP_FAILED) {
    ::close(fds[0]);
    ::close(fds[1]);
    return read();
  }
  auto* note = static_cast<SharedNote*>(shared);
  note->file[0] = '\0';
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    ::munmap(shared, sizeof(SharedNote));
    return read();
  }
  if (pid == 0) {  // the child: read, send, _exit (no atexit handlers, no leak check)
    ::close(fds[0]);
    // ADAMESH_DICOM_CHILD_STDERR=FILE keeps what the child prints (GDCM's and the decoders'
    // messages, a sanitizer's report): fuzz_dicom uses it to tell GDCM's crashes from adamesh's.
    const char* keep = std::getenv("ADAMESH_DICOM_CHILD_STDERR");
    const int err = keep && *keep ? ::open(keep, O_WRONLY | O_CREAT | O_TRUNC, 0644)
                                  : ::open("/dev/null", O_WRONLY);
    if (err >= 0) ::dup2(err, 2);
    g_note = note;
    limit_child_memory(bytes);
    Reply reply;
    std::string text;
    Volume v;
    try {
      v = read();
      reply.kind = 1;
      reply.type = static_cast<std::int32_t>(v.type);
      for (int i = 0; i < 3; ++i) {
        reply.dims[i] = v.grid.dims[static_cast<std::size_t>(i)];
        reply.spacing[i] = v.grid.spacing[i];
        reply.origin[i] = v.grid.origin[i];
        for (int j = 0; j < 3; ++j) reply.direction[3 * i + j] = v.grid.direction.m[i][j];
      }
      text = v.format;
      reply.data_bytes = v.data.size();
    } catch (const Error& e) {
      reply.kind = 2;
      reply.status = static_cast<std::int32_t>(e.status());
      text = e.what();
    } catch (const std::bad_alloc&) {
      reply.kind = 2;
      reply.status = static_cast<std::int32_t>(Status::invalid_input);
      text = std::string(note->file[0] ? note->file : where.c_str()) +
             ": the DICOM data asks for more memory than files of this size can need (corrupt?)";
    } catch (const std::exception& e) {
      reply.kind = 2;
      reply.status = static_cast<std::int32_t>(Status::invalid_input);
      text = where + ": " + e.what();
    }
    reply.text_bytes = text.size();
    const bool ok = write_all(fds[1], &reply, sizeof reply) &&
                    write_all(fds[1], text.data(), text.size()) &&
                    (reply.kind != 1 || write_all(fds[1], v.data.data(), v.data.size()));
    ::_exit(ok ? 0 : 1);
  }
  ::close(fds[1]);
  Reply reply;
  std::string text;
  Volume v;
  bool complete = read_all(fds[0], &reply, sizeof reply) && (reply.kind == 1 || reply.kind == 2) &&
                  reply.text_bytes < (1u << 20);
  if (complete) {
    text.resize(reply.text_bytes);
    complete = read_all(fds[0], text.data(), text.size());
  }
  if (complete && reply.kind == 1) {
    Grid grid;
    for (int i = 0; i < 3; ++i) {
      grid.dims[static_cast<std::size_t>(i)] = reply.dims[i];
      grid.spacing[i] = reply.spacing[i];
      grid.origin[i] = reply.origin[i];
      for (int j = 0; j < 3; ++j) grid.direction.m[i][j] = reply.direction[3 * i + j];
    }
    v = allocate_volume(grid, static_cast<ScalarType>(reply.type), where);
    complete = v.data.size() == reply.data_bytes && read_all(fds[0], v.data.data(), v.data.size());
    v.format = text;
  }
  ::close(fds[0]);
  int wstatus = 0;
  while (::waitpid(pid, &wstatus, 0) < 0 && errno == EINTR) {
  }
  std::string file = note->file;
  ::munmap(shared, sizeof(SharedNote));
  if (!complete) {
    g_child_failures.fetch_add(1, std::memory_order_relaxed);
    if (file.empty()) file = where;
    if (WIFSIGNALED(wstatus))
      fail_input(file, std::string("GDCM crashed reading this DICOM data (") +
                           signal_name(WTERMSIG(wstatus)) +
                           "): a corrupt file or an encoding GDCM mishandles");
    fail_input(file, "the DICOM reader process ended without a result");
  }
  if (reply.kind == 2) throw Error(static_cast<Status>(reply.status), text);
  return v;
}

}  // namespace

bool is_dicom_file(const std::string& path) { return has_dicom_magic(path); }

std::uint64_t dicom_child_failures() noexcept {
  return g_child_failures.load(std::memory_order_relaxed);
}

namespace {

Volume read_series_in_process(const std::vector<std::string>& all_files, const std::string& where,
                              const std::string& series_uid) {
  quiet_gdcm();
  // GDCM may abort or allocate gigabytes on a file whose element structure is broken: such a
  // file with the Part 10 preamble is an error (it was meant as a slice; leaving it out would
  // change the volume); one without is ignored, as any file that is not a DICOM image.
  std::vector<std::string> files;
  for (const std::string& f : all_files) {
    const std::string problem = structure_problem(f);
    if (problem.empty())
      files.push_back(f);
    else if (has_dicom_magic(f))
      fail_input(f, "not a readable DICOM file: " + problem);
  }
  gdcm::Scanner scanner;
  for (const gdcm::Tag& t : {kSeriesUid, kSeriesDescription, kModality, kPosition, kOrientation,
                             kPixelSpacing, kRows, kColumns, kFrames})
    scanner.AddTag(t);
  note_gdcm_work(where + " (scanning the headers of " + std::to_string(files.size()) + " files)");
  if (!scanner.Scan(files)) fail_input(where, "cannot scan the DICOM files");
  std::map<std::string, std::vector<std::string>> series;  // uid -> files
  for (const std::string& f : files)
    if (scanner.IsKey(f.c_str()))
      series[trimmed(scanner.GetValue(f.c_str(), kSeriesUid))].push_back(f);
  if (series.empty())
    fail_input(where,
               "no DICOM image files (" + std::to_string(all_files.size()) + " files looked at)");

  std::string uid = series_uid;
  if (uid.empty()) {
    if (series.size() > 1) {
      std::string list;
      for (const auto& [u, fs_] : series) {
        const char* f0 = fs_.front().c_str();
        // One line (errors are one line; a newline would be escaped): "UID (CT, 12 files,
        // 'description')" entries separated by "; ".
        list += std::string(list.empty() ? " " : "; ") +
                (u.empty() ? std::string("(no SeriesInstanceUID)") : u) + " (" +
                trimmed(scanner.GetValue(f0, kModality)) + ", " + std::to_string(fs_.size()) +
                (fs_.size() == 1 ? " file" : " files") + ", '" +
                trimmed(scanner.GetValue(f0, kSeriesDescription)) + "')";
      }
      fail(Status::usage, where + ": " + std::to_string(series.size()) +
                              " DICOM series; choose one with --series UID:" + list);
    }
    uid = series.begin()->first;
  } else if (!series.count(uid)) {
    std::string list;
    for (const auto& s : series) list += " " + s.first;
    fail(Status::usage,
         where + ": no DICOM series with UID " + uid + " (series here:" + list + ")");
  }
  const std::vector<std::string>& names = series[uid];
  if (names.size() < 2)
    fail(Status::unsupported,
         where + ": DICOM series " + uid + " has a single slice: a volume needs at least 2");

  // Geometry from the headers: every slice must share orientation, size and pixel spacing.
  const std::string f0 = names.front();
  const std::vector<double> iop = numbers(trimmed(scanner.GetValue(f0.c_str(), kOrientation)));
  const std::vector<double> ps = numbers(trimmed(scanner.GetValue(f0.c_str(), kPixelSpacing)));
  if (iop.size() != 6) fail_input(f0, "missing or invalid ImageOrientationPatient (0020,0037)");
  if (ps.size() != 2 || !(ps[0] > 0) || !(ps[1] > 0))
    fail_input(f0, "missing or invalid PixelSpacing (0028,0030)");
  const Vec3 row{iop[0], iop[1], iop[2]}, col{iop[3], iop[4], iop[5]};
  if (std::abs(norm(row) - 1) > 1e-3 || std::abs(norm(col) - 1) > 1e-3 ||
      std::abs(dot(row, col)) > 1e-3)
    fail_input(f0, "ImageOrientationPatient is not two orthogonal unit vectors");
  const Vec3 r = normalized(row), c = normalized(col), n = normalized(cross(row, col));
  std::vector<Slice> slices;
  for (const std::string& f : names) {
    const char* fc = f.c_str();
    if (trimmed(scanner.GetValue(fc, kOrientation)) !=
        trimmed(scanner.GetValue(f0.c_str(), kOrientation))) {
      const std::vector<double> o = numbers(trimmed(scanner.GetValue(fc, kOrientation)));
      double diff = o.size() == 6 ? 0 : 1;
      for (std::size_t i = 0; i < o.size() && i < 6; ++i)
        diff = std::max(diff, std::abs(o[i] - iop[i]));
      if (diff > 1e-4)
        fail(Status::unsupported, f + ": ImageOrientationPatient differs from " + f0 +
                                      " (slices in several orientations)");
    }
    if (trimmed(scanner.GetValue(fc, kRows)) != trimmed(scanner.GetValue(f0.c_str(), kRows)) ||
        trimmed(scanner.GetValue(fc, kColumns)) != trimmed(scanner.GetValue(f0.c_str(), kColumns)))
      fail(Status::unsupported, f + ": slice size differs from " + f0);
    const std::vector<double> p2 = numbers(trimmed(scanner.GetValue(fc, kPixelSpacing)));
    if (p2.size() != 2 || std::abs(p2[0] - ps[0]) > 1e-4 * ps[0] ||
        std::abs(p2[1] - ps[1]) > 1e-4 * ps[1])
      fail(Status::unsupported, f + ": PixelSpacing differs from " + f0);
    const std::string frames = trimmed(scanner.GetValue(fc, kFrames));
    if (!frames.empty() && frames != "1")
      fail(Status::unsupported, f + ": multi-frame DICOM (" + frames + " frames) is not supported");
    const std::vector<double> p = numbers(trimmed(scanner.GetValue(fc, kPosition)));
    if (p.size() != 3) fail_input(f, "missing or invalid ImagePositionPatient (0020,0032)");
    Slice s{f, {p[0], p[1], p[2]}, 0};
    s.along = dot(s.position, n);
    slices.push_back(s);
  }
  std::sort(slices.begin(), slices.end(),
            [](const Slice& a, const Slice& b) { return a.along < b.along; });
  const std::size_t nz = slices.size();
  const double dz = (slices.back().along - slices.front().along) / static_cast<double>(nz - 1);
  for (std::size_t k = 1; k < nz; ++k) {
    const double step = slices[k].along - slices[k - 1].along;
    if (step < 1e-6 * std::max(1.0, std::abs(dz)))
      fail(Status::unsupported, where + ": two slices at the same position (" + slices[k - 1].file +
                                    ", " + slices[k].file +
                                    "): several acquisitions, echoes or time points in one series");
    if (std::abs(step - dz) > 0.01 * dz + 1e-4)
      fail(Status::unsupported, where + ": uneven slice spacing: " + std::to_string(step) +
                                    " mm between " + slices[k - 1].file + " and " + slices[k].file +
                                    ", " + std::to_string(dz) +
                                    " mm on average (missing slices?); not resampled");
    // Gantry tilt: the slice origins must move along the normal only.
    const Vec3 d = slices[k].position - slices[0].position;
    const Vec3 lateral = d - n * dot(d, n);
    if (norm(lateral) > 0.01 * std::min({ps[0], ps[1], dz}) * static_cast<double>(k) + 1e-3)
      fail(Status::unsupported,
           where +
               ": slice positions are not along the slice normal (gantry tilt or "
               "sheared series, offset " +
               std::to_string(norm(lateral)) + " mm at " + slices[k].file + "); not resampled");
  }

  // Pixels: read every slice, then choose the output type from the rescaled range.
  Grid grid;
  std::array<std::int64_t, 2> size{0, 0};
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  bool integral = true;
  std::vector<std::pair<double, double>> rescale(nz);
  std::vector<gdcm::PixelFormat> formats;
  std::vector<std::vector<char>> buffers(nz);
  for (std::size_t k = 0; k < nz; ++k) {
    gdcm::ImageReader reader;
    reader.SetFileName(slices[k].file.c_str());
    note_gdcm_work(slices[k].file);
    if (!reader.Read())
      fail_input(slices[k].file,
                 "GDCM cannot read the image (corrupt file or unsupported transfer syntax)");
    const gdcm::Image& img = reader.GetImage();
    const unsigned int* dim = img.GetDimensions();
    if (img.GetNumberOfDimensions() == 3 && dim[2] != 1)
      fail(Status::unsupported, slices[k].file + ": multi-frame DICOM is not supported");
    const gdcm::PixelFormat pf = img.GetPixelFormat();
    if (pf.GetSamplesPerPixel() != 1)
      fail(Status::unsupported, slices[k].file + ": colour DICOM images are not supported");
    if (k == 0) size = {dim[0], dim[1]};
    if (dim[0] != size[0] || dim[1] != size[1])
      fail(Status::unsupported, slices[k].file + ": slice size differs");
    if (pf.GetScalarType() == gdcm::PixelFormat::UNKNOWN || pf.GetBitsAllocated() > 32 ||
        pf.GetBitsAllocated() % 8 != 0)
      fail(Status::unsupported, slices[k].file + ": pixel format with " +
                                    std::to_string(pf.GetBitsAllocated()) +
                                    " bits allocated is not supported");
    buffers[k].resize(img.GetBufferLength());
    if (!img.GetBuffer(buffers[k].data()))
      fail_input(slices[k].file, "cannot decode the pixel data");
    const std::size_t bytes = pf.GetPixelSize();
    if (buffers[k].size() < static_cast<std::size_t>(size[0] * size[1]) * bytes)
      fail_input(slices[k].file, "pixel data shorter than the image size");
    rescale[k] = {img.GetSlope(), img.GetIntercept()};
    formats.push_back(pf);
    // Plain variables, not a structured binding: clang 14 (the fuzz preset) cannot capture
    // those in the lambdas below.
    const double slope = std::get<0>(rescale[k]), icpt = std::get<1>(rescale[k]);
    if (slope != std::floor(slope) || icpt != std::floor(icpt) || !(slope != 0)) integral = false;
    // Range of the rescaled values: the output type is the smallest that holds them exactly.
    const char* src = buffers[k].data();
    const std::size_t count = static_cast<std::size_t>(size[0] * size[1]);
    auto range = [&](auto in_tag) {
      using In = decltype(in_tag);
      if constexpr (std::is_floating_point_v<In>) integral = false;
      for (std::size_t i = 0; i < count; ++i) {
        In x;
        std::memcpy(&x, src + i * sizeof(In), sizeof(In));
        const double y = static_cast<double>(x) * slope + icpt;
        if (!std::isfinite(y)) continue;  // NaN/Inf samples: load_input reports them
        lo = std::min(lo, y);
        hi = std::max(hi, y);
      }
    };
    switch (pf.GetScalarType()) {
      case gdcm::PixelFormat::UINT8:
        range(std::uint8_t{});
        break;
      case gdcm::PixelFormat::INT8:
        range(std::int8_t{});
        break;
      case gdcm::PixelFormat::UINT16:
        range(std::uint16_t{});
        break;
      case gdcm::PixelFormat::INT16:
        range(std::int16_t{});
        break;
      case gdcm::PixelFormat::UINT32:
        range(std::uint32_t{});
        break;
      case gdcm::PixelFormat::INT32:
        range(std::int32_t{});
        break;
      case gdcm::PixelFormat::FLOAT32:
        range(float{});
        break;
      case gdcm::PixelFormat::FLOAT64:
        range(double{});
        break;
      default:
        fail(Status::unsupported,
             slices[k].file + ": unsupported pixel type " + pf.GetScalarTypeAsString());
    }
  }
  ScalarType type = ScalarType::f32;
  if (integral) {
    if (lo >= 0 && hi <= 255)
      type = ScalarType::u8;
    else if (lo >= -32768 && hi <= 32767)
      type = ScalarType::i16;
    else if (lo >= 0 && hi <= 65535)
      type = ScalarType::u16;
    else if (lo >= -2147483648.0 && hi <= 2147483647.0)
      type = ScalarType::i32;
  }

  grid.dims = {size[0], size[1], static_cast<std::int64_t>(nz)};
  grid.spacing = {ps[1], ps[0], dz};  // PixelSpacing = (between rows, between columns)
  grid.origin = slices.front().position;
  grid.direction = Mat3::from_columns(r, c, n);
  Volume v = allocate_volume(grid, type, where);
  v.format = "DICOM";
  const std::size_t per_slice = static_cast<std::size_t>(size[0] * size[1]);
  for (std::size_t k = 0; k < nz; ++k) {
    const gdcm::PixelFormat& pf = formats[k];
    // Plain variables, not a structured binding: clang 14 (the fuzz preset) cannot capture
    // those in the lambdas below.
    const double slope = std::get<0>(rescale[k]), icpt = std::get<1>(rescale[k]);
    const char* src = buffers[k].data();
    dispatch_scalar(type, [&](auto out_tag) {
      using Out = decltype(out_tag);
      Out* dst = v.samples<Out>() + k * per_slice;
      constexpr double omin = static_cast<double>(std::numeric_limits<Out>::lowest());
      constexpr double omax = static_cast<double>(std::numeric_limits<Out>::max());
      auto convert = [&](auto in_tag) {
        using In = decltype(in_tag);
        for (std::size_t i = 0; i < per_slice; ++i) {
          In x;
          std::memcpy(&x, src + i * sizeof(In), sizeof(In));
          const double y = static_cast<double>(x) * slope + icpt;
          dst[i] = static_cast<Out>(std::clamp(y, omin, omax));
        }
      };
      switch (pf.GetScalarType()) {
        case gdcm::PixelFormat::UINT8:
          convert(std::uint8_t{});
          break;
        case gdcm::PixelFormat::INT8:
          convert(std::int8_t{});
          break;
        case gdcm::PixelFormat::UINT16:
          convert(std::uint16_t{});
          break;
        case gdcm::PixelFormat::INT16:
          convert(std::int16_t{});
          break;
        case gdcm::PixelFormat::UINT32:
          convert(std::uint32_t{});
          break;
        case gdcm::PixelFormat::INT32:
          convert(std::int32_t{});
          break;
        case gdcm::PixelFormat::FLOAT32:
          convert(float{});
          break;
        case gdcm::PixelFormat::FLOAT64:
          convert(double{});
          break;
        default:
          fail(Status::unsupported, slices[k].file + ": unsupported pixel type");
      }
    });
    std::vector<char>().swap(buffers[k]);
  }
  return v;
}

Volume read_dicom_in_process(const std::string& path, const std::string& series_uid) {
  std::error_code ec;
  std::vector<std::string> files;
  std::string uid = series_uid;
  if (fs::is_directory(path, ec)) {
    for (const auto& e : fs::directory_iterator(path, ec))
      if (e.is_regular_file(ec)) files.push_back(e.path().string());
    if (ec) fail_input(path, "cannot list the directory: " + ec.message());
    std::sort(files.begin(), files.end());
  } else {
    // One slice named: its series, read from the slice's directory.
    quiet_gdcm();
    if (const std::string problem = structure_problem(path); !problem.empty())
      fail_input(path, "not a readable DICOM file: " + problem);
    gdcm::Scanner one;
    one.AddTag(kSeriesUid);
    note_gdcm_work(path);
    if (!one.Scan({path}) || !one.IsKey(path.c_str())) fail_input(path, "not a DICOM image file");
    const std::string own = trimmed(one.GetValue(path.c_str(), kSeriesUid));
    if (!uid.empty() && uid != own)
      fail(Status::usage, path + ": this file belongs to series " + own + ", not " + uid);
    uid = own;
    const fs::path dir =
        fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path();
    for (const auto& e : fs::directory_iterator(dir, ec))
      if (e.is_regular_file(ec)) files.push_back(e.path().string());
    std::sort(files.begin(), files.end());
  }
  return read_series_in_process(files, path, uid);
}

}  // namespace

Volume read_dicom_series(const std::vector<std::string>& files, const std::string& where,
                         const std::string& series_uid) {
  std::uint64_t bytes = 0;
  for (const std::string& f : files) bytes += input_bytes(f);
  return isolated(where, bytes, [&] { return read_series_in_process(files, where, series_uid); });
}

Volume read_dicom(const std::string& path, const std::string& series_uid) {
  // A named slice reads its folder's series.
  std::error_code ec;
  const std::string folder = fs::is_directory(path, ec) || fs::path(path).parent_path().empty()
                                 ? (fs::is_directory(path, ec) ? path : std::string("."))
                                 : fs::path(path).parent_path().string();
  return isolated(path, input_bytes(folder),
                  [&] { return read_dicom_in_process(path, series_uid); });
}

}  // namespace adamesh::detail
