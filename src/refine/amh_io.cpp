// `.amh` hierarchy files (docs/HIERARCHY.md): header, base mesh, splits in progressive order,
// FNV-1a checksum. Little-endian, fixed-size records, written atomically.
//
// Reference: Hoppe, "Progressive meshes" (1996) — a base mesh followed by a refinement stream;
// any prefix of the split list is a valid coarser conforming mesh.
//
// The reader never allocates more than the file holds: every count is checked against the file
// size before anything is allocated, then the whole hierarchy is validated by a replay.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <vector>

#include "adamesh/atomic_file.h"
#include "adamesh/error.h"
#include "adamesh/refine.h"

namespace adamesh {

namespace {

constexpr char kMagic[8] = {'A', 'D', 'A', 'M', 'H', 'I', 'E', 'R'};
constexpr std::uint32_t kVersion = 1;
constexpr std::uint32_t kFlagAnchors = 1;
constexpr std::uint64_t kHeaderBytes = 8 + 4 + 4 + 3 * 8 + 2 * 8 + 6 * 8;  // 104
constexpr std::uint64_t kSplitBytes = 4 + 4 + 3 * 8;                       // 32
constexpr std::uint64_t kFooterBytes = 8;

std::uint64_t fnv1a(const unsigned char* p, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

class Writer {
 public:
  template <class T>
  void put(T v) {
    static_assert(std::is_trivially_copyable_v<T>);
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
    buf.insert(buf.end(), b, b + sizeof(T));
  }
  std::vector<unsigned char> buf;
};

class Reader {
 public:
  Reader(const std::vector<unsigned char>& b, std::string where) : buf_(b), where_(std::move(where)) {}
  template <class T>
  T get() {
    if (pos_ + sizeof(T) > buf_.size()) fail_input(where_, "truncated file");
    unsigned char b[sizeof(T)];
    std::memcpy(b, buf_.data() + pos_, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
    pos_ += sizeof(T);
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }
  std::size_t pos() const { return pos_; }

 private:
  const std::vector<unsigned char>& buf_;
  std::string where_;
  std::size_t pos_ = 0;
};

/// Bytes before the split list, or nullopt on overflow.
std::optional<std::uint64_t> fixed_bytes(std::uint64_t v0, std::uint64_t f0, bool anchors) {
  constexpr std::uint64_t kMax = std::numeric_limits<std::uint32_t>::max();
  if (v0 > kMax || f0 > kMax) return std::nullopt;
  return kHeaderBytes + v0 * (24 + 1 + (anchors ? 4 : 0)) + f0 * 12;
}

}  // namespace

void write_hierarchy(const Hierarchy& h, const std::string& path) {
  validate_hierarchy(h, path);
  Writer w;
  for (char c : kMagic) w.put(c);
  const bool anchors = !h.base_anchor.empty();
  w.put(kVersion);
  w.put(anchors ? kFlagAnchors : 0u);
  w.put(static_cast<std::uint64_t>(h.base_positions.size()));
  w.put(static_cast<std::uint64_t>(h.base_triangles.size()));
  w.put(static_cast<std::uint64_t>(h.splits.size()));
  w.put(h.iso);
  w.put(h.voxel);
  for (int i = 0; i < 3; ++i) w.put(h.bounds.lo[i]);
  for (int i = 0; i < 3; ++i) w.put(h.bounds.hi[i]);
  for (const auto& p : h.base_positions) {
    w.put(p.x);
    w.put(p.y);
    w.put(p.z);
  }
  for (const auto b : h.base_border) w.put(b);
  if (anchors)
    for (const auto a : h.base_anchor) w.put(a);
  for (const auto& t : h.base_triangles)
    for (const auto v : t) w.put(v);
  for (const auto& s : h.splits) {
    w.put(s.triangle);
    w.put(s.error);
    w.put(s.position.x);
    w.put(s.position.y);
    w.put(s.position.z);
  }
  w.put(fnv1a(w.buf.data(), w.buf.size()));
  write_file_atomically(path, [&](std::ostream& os) {
    os.write(reinterpret_cast<const char*>(w.buf.data()), static_cast<std::streamsize>(w.buf.size()));
  });
}

Hierarchy read_hierarchy(const std::string& path, const HierarchyReadOptions& options) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) fail_input(path, "cannot read: " + ec.message());
  if (size < kHeaderBytes) fail_input(path, "truncated: " + std::to_string(size) +
                                                " bytes, shorter than the .amh header");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail_input(path, "cannot open");
  std::vector<unsigned char> buf(static_cast<std::size_t>(size));
  in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(size));
  if (static_cast<std::uint64_t>(in.gcount()) != size) fail_input(path, "read error");

