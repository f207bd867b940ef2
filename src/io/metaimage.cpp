// MetaImage reader (.mhd header + data file, .mha with LOCAL data), following the MetaIO
// documentation (itk.org/Wiki/ITK/MetaIO/Documentation) and ITK's MetaImageIO conventions.
//
// "Key = Value" lines up to ElementDataFile (keys matched case-insensitively). Supported:
// ObjectType Image or absent; NDims 3 (or more when the extra sizes are 1); ElementType
// MET_(U)CHAR, MET_(U)SHORT, MET_(U)INT, MET_FLOAT, MET_DOUBLE; ElementNumberOfChannels 1;
// ElementSpacing (else ElementSize); Offset / Origin / Position; TransformMatrix / Rotation /
// Orientation (consecutive triples are the world directions of the index axes, as ITK reads
// them); ElementByteOrderMSB / BinaryDataByteOrderMSB; BinaryData False (ASCII samples);
// CompressedData True (zlib or gzip stream to the end of the file; CompressedDataSize is
// ignored as real files get it wrong); HeaderSize (-1: data
// at the end of the file); ElementDataFile LOCAL, a file name, LIST [subdim] with one name per
// following line, or a printf pattern "name%03d.raw min max step [subdim]".
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
  std::vector<std::string> list_files;
  std::uint64_t data_start = 0;  // offset after the ElementDataFile line
};

Header parse_header(const InputFile& f) {
  std::string text = f.read_string(0, 1 << 16);
  Header h;
  std::size_t pos = 0;
  bool found_data_file = false, in_list = false;
  for (;;) {
    const std::size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) {
      if (text.size() < f.size() && text.size() < kMaxHeader) {  // read more, keep parsing
        text = f.read_string(0, std::min<std::size_t>(text.size() * 4, kMaxHeader));
        continue;
      }
      if (text.size() >= kMaxHeader) fail_input(f.path(), "header longer than 16 MiB");
    }
    const std::size_t end = nl == std::string::npos ? text.size() : nl;
    std::string_view line = trim(std::string_view(text).substr(pos, end - pos));
    pos = nl == std::string::npos ? text.size() : nl + 1;
    if (in_list) {
      // LIST: the rest of the file names the data files, one per line.
      if (!line.empty()) h.list_files.emplace_back(line);
      if (pos >= text.size()) break;
      continue;
    }
    if (!line.empty()) {
      const std::size_t eq = line.find('=');
      if (eq == std::string::npos) {
        if (h.fields.empty()) fail_input(f.path(), "not a MetaImage header (no 'Key = Value' line)");
        fail_input(f.path(), "malformed header line '" + std::string(line.substr(0, 60)) + "'");
      }
      std::string key = to_lower(trim(line.substr(0, eq)));
      std::string value(trim(line.substr(eq + 1)));
      if (key == "elementdatafile") {
        found_data_file = true;
        h.data_start = pos;
        in_list = split_ws(value).size() >= 1 && split_ws(value)[0] == "LIST";
      }
      h.fields.emplace_back(std::move(key), std::move(value));
      if (found_data_file && !in_list) break;
    }
    if (pos >= text.size()) break;
  }
  if (h.fields.empty()) fail_input(f.path(), "not a MetaImage header (no 'Key = Value' line)");
  if (!found_data_file) fail_input(f.path(), "missing required field 'ElementDataFile'");
  return h;
}

const std::string* field(const Header& h, const char* key) {
  for (const auto& [k, v] : h.fields)
    if (k == key) return &v;
  return nullptr;
}

bool parse_bool(const std::string& path, const std::string& v, const char* name) {
  const std::string l = to_lower(v);
  if (l == "true" || l == "1") return true;
  if (l == "false" || l == "0") return false;
  fail_input(path, std::string("invalid ") + name + " '" + v + "' (expected True or False)");
}

