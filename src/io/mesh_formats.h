// Internal interface of the mesh readers and writers (one .cpp per format, dispatch in
// mesh_io.cpp): buffered output, whole-file input, number formatting and parsing helpers.
#pragma once

#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ostream>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "adamesh/error.h"
#include "adamesh/io.h"
#include "adamesh/mesh.h"

namespace adamesh::detail::meshfmt {

// ---- Format entry points. Writers get a mesh already checked by check_mesh_for_writing(). ----
void write_ply(const Mesh& mesh, std::ostream& os, const MeshWriteOptions& options);
void write_obj(const Mesh& mesh, std::ostream& os, const MeshWriteOptions& options);
void write_off(const Mesh& mesh, std::ostream& os, const MeshWriteOptions& options);
void write_stl(const Mesh& mesh, std::ostream& os);
void write_glb(const Mesh& mesh, std::ostream& os, const MeshWriteOptions& options);
/// `.gltf` JSON at `path` plus its buffer in gltf_bin_path(path), both written atomically.
void write_gltf(const Mesh& mesh, const std::string& path, const MeshWriteOptions& options);
std::string gltf_bin_path(const std::string& path);

/// Readers parse the whole file held in `data`; `path` only names the file in error messages.
Mesh read_ply(const std::string& path, std::string_view data);
Mesh read_obj(const std::string& path, std::string_view data);
Mesh read_off(const std::string& path, std::string_view data);
Mesh read_stl(const std::string& path, std::string_view data);

/// Collects output in a 1 MiB block and hands full blocks to the stream (one write per block).
class OutBuffer {
 public:
  explicit OutBuffer(std::ostream& os) : os_(os) { buf_.resize(kSize); }
  OutBuffer(const OutBuffer&) = delete;
  OutBuffer& operator=(const OutBuffer&) = delete;

  void put(char c) {
    if (used_ == kSize) drain();
    buf_[used_++] = c;
  }
  void bytes(const void* p, std::size_t n) {
    if (used_ + n > kSize) drain();
    if (n > kSize) {
      os_.write(static_cast<const char*>(p), static_cast<std::streamsize>(n));
      return;
    }
    std::memcpy(buf_.data() + used_, p, n);
    used_ += n;
  }
  void text(std::string_view s) { bytes(s.data(), s.size()); }
  /// Shortest decimal text that reads back to exactly the same float (std::to_chars).
  void number(float v) { format(v); }
  void number(double v) { format(v); }
  void number(std::int64_t v) { format(v); }
  void number(std::uint32_t v) { format(v); }
  void number(std::int32_t v) { format(v); }
  /// Little-endian binary scalar (the host is little-endian; checked in mesh_io.cpp).
  template <class T>
  void binary(T v) {
    bytes(&v, sizeof v);
  }
  /// Writes what is buffered to the stream (call once at the end).
  void drain() {
    if (used_) os_.write(buf_.data(), static_cast<std::streamsize>(used_));
    used_ = 0;
  }

 private:
  static constexpr std::size_t kSize = 1 << 20;
  template <class T>
  void format(T v) {
    if (used_ + 64 > kSize) drain();
    auto r = std::to_chars(buf_.data() + used_, buf_.data() + kSize, v);
    used_ = static_cast<std::size_t>(r.ptr - buf_.data());
  }

  std::ostream& os_;
  std::vector<char> buf_;
  std::size_t used_ = 0;
};

/// Lines of a text file, with the 1-based line number for messages. Handles \n and \r\n.
class LineReader {
 public:
  explicit LineReader(std::string_view data) : data_(data) {}
  /// Next line without its terminator; false at the end of the data.
  bool next(std::string_view& line) {
    if (pos_ >= data_.size()) return false;
    const std::size_t end = data_.find('\n', pos_);
    const std::size_t stop = end == std::string_view::npos ? data_.size() : end;
    line = data_.substr(pos_, stop - pos_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = end == std::string_view::npos ? data_.size() : stop + 1;
    ++line_no_;
    return true;
  }
  std::size_t line_no() const { return line_no_; }
  std::size_t offset() const { return pos_; }

 private:
  std::string_view data_;
  std::size_t pos_ = 0;
  std::size_t line_no_ = 0;
};

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

/// Splits off the next whitespace-separated token of `s` (empty when none is left).
inline std::string_view next_token(std::string_view& s) {
  std::size_t i = 0;
  while (i < s.size() && is_space(s[i])) ++i;
  std::size_t j = i;
  while (j < s.size() && !is_space(s[j])) ++j;
  const std::string_view tok = s.substr(i, j - i);
  s.remove_prefix(j);
  return tok;
}

/// Parses a whole token as a number; false if the token is not exactly one number.
/// Floats are parsed directly in the target precision so text written by OutBuffer round-trips.
template <class T>
inline bool parse_number(std::string_view tok, T& out) {
  if (tok.empty()) return false;
  const char* b = tok.data();
  const char* e = b + tok.size();
  if (*b == '+' && tok.size() > 1) ++b;  // from_chars does not take a leading '+'
  auto r = std::from_chars(b, e, out);
  if (r.ec == std::errc::result_out_of_range) {
    if constexpr (std::is_floating_point_v<T>) {  // under/overflow: fall back to strtod's rounding
      out = static_cast<T>(std::strtod(std::string(tok).c_str(), nullptr));
      return true;
    }
    return false;
  }
  return r.ec == std::errc() && r.ptr == e;
}

/// "<path>: <what>" as Error(invalid_input).
[[noreturn]] inline void bad_mesh(const std::string& path, const std::string& what) {
  fail_input(path, what);
}

}  // namespace adamesh::detail::meshfmt
