// VTK legacy reader for DATASET STRUCTURED_POINTS, following "VTK File Formats" (VTK User's
// Guide, simple legacy formats, versions 1.0 to 5.1).
//
// Header: "# vtk DataFile Version x.y", a title line, ASCII or BINARY, DATASET
// STRUCTURED_POINTS, then DIMENSIONS, SPACING (or ASPECT_RATIO, version 1.0), ORIGIN in any
// order; blank lines anywhere between keywords (old files have them). Samples: the first
// SCALARS array of POINT_DATA (one component; LOOKUP_TABLE line optional). Attribute arrays
// before it (VECTORS, NORMALS, TENSORS, TEXTURE_COORDINATES, COLOR_SCALARS, LOOKUP_TABLE,
// FIELD, and any CELL_DATA section) are skipped; everything after it is ignored. BINARY data is
// big-endian. Unsupported (Status::unsupported): other dataset types, multi-component
// SCALARS, "bit", 64-bit and platform-sized integer types.
#include <cmath>
#include <sstream>

#include "adamesh/error.h"
#include "io_util.h"
#include "volume_readers.h"

namespace adamesh::detail {
namespace {

// Reads text lines from a file position (the header lines between binary blocks).
class LineReader {
 public:
  LineReader(const InputFile& f, std::uint64_t pos) : f_(f), pos_(pos) {}
  /// Next line without its end of line; false at the end of the file.
  bool next(std::string& line) {
    line.clear();
    while (pos_ < f_.size()) {
      const std::string chunk = f_.read_string(pos_, 4096);
      const std::size_t nl = chunk.find('\n');
      if (nl == std::string::npos) {
        line += chunk;
        pos_ += chunk.size();
        if (line.size() > (1 << 20)) fail_input(f_.path(), "header line longer than 1 MiB");
        continue;
      }
      line.append(chunk, 0, nl);
      pos_ += nl + 1;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      return true;
    }
    return !line.empty();
  }
  /// Next line with tokens (blank lines skipped); false at the end of the file.
  bool next_tokens(std::vector<std::string>& toks) {
    std::string line;
    while (next(line)) {
      toks = split_ws(line);
      if (!toks.empty()) return true;
    }
    return false;
  }
  std::uint64_t pos() const { return pos_; }
  void seek(std::uint64_t p) { pos_ = p; }