ScalarType parse_element_type(const std::string& path, const std::string& t) {
  static const std::pair<const char*, ScalarType> types[] = {
      {"MET_UCHAR", ScalarType::u8},  {"MET_CHAR", ScalarType::i8},   {"MET_USHORT", ScalarType::u16},
      {"MET_SHORT", ScalarType::i16}, {"MET_UINT", ScalarType::u32},  {"MET_INT", ScalarType::i32},
      {"MET_FLOAT", ScalarType::f32}, {"MET_DOUBLE", ScalarType::f64}};
  for (const auto& [name, type] : types)
    if (t == name) return type;
  if (t.rfind("MET_", 0) == 0)
    fail(Status::unsupported, path + ": ElementType " + t + " is not supported");
  fail_input(path, "unknown ElementType '" + t + "'");
}

}  // namespace

Volume read_metaimage(const std::string& path) {
  const InputFile file(path);
  const Header h = parse_header(file);
  auto required = [&](const char* key, const char* name) -> const std::string& {
    const std::string* v = field(h, key);
    if (!v) fail_input(path, std::string("missing required field '") + name + "'");
    return *v;
  };
  if (const std::string* ot = field(h, "objecttype"); ot && to_lower(*ot) != "image")
    fail(Status::unsupported, path + ": ObjectType " + *ot + " is not supported (only Image)");
  const std::int64_t ndims = parse_int(required("ndims", "NDims"), path, "NDims");
  if (ndims < 3 || ndims > 16)
    fail(Status::unsupported, path + ": NDims " + std::to_string(ndims) + ": only 3-D images are supported");
  const auto size = parse_ints(required("dimsize", "DimSize"), std::size_t(ndims), path, "DimSize");
  for (auto s : size)
    if (s < 1) fail_input(path, "invalid DimSize '" + required("dimsize", "DimSize") + "' (each must be at least 1)");
  for (std::int64_t a = 3; a < ndims; ++a)
    if (size[a] != 1)
      fail(Status::unsupported, path + ": " + std::to_string(ndims) + "-D image with DimSize '" +
                                    required("dimsize", "DimSize") + "': only 3-D images are supported");
  const ScalarType type = parse_element_type(path, required("elementtype", "ElementType"));
  if (const std::string* ch = field(h, "elementnumberofchannels")) {
    const std::int64_t n = parse_int(*ch, path, "ElementNumberOfChannels");
    if (n != 1) fail(Status::unsupported, path + ": " + std::to_string(n) + " channels per voxel: only scalar images are supported");
  }

  Grid grid;
  for (int a = 0; a < 3; ++a) grid.dims[a] = size[a];
  const std::string* sp = field(h, "elementspacing");
  if (!sp) sp = field(h, "elementsize");
  if (sp) {
    const auto s = parse_doubles(*sp, std::size_t(ndims), path, "ElementSpacing");
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(s[a]) || s[a] <= 0) fail_input(path, "invalid ElementSpacing '" + *sp + "'");
      grid.spacing[a] = s[a];
    }
  }
  for (const char* key : {"offset", "origin", "position"}) {
    if (const std::string* o = field(h, key)) {
      const auto v = parse_doubles(*o, std::size_t(ndims), path, "Offset");
      for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(v[a])) fail_input(path, "non-finite Offset '" + *o + "'");
        grid.origin[a] = v[a];
      }
      break;
    }
  }
  for (const char* key : {"transformmatrix", "rotation", "orientation"}) {
    if (const std::string* m = field(h, key)) {
      const auto v = parse_doubles(*m, std::size_t(ndims * ndims), path, "TransformMatrix");
      Vec3 cols[3];
      for (int c = 0; c < 3; ++c) cols[c] = {v[c * ndims], v[c * ndims + 1], v[c * ndims + 2]};
      const Vec3 spacing = grid.spacing;
      set_axes_from_vectors(grid, cols[0], cols[1], cols[2], path, "TransformMatrix");
      grid.spacing = spacing;  // the matrix holds directions only
      break;
    }
  }

  bool big_endian = false;
  if (const std::string* msb = field(h, "elementbyteordermsb"))
    big_endian = parse_bool(path, *msb, "ElementByteOrderMSB");
  else if (const std::string* bmsb = field(h, "binarydatabyteordermsb"))
    big_endian = parse_bool(path, *bmsb, "BinaryDataByteOrderMSB");
  const bool binary = field(h, "binarydata") ? parse_bool(path, *field(h, "binarydata"), "BinaryData") : true;
  const bool compressed =
      field(h, "compresseddata") ? parse_bool(path, *field(h, "compresseddata"), "CompressedData") : false;
  DataEncoding enc = binary ? DataEncoding::raw : DataEncoding::ascii;
  if (compressed) enc = DataEncoding::zlib_or_gzip;
  // CompressedDataSize is not used as a bound: real files get it wrong (frogtissue.mhd says
  // 260020 bytes, its zlib stream is 262087 bytes long). The stream runs to the file's end and
  // must inflate to exactly the image size.
  std::int64_t header_size = 0;
  if (const std::string* hs = field(h, "headersize")) header_size = parse_int(*hs, path, "HeaderSize");

  // Data pieces.
  const std::string& df = required("elementdatafile", "ElementDataFile");
  const auto toks = split_ws(df);
  std::vector<DataPiece> pieces;
  std::int64_t subdim = -1;
  if (toks.empty()) fail_input(path, "empty ElementDataFile");
  if (toks[0] == "LOCAL") {
    pieces.emplace_back(path, h.data_start);
  } else if (toks[0] == "LIST") {
    if (toks.size() > 2) fail_input(path, "malformed ElementDataFile '" + df + "'");
    if (toks.size() == 2) subdim = parse_int(toks[1], path, "ElementDataFile LIST subdim");
    for (const auto& name : h.list_files) pieces.emplace_back(resolve_relative(path, name));
    if (pieces.empty()) fail_input(path, "ElementDataFile = LIST names no files");
  } else if (toks.size() >= 4 && toks.size() <= 5 && toks[0].find('%') != std::string::npos) {
    const std::int64_t lo = parse_int(toks[1], path, "ElementDataFile min");
    const std::int64_t hi = parse_int(toks[2], path, "ElementDataFile max");
    const std::int64_t step = parse_int(toks[3], path, "ElementDataFile step");
    if (toks.size() == 5) subdim = parse_int(toks[4], path, "ElementDataFile subdim");
    for (const auto& name : expand_file_pattern(toks[0], lo, hi, step, path, "ElementDataFile"))
      pieces.emplace_back(resolve_relative(path, name));
  } else {
    pieces.emplace_back(resolve_relative(path, df));  // a single name (may contain spaces)
  }

  const std::size_t total = checked_volume_bytes(grid.dims, type, path);
  const std::size_t samples = total / scalar_size(type);
  if (subdim >= 0) {
    std::int64_t files = 1;
    for (std::int64_t a = subdim; a < ndims && a >= 0; ++a) files *= size[a];
    if (subdim < 1 || subdim > ndims || files != static_cast<std::int64_t>(pieces.size()))
      fail_input(path, "ElementDataFile subdim " + std::to_string(subdim) + " does not match " +
                           std::to_string(pieces.size()) + " data files");
  }
  if (samples % pieces.size() != 0)
    fail_input(path, std::to_string(pieces.size()) + " data files do not divide " +
                         std::to_string(samples) + " samples evenly");
  const std::size_t per_piece = total / pieces.size();
  for (auto& p : pieces) {
    p.byte_skip = header_size;
    check_data_piece(path, p, enc, type, per_piece);
  }
  Volume v = allocate_volume(grid, type, path);
  v.format = "MetaImage";
  for (std::size_t i = 0; i < pieces.size(); ++i)
    read_data_piece(path, pieces[i], enc, type, v.data.data() + i * per_piece, per_piece);
  if (enc != DataEncoding::ascii) fix_byte_order(v, big_endian);
  return v;
}

}  // namespace adamesh::detail