  if (std::memcmp(buf.data(), kMagic, sizeof(kMagic)) != 0)
    fail_input(path, "not an adamesh hierarchy file (bad magic)");
  Reader r(buf, path);
  for (std::size_t i = 0; i < sizeof(kMagic); ++i) r.get<char>();
  const auto version = r.get<std::uint32_t>();
  if (version != kVersion)
    fail(Status::unsupported, path + ": .amh version " + std::to_string(version) +
                                  " (this build reads version " + std::to_string(kVersion) + ")");
  const auto flags = r.get<std::uint32_t>();
  if (flags & ~kFlagAnchors) fail_input(path, "unknown header flags");
  const bool anchors = flags & kFlagAnchors;
  const auto v0 = r.get<std::uint64_t>(), f0 = r.get<std::uint64_t>();
  auto ns = r.get<std::uint64_t>();
  const auto fixed = fixed_bytes(v0, f0, anchors);
  if (!fixed || ns > std::numeric_limits<std::uint32_t>::max() / 4)
    fail_input(path, "corrupt header: counts out of range");
  const std::uint64_t expected = *fixed + ns * kSplitBytes + kFooterBytes;
  if (size != expected) {
    if (!options.allow_partial || size < *fixed)
      fail_input(path, (size < expected ? "truncated: " : "corrupt: ") + std::to_string(size) +
                           " bytes where the header announces " + std::to_string(expected));
    ns = std::min<std::uint64_t>(ns, (size - *fixed) / kSplitBytes);
  } else {
    const std::size_t body = static_cast<std::size_t>(size - kFooterBytes);
    std::uint64_t stored = 0;
    for (int i = 7; i >= 0; --i) stored = (stored << 8) | buf[body + static_cast<std::size_t>(i)];
    if (stored != fnv1a(buf.data(), body)) fail_input(path, "checksum mismatch (corrupt file)");
  }

  Hierarchy h;
  h.iso = r.get<double>();
  h.voxel = r.get<double>();
  for (int i = 0; i < 3; ++i) h.bounds.lo[i] = r.get<double>();
  for (int i = 0; i < 3; ++i) h.bounds.hi[i] = r.get<double>();
  h.base_positions.resize(v0);
  for (auto& p : h.base_positions) {
    p.x = r.get<double>();
    p.y = r.get<double>();
    p.z = r.get<double>();
  }
  h.base_border.resize(v0);
  for (auto& b : h.base_border) b = r.get<std::uint8_t>();
  if (anchors) {
    h.base_anchor.resize(v0);
    for (auto& a : h.base_anchor) a = r.get<std::uint32_t>();
  }
  h.base_triangles.resize(f0);
  for (auto& t : h.base_triangles)
    for (auto& v : t) v = r.get<std::uint32_t>();
  h.splits.resize(ns);
  for (auto& s : h.splits) {
    s.triangle = r.get<std::uint32_t>();
    s.error = r.get<float>();
    s.position.x = r.get<double>();
    s.position.y = r.get<double>();
    s.position.z = r.get<double>();
  }
  validate_hierarchy(h, path);
  return h;
}

}  // namespace adamesh