 private:
  const InputFile& f_;
  std::uint64_t pos_;
};

// Size of a VTK legacy data type name (0: unknown or platform-dependent).
std::size_t type_size(const std::string& t) {
  const std::string l = to_lower(t);
  if (l == "unsigned_char" || l == "char" || l == "signed_char") return 1;
  if (l == "short" || l == "unsigned_short") return 2;
  if (l == "int" || l == "unsigned_int" || l == "float") return 4;
  if (l == "double" || l == "vtktypeint64" || l == "vtktypeuint64") return 8;
  return 0;
}

std::optional<ScalarType> scalar_type(const std::string& t) {
  const std::string l = to_lower(t);
  if (l == "unsigned_char") return ScalarType::u8;
  if (l == "char" || l == "signed_char") return ScalarType::i8;
  if (l == "short") return ScalarType::i16;
  if (l == "unsigned_short") return ScalarType::u16;
  if (l == "int") return ScalarType::i32;
  if (l == "unsigned_int") return ScalarType::u32;
  if (l == "float") return ScalarType::f32;
  if (l == "double") return ScalarType::f64;
  return std::nullopt;
}

// Offset after `count` whitespace-separated tokens starting at `pos`.
std::uint64_t skip_tokens(const InputFile& f, std::uint64_t pos, std::uint64_t count) {
  bool in_token = false;
  while (count > 0 || in_token) {
    const std::string chunk = f.read_string(pos, 1 << 16);
    if (chunk.empty()) {
      if (in_token && count == 1) return pos;
      fail_input(f.path(), "truncated data: the file ends inside an ASCII attribute array");
    }
    for (std::size_t i = 0; i < chunk.size(); ++i) {
      const bool space = std::isspace(static_cast<unsigned char>(chunk[i])) != 0;
      if (in_token && space) {
        in_token = false;
        if (--count == 0) return pos + i;
      } else if (!in_token && !space) {
        in_token = true;
      }
    }
    pos += chunk.size();
  }
  return pos;
}

}  // namespace

Volume read_vtk_legacy(const std::string& path) {
  const InputFile f(path);
  LineReader in(f, 0);
  std::string line;
  if (!in.next(line) || line.rfind("# vtk DataFile", 0) != 0)
    fail_input(path, "not a VTK legacy file (missing '# vtk DataFile Version' line)");
  if (!in.next(line)) fail_input(path, "truncated header: no title line");
  std::vector<std::string> toks;
  if (!in.next_tokens(toks)) fail_input(path, "truncated header: missing ASCII/BINARY line");
  const std::string mode = to_lower(toks[0]);
  if (mode != "ascii" && mode != "binary") fail_input(path, "expected ASCII or BINARY, found '" + toks[0] + "'");
  const bool binary = mode == "binary";
  if (!in.next_tokens(toks) || to_lower(toks[0]) != "dataset" || toks.size() < 2)
    fail_input(path, "missing DATASET line");
  if (to_lower(toks[1]) != "structured_points")
    fail(Status::unsupported, path + ": VTK dataset type " + toks[1] + " is not supported (only STRUCTURED_POINTS)");

  Grid grid;
  bool have_dims = false, point_section = false;
  std::int64_t section_count = 0;
  auto vec3 = [&](const char* what) {
    if (toks.size() != 4) fail_input(path, std::string(what) + " needs 3 values");
    return Vec3{parse_double(toks[1], path, what), parse_double(toks[2], path, what),
                parse_double(toks[3], path, what)};
  };
  // Skips `count` values of `type` (binary) or `count` tokens (ASCII) from the reader position.
  auto skip_values = [&](std::uint64_t count, const std::string& type, const char* what) {
    if (binary) {
      const std::size_t sz = type_size(type);
      if (sz == 0) fail(Status::unsupported, path + ": cannot skip " + what + " of type " + type);
      require_range(f, in.pos(), count * sz, what);
      in.seek(in.pos() + count * sz);
    } else {
      in.seek(skip_tokens(f, in.pos(), count));
    }
  };

  // After a SCALARS line: consumes an optional "LOOKUP_TABLE name" line.
  auto skip_lookup_table_line = [&] {
    const std::uint64_t after = in.pos();
    if (binary) {
      if (f.read_string(after, 12) == "LOOKUP_TABLE") in.next(line);
      return;
    }
    std::vector<std::string> look;
    if (!in.next_tokens(look) || to_lower(look[0]) != "lookup_table") in.seek(after);
  };

  for (;;) {
    if (!in.next_tokens(toks)) fail_input(path, "no SCALARS point data found");
    const std::string key = to_lower(toks[0]);
    if (key == "dimensions") {
      if (toks.size() != 4) fail_input(path, "DIMENSIONS needs 3 values");
      for (int a = 0; a < 3; ++a) grid.dims[a] = parse_int(toks[a + 1], path, "DIMENSIONS");
      have_dims = true;
    } else if (key == "spacing" || key == "aspect_ratio") {
      const Vec3 s = vec3(key == "spacing" ? "SPACING" : "ASPECT_RATIO");
      for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(s[a]) || s[a] == 0) fail_input(path, "invalid spacing " + format_number(s[a]));
        grid.spacing[a] = std::abs(s[a]);
        if (s[a] < 0) grid.direction.m[a][a] = -1;
      }
    } else if (key == "origin") {
      grid.origin = vec3("ORIGIN");
      for (int a = 0; a < 3; ++a)
        if (!std::isfinite(grid.origin[a])) fail_input(path, "non-finite ORIGIN");
    } else if (key == "point_data" || key == "cell_data") {
      if (toks.size() < 2) fail_input(path, toks[0] + " needs a count");
      section_count = parse_int(toks[1], path, toks[0]);
      point_section = key == "point_data";
      if (!have_dims) fail_input(path, "missing DIMENSIONS before " + toks[0]);
      if (point_section) {
        checked_volume_bytes(grid.dims, ScalarType::u8, path);
        if (section_count != grid.num_samples())
          fail_input(path, "POINT_DATA " + toks[1] + " does not match DIMENSIONS " + format_dims(grid.dims));
      } else if (section_count < 0) {
        fail_input(path, "invalid CELL_DATA count " + toks[1]);
      }
    } else if (key == "scalars" && point_section) {
      if (toks.size() < 3) fail_input(path, "SCALARS needs a name and a type");
      const auto type = scalar_type(toks[2]);
      if (!type) fail(Status::unsupported, path + ": SCALARS type '" + toks[2] + "' is not supported");
      if (toks.size() >= 4 && parse_int(toks[3], path, "SCALARS components") != 1)
        fail(Status::unsupported, path + ": SCALARS with " + toks[3] + " components: only one is supported");
      skip_lookup_table_line();
      const std::size_t bytes = checked_volume_bytes(grid.dims, *type, path);
      if (binary) {
        require_range(f, in.pos(), bytes, "sample data");
      } else if (f.size() - in.pos() < bytes / scalar_size(*type)) {
        fail_input(path, "truncated ASCII sample data: " + std::to_string(bytes / scalar_size(*type)) +
                             " values cannot fit in the rest of the file");
      }
      Volume v = allocate_volume(grid, *type, path);
      v.format = "VTK legacy";
      if (binary) {
        f.read_exact(in.pos(), v.data.data(), bytes, "sample data");
        fix_byte_order(v, true);
      } else {
        read_ascii_samples(f, in.pos(), *type, v.data.data(), bytes / scalar_size(*type), "sample data");
      }
      return v;
    } else if (key == "scalars" || key == "vectors" || key == "normals" || key == "tensors" ||
               key == "texture_coordinates" || key == "color_scalars" || key == "lookup_table" ||
               key == "field") {
      if (section_count == 0 && key != "field") fail_input(path, toks[0] + " outside POINT_DATA/CELL_DATA");
      const auto n = static_cast<std::uint64_t>(section_count);
      // Value counts of attribute arrays: a negative factor or a product beyond 2^56 (e.g. a
      // LOOKUP_TABLE of 2^62 entries, whose 4*n wraps to 0) is a corrupt header, not an empty array.
      const auto values = [&](std::uint64_t a, std::int64_t b, const std::string& what) {
        constexpr std::uint64_t kMax = std::uint64_t(1) << 56;  // x 8 bytes still fits
        if (b < 0 || a > kMax || (b > 0 && a > kMax / static_cast<std::uint64_t>(b)))
          fail_input(path, "invalid " + what + " size (" + std::to_string(a) + " x " +
                               std::to_string(b) + " values)");
        return a * static_cast<std::uint64_t>(b);
      };
      if (key == "scalars") {  // cell scalars: skip
        if (toks.size() < 3) fail_input(path, "SCALARS needs a name and a type");
        const std::int64_t comps = toks.size() >= 4 ? parse_int(toks[3], path, "SCALARS components") : 1;
        const std::string type = toks[2];
        skip_lookup_table_line();
        skip_values(values(n, comps, "SCALARS"), type, "cell scalars");
      } else if (key == "vectors" || key == "normals" || key == "tensors") {
        if (toks.size() < 3) fail_input(path, toks[0] + " needs a name and a type");
        skip_values(values(n, key == "tensors" ? 9 : 3, toks[0]), toks[2], "attribute array");
      } else if (key == "texture_coordinates") {
        if (toks.size() < 4) fail_input(path, "TEXTURE_COORDINATES needs a name, a dimension and a type");
        skip_values(values(n, parse_int(toks[2], path, "TEXTURE_COORDINATES"), "TEXTURE_COORDINATES"), toks[3], "texture coordinates");
      } else if (key == "color_scalars") {
        if (toks.size() < 3) fail_input(path, "COLOR_SCALARS needs a name and a count");
        skip_values(values(n, parse_int(toks[2], path, "COLOR_SCALARS"), "COLOR_SCALARS"), binary ? "unsigned_char" : "float", "color scalars");
      } else if (key == "lookup_table") {
        if (toks.size() < 3) fail_input(path, "LOOKUP_TABLE needs a name and a size");
        skip_values(values(4, parse_int(toks[2], path, "LOOKUP_TABLE"), "LOOKUP_TABLE"), binary ? "unsigned_char" : "float", "lookup table");
      } else {  // FIELD name numArrays, then per array: name components tuples type + data
        if (toks.size() < 3) fail_input(path, "FIELD needs a name and an array count");
        const std::int64_t arrays = parse_int(toks[2], path, "FIELD");
        for (std::int64_t a = 0; a < arrays; ++a) {
          if (!in.next_tokens(toks) || toks.size() < 4) fail_input(path, "malformed FIELD array header");
          const std::int64_t comps = parse_int(toks[1], path, "FIELD components");
          const std::int64_t tuples = parse_int(toks[2], path, "FIELD tuples");
          if (comps < 0 || tuples < 0) fail_input(path, "malformed FIELD array header");
          skip_values(values(static_cast<std::uint64_t>(comps), tuples, "FIELD array"), toks[3], "field array");
        }
      }
    } else if (key == "metadata") {
      while (in.next(line) && !trim(line).empty()) {}
    } else {
      fail_input(path, "unexpected keyword '" + toks[0] + "' in the header");
    }
  }
}

}  // namespace adamesh::detail
