// NRRD reader (.nrrd with attached data, .nhdr with detached data), following the NRRD file
// format specification version 5 (teem.sourceforge.net/nrrd/format.html).
//
// Supported: magic NRRD0001..NRRD0005; every type spelling of the spec except 64-bit integers
// and "block"; encodings raw, gzip (gz) and text (txt, ascii); both endiannesses; "data file"
// as a single name, a printf pattern ("quarter.%d 1 93 1 [subdim]") or LIST; line skip and byte
// skip (-1 = data at the end of a raw file; for gzip, bytes skipped after decompression);
// "space directions"/"space origin" (any space, including 3D-left-handed: the file's world
// frame is kept), "spacings"; 4-D arrays whose extra axes have size 1. Unsupported (clear
// error, Status::unsupported): bzip2 and hex encodings, 64-bit integers, block type, more than
// three axes of size > 1, fewer than three axes.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "adamesh/error.h"
#include "io_util.h"
#include "volume_readers.h"

namespace adamesh::detail {
namespace {

constexpr std::size_t kMaxHeader = std::size_t(16) << 20;

struct Header {
  std::vector<std::pair<std::string, std::string>> fields;  // lower-case key, value
  std::vector<std::string> list_files;                        // after "data file: LIST"
  std::uint64_t data_start = 0;                               // attached data offset
  bool has_blank_line = false;
};

// Splits the header text into fields; stops at the first blank line.
Header parse_header(const InputFile& f) {
  std::string text = f.read_string(0, 1 << 16);
  Header h;
  for (;;) {
    const std::size_t a = text.find("\n\n"), b = text.find("\n\r\n");
    const std::size_t end = std::min(a, b);
    if (end != std::string::npos) {
      h.has_blank_line = true;
      h.data_start = end + (end == a ? 2 : 3);
      text.resize(end + 1);
      break;
    }
    if (text.size() >= f.size()) break;  // whole file is header (detached)
    if (text.size() >= kMaxHeader)
      fail_input(f.path(), "header longer than 16 MiB (missing blank line after the header?)");
    text = f.read_string(0, std::min<std::size_t>(text.size() * 4, kMaxHeader));
  }
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  if (line.rfind("NRRD000", 0) != 0) fail_input(f.path(), "not a NRRD file (missing NRRD000x magic)");
  if (line.size() < 8 || line[7] < '1' || line[7] > '5')
    fail(Status::unsupported, f.path() + ": unsupported NRRD version '" + std::string(trim(line)) + "'");
  bool in_list = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (in_list) {
      const std::string_view name = trim(line);
      if (!name.empty()) h.list_files.emplace_back(name);
      continue;
    }
    if (line.empty() || line[0] == '#') continue;
    if (line.find(":=") != std::string::npos &&
        line.find(":=") < line.find(": ")) continue;  // key/value pair, not a field
    std::size_t colon = line.find(": ");
    if (colon == std::string::npos) colon = line.find(':');
    if (colon == std::string::npos)
      fail_input(f.path(), "malformed header line '" + line.substr(0, 60) + "'");
    std::string key = to_lower(trim(std::string_view(line).substr(0, colon)));
    std::string value(trim(std::string_view(line).substr(colon + 1)));
    if (key == "datafile") key = "data file";
    if (key == "lineskip") key = "line skip";
    if (key == "byteskip") key = "byte skip";
    if (key == "data file" && split_ws(value).size() >= 1 && split_ws(value)[0] == "LIST")
      in_list = true;
    h.fields.emplace_back(std::move(key), std::move(value));
  }
  return h;
}

const std::string* field(const Header& h, const char* key) {
  for (const auto& [k, v] : h.fields)
    if (k == key) return &v;
  return nullptr;
}

ScalarType parse_type(const std::string& path, const std::string& spelled) {
  std::string t;
  for (const auto& tok : split_ws(to_lower(spelled))) t += (t.empty() ? "" : " ") + tok;
  if (t == "block") fail(Status::unsupported, path + ": NRRD type 'block' is not supported");
  static const char* int64_names[] = {"longlong", "long long", "long long int", "signed long long",
                                      "signed long long int", "int64", "int64_t", "ulonglong",
                                      "unsigned long long", "unsigned long long int", "uint64",
                                      "uint64_t"};
  for (const char* n : int64_names)
    if (t == n) fail(Status::unsupported, path + ": 64-bit integer samples ('" + spelled + "') are not supported");
  if (t == "char") fail_input(path, "NRRD type 'char' is ambiguous (use 'signed char' or 'uchar')");
  if (auto st = parse_scalar_type(t)) return *st;
  fail_input(path, "unknown NRRD type '" + spelled + "'");
}

// "(1,0,0) (0,1,0) none (0,0,2.5)" -> vectors (empty optional for "none").
std::vector<std::optional<Vec3>> parse_vectors(const std::string& path, const std::string& s,
                                               const char* what) {
  std::vector<std::optional<Vec3>> out;
  std::size_t i = 0;
  while (i < s.size()) {
    if (std::isspace(static_cast<unsigned char>(s[i]))) {
      ++i;
      continue;
    }
    if (s.compare(i, 4, "none") == 0) {
      out.emplace_back();
      i += 4;
      continue;
    }
    if (s[i] != '(') fail_input(path, std::string("malformed ") + what + " '" + s + "'");
    const std::size_t close = s.find(')', i);
    if (close == std::string::npos) fail_input(path, std::string("malformed ") + what + " '" + s + "'");
    std::string inner = s.substr(i + 1, close - i - 1);
    for (char& c : inner)
      if (c == ',') c = ' ';
    const auto v = parse_doubles(inner, 3, path, what);
    out.emplace_back(Vec3{v[0], v[1], v[2]});
    i = close + 1;
  }
  return out;
}

}  // namespace

Volume read_nrrd(const std::string& path) {
  const InputFile file(path);
  const Header h = parse_header(file);
  auto required = [&](const char* key) -> const std::string& {
    const std::string* v = field(h, key);
    if (!v) fail_input(path, std::string("missing required field '") + key + "'");
    return *v;
  };

  const ScalarType type = parse_type(path, required("type"));
  const std::int64_t dimension = parse_int(required("dimension"), path, "dimension");
  if (dimension < 1 || dimension > 16) fail_input(path, "invalid dimension " + std::to_string(dimension));
  const auto sizes = parse_ints(required("sizes"), static_cast<std::size_t>(dimension), path, "sizes");
  for (auto s : sizes)
    if (s < 1) fail_input(path, "invalid sizes '" + required("sizes") + "' (each must be at least 1)");
  if (dimension < 3)
    fail(Status::unsupported, path + ": " + std::to_string(dimension) +
                                  "-D NRRD: only 3-D volumes are supported");
  std::vector<std::optional<Vec3>> directions;
  if (const std::string* sd = field(h, "space directions")) {
    directions = parse_vectors(path, *sd, "space directions");
    if (static_cast<std::int64_t>(directions.size()) != dimension)
      fail_input(path, "space directions has " + std::to_string(directions.size()) +
                           " entries for " + std::to_string(dimension) + " axes");
  }
  // More than three axes: drop axes of size 1 (they do not change the memory layout),
  // non-spatial ones ("none" direction) first.
  std::vector<int> axes;
  for (int a = 0; a < dimension; ++a) axes.push_back(a);
  for (int pass = 0; pass < 2; ++pass) {
    for (int a = static_cast<int>(dimension) - 1; a >= 0 && axes.size() > 3; --a) {
      const bool spatial = !directions.empty() && directions[a].has_value();
      if (sizes[a] == 1 && (pass == 1 || !spatial)) axes.erase(std::find(axes.begin(), axes.end(), a));
    }
  }
  if (axes.size() > 3)
    fail(Status::unsupported, path + ": NRRD with sizes '" + required("sizes") +
                                  "' has more than three axes of size > 1: only scalar 3-D volumes are supported");

  Grid grid;
  for (int k = 0; k < 3; ++k) grid.dims[k] = sizes[axes[k]];

  // World space: space directions (+ space origin), else spacings.
  if (!directions.empty()) {
    Vec3 cols[3];
    for (int k = 0; k < 3; ++k) {
      if (!directions[axes[k]])
        fail_input(path, "space directions: spatial axis " + std::to_string(axes[k]) + " is 'none'");
      cols[k] = *directions[axes[k]];
    }
    set_axes_from_vectors(grid, cols[0], cols[1], cols[2], path, "space directions");
  } else if (const std::string* sp = field(h, "spacings")) {
    const auto toks = split_ws(*sp);
    if (static_cast<std::int64_t>(toks.size()) != dimension)
      fail_input(path, "spacings has " + std::to_string(toks.size()) + " values for " +
                           std::to_string(dimension) + " axes");
    for (int k = 0; k < 3; ++k) {
      const std::string& t = toks[axes[k]];
      const double s = to_lower(t) == "nan" ? std::nan("") : parse_double(t, path, "spacings");
      if (std::isnan(s)) continue;  // unknown spacing: 1
      if (!std::isfinite(s) || s == 0) fail_input(path, "invalid spacing '" + t + "'");
      grid.spacing[k] = std::abs(s);
      if (s < 0) grid.direction.m[k][k] = -1;
    }
  }
  if (const std::string* so = field(h, "space origin")) {
    const auto o = parse_vectors(path, *so, "space origin");
    if (o.size() != 1 || !o[0]) fail_input(path, "malformed space origin '" + *so + "'");
    grid.origin = *o[0];
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(grid.origin[k])) fail_input(path, "non-finite space origin '" + *so + "'");
  }

  // Encoding and byte order.
  const std::string enc_name = field(h, "encoding") ? to_lower(required("encoding")) : "";
  if (enc_name.empty()) fail_input(path, "missing required field 'encoding'");
  DataEncoding enc;
  if (enc_name == "raw") enc = DataEncoding::raw;
  else if (enc_name == "gzip" || enc_name == "gz") enc = DataEncoding::gzip;
  else if (enc_name == "text" || enc_name == "txt" || enc_name == "ascii") enc = DataEncoding::ascii;
  else if (enc_name == "bzip2" || enc_name == "bz2" || enc_name == "hex")
    fail(Status::unsupported, path + ": NRRD encoding '" + enc_name + "' is not supported (raw, gzip and text are)");
  else fail_input(path, "unknown NRRD encoding '" + enc_name + "'");
  bool big_endian = false;
  if (const std::string* e = field(h, "endian")) {
    const std::string en = to_lower(*e);
    if (en != "little" && en != "big") fail_input(path, "invalid endian '" + *e + "'");
    big_endian = en == "big";
  } else if (scalar_size(type) > 1 && enc != DataEncoding::ascii) {
    fail_input(path, std::string("missing 'endian' field (required for ") + to_string(type) + " data)");
  }

  std::int64_t line_skip = 0, byte_skip = 0;
  if (const std::string* ls = field(h, "line skip")) line_skip = parse_int(*ls, path, "line skip");
  if (const std::string* bs = field(h, "byte skip")) byte_skip = parse_int(*bs, path, "byte skip");
  if (line_skip < 0) fail_input(path, "invalid line skip " + std::to_string(line_skip));

  // Data pieces: the header file itself, or the detached file(s).
  std::vector<DataPiece> pieces;
  std::int64_t subdim = -1;
  if (const std::string* df = field(h, "data file")) {
    const auto toks = split_ws(*df);
    if (toks.empty()) fail_input(path, "empty 'data file' field");
    if (toks[0] == "LIST") {
      if (toks.size() > 2) fail_input(path, "malformed data file '" + *df + "'");
      if (toks.size() == 2) subdim = parse_int(toks[1], path, "data file LIST subdim");
      for (const auto& name : h.list_files) pieces.emplace_back(resolve_relative(path, name));
      if (pieces.empty()) fail_input(path, "data file: LIST names no files");
    } else if (toks.size() >= 4 && toks[0].find('%') != std::string::npos) {
      if (toks.size() > 5) fail_input(path, "malformed data file '" + *df + "'");
      const std::int64_t lo = parse_int(toks[1], path, "data file min");
      const std::int64_t hi = parse_int(toks[2], path, "data file max");
      const std::int64_t step = parse_int(toks[3], path, "data file step");
      if (toks.size() == 5) subdim = parse_int(toks[4], path, "data file subdim");
      for (const auto& name : expand_file_pattern(toks[0], lo, hi, step, path, "data file"))
        pieces.emplace_back(resolve_relative(path, name));
    } else {
      if (toks.size() != 1) fail_input(path, "malformed data file '" + *df + "'");
      pieces.emplace_back(resolve_relative(path, toks[0]));
    }
  } else {
    if (!h.has_blank_line) fail_input(path, "truncated data: no blank line ends the header");
    pieces.emplace_back(path, h.data_start);
  }

  const std::size_t total = checked_volume_bytes(grid.dims, type, path);
  if (subdim >= 0) {
    std::int64_t files = 1;
    for (std::int64_t a = subdim; a < dimension && a >= 0; ++a) files *= sizes[a];
    if (subdim < 1 || subdim > dimension || files != static_cast<std::int64_t>(pieces.size()))
      fail_input(path, "data file subdim " + std::to_string(subdim) + " does not match " +
                           std::to_string(pieces.size()) + " data files");
  }
  const std::size_t samples = total / scalar_size(type);
  if (samples % pieces.size() != 0)
    fail_input(path, std::to_string(pieces.size()) + " data files do not divide " +
                         std::to_string(samples) + " samples evenly");
  const std::size_t per_piece = total / pieces.size();
  for (auto& p : pieces) {
    p.line_skip = line_skip;
    p.byte_skip = byte_skip;
    check_data_piece(path, p, enc, type, per_piece);  // before allocating
  }
  Volume v = allocate_volume(grid, type, path);
  v.format = "NRRD";
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    read_data_piece(path, pieces[i], enc, type, v.data.data() + i * per_piece, per_piece);
  }
  if (enc != DataEncoding::ascii) fix_byte_order(v, big_endian);
  return v;
}

}  // namespace adamesh::detail
