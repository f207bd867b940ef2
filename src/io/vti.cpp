// VTK XML ImageData reader (.vti), following "VTK File Formats" (XML formats: VTKFile,
// ImageData, Piece, PointData, DataArray, AppendedData) as written by vtkXMLWriter.
//
// Supported: byte_order LittleEndian/BigEndian; header_type UInt32 (default) or UInt64;
// compressor none or vtkZLibDataCompressor (block header [nblocks, blocksize, lastsize,
// csize...]); DataArray format ascii, binary (inline base64; the header may be encoded
// separately from the data or together with it — the decoder accepts '=' padding between the
// two) and appended (AppendedData encoding raw or base64, with `offset`); WholeExtent with any
// start (a non-zero start shifts the origin), Origin, Spacing and Direction (row-major 3x3,
// columns = world directions of i, j, k). The array read is the PointData array named by its
// Scalars attribute, else the first PointData DataArray; it must have one component. The XML
// part is parsed with pugixml; appended binary data is never handed to the XML parser.
// Unsupported (Status::unsupported): other dataset types, several pieces, other compressors,
// 64-bit integer arrays, multi-component arrays, CellData-only files.
#include <pugixml.hpp>

#include <cmath>
#include <cstring>
#include <functional>
#include <sstream>

#include "adamesh/error.h"
#include "io_util.h"
#include "volume_readers.h"

namespace adamesh::detail {
namespace {

// Position of `needle` in the file, or npos (scans in chunks, no whole-file copy).
std::uint64_t find_in_file(const InputFile& f, const std::string& needle) {
  const std::size_t chunk = std::size_t(1) << 20;
  std::uint64_t pos = 0;
  while (pos < f.size()) {
    const std::string s = f.read_string(pos, chunk + needle.size());
    const std::size_t hit = s.find(needle);
    if (hit != std::string::npos) return pos + hit;
    if (s.size() <= needle.size()) break;
    pos += s.size() - needle.size();
  }
  return std::string::npos;
}

std::vector<double> attr_doubles(const std::string& path, const pugi::xml_node& n, const char* name,
                                 std::size_t count, std::vector<double> fallback) {
  const pugi::xml_attribute a = n.attribute(name);
  if (!a) return fallback;
  return parse_doubles(a.value(), count, path, name);
}

ScalarType array_type(const std::string& path, const std::string& t) {
  static const std::pair<const char*, ScalarType> types[] = {
      {"Int8", ScalarType::i8},     {"UInt8", ScalarType::u8},     {"Int16", ScalarType::i16},
      {"UInt16", ScalarType::u16},  {"Int32", ScalarType::i32},    {"UInt32", ScalarType::u32},
      {"Float32", ScalarType::f32}, {"Float64", ScalarType::f64}, {"Char", ScalarType::i8}};
  for (const auto& [name, type] : types)
    if (t == name) return type;
  if (t == "Int64" || t == "UInt64")
    fail(Status::unsupported, path + ": DataArray type " + t + " (64-bit integers) is not supported");
  fail_input(path, "unknown DataArray type '" + t + "'");
}

// Reads header words (UInt32/UInt64 in the file's byte order) from a byte source.
struct WordReader {
  std::function<void(void*, std::size_t)> read;
  std::size_t size;
  bool big_endian;
  std::uint64_t next() {
    std::uint8_t b[8] = {};
    read(b, size);
    if (big_endian != !host_is_little_endian()) swap_bytes_in_place(b, 1, size);
    if (size == 4) {
      std::uint32_t v;
      std::memcpy(&v, b, 4);
      return v;
    }
    std::uint64_t v;
    std::memcpy(&v, b, 8);
    return v;
  }
};

struct BlockHeader {
  std::uint64_t block_size = 0, last_size = 0;
  std::vector<std::uint64_t> csize;
  std::uint64_t compressed_total = 0;
};

// [nblocks, blocksize, lastsize, csize...]; checks it describes exactly `expected` bytes and
// that the compressed sizes fit in `available` bytes.
BlockHeader read_block_header(const std::string& path, WordReader& w, std::uint64_t expected,
                              std::uint64_t available) {
  BlockHeader h;
  const std::uint64_t nblocks = w.next();
  h.block_size = w.next();
  h.last_size = w.next();
  // The full blocks before the last one must fit in the extent: bounding (nblocks - 1) by
  // expected / block_size first keeps (nblocks - 1) * block_size from wrapping around.
  if (nblocks > available || (nblocks > 0 && h.block_size == 0) || h.last_size > h.block_size ||
      (nblocks > 1 && (h.block_size > expected || nblocks - 1 > expected / h.block_size)))
    fail_input(path, "corrupt compression header (" + std::to_string(nblocks) + " blocks of " +
                         std::to_string(h.block_size) + " bytes, last " +
                         std::to_string(h.last_size) + ", the extent needs " +
                         std::to_string(expected) + ")");
  const std::uint64_t total =
      nblocks == 0 ? 0 : (nblocks - 1) * h.block_size + (h.last_size ? h.last_size : h.block_size);
  if (total != expected)
    fail_input(path, "compression header describes " + std::to_string(total) + " bytes, the extent needs " +
                         std::to_string(expected));
  h.csize.resize(static_cast<std::size_t>(nblocks));
  for (auto& c : h.csize) {
    c = w.next();
    h.compressed_total += c;
    if (c > available || h.compressed_total > available)
      fail_input(path, "truncated compressed data: blocks need more bytes than the file has");
  }
  return h;
}

// Inflates the blocks (fetched one at a time by `fetch`) into dst.
void inflate_blocks(const std::string& path, const BlockHeader& h, std::byte* dst,
                    const std::function<void(std::vector<std::uint8_t>&, std::uint64_t)>& fetch) {
  std::vector<std::uint8_t> block;
  std::uint64_t out = 0;
  for (std::size_t b = 0; b < h.csize.size(); ++b) {
    const std::uint64_t size =
        (b + 1 == h.csize.size() && h.last_size) ? h.last_size : h.block_size;
    fetch(block, h.csize[b]);
    inflate_buffer(block.data(), block.size(), dst + out, static_cast<std::size_t>(size), ZWrap::zlib,
                   path + ": block " + std::to_string(b));
    out += size;
  }
}

}  // namespace

Volume read_vti(const std::string& path) {
  const InputFile f(path);
  // Only the XML before <AppendedData> goes to the parser.
  const std::uint64_t appended_at = find_in_file(f, "<AppendedData");
  const std::uint64_t xml_len = appended_at == std::string::npos ? f.size() : appended_at;
  if (xml_len > (std::uint64_t(1) << 34)) fail_input(path, "XML part larger than 16 GiB");
  std::string xml = f.read_string(0, static_cast<std::size_t>(xml_len));
  if (appended_at != std::string::npos) xml += "</VTKFile>";
  pugi::xml_document doc;
  const pugi::xml_parse_result ok = doc.load_buffer_inplace(xml.data(), xml.size());
  if (!ok)
    fail_input(path, std::string("malformed XML: ") + ok.description() + " at byte " + std::to_string(ok.offset));

  const pugi::xml_node root = doc.child("VTKFile");
  if (!root) fail_input(path, "not a VTK XML file (no VTKFile element)");
  if (std::string(root.attribute("type").value()) != "ImageData")
    fail(Status::unsupported, path + ": VTK XML type '" + root.attribute("type").value() +
                                  "' is not supported (only ImageData)");
  const std::string order = root.attribute("byte_order").value();
  if (!order.empty() && order != "LittleEndian" && order != "BigEndian")
    fail_input(path, "invalid byte_order '" + order + "'");
  const bool big_endian = order == "BigEndian";
  const std::string header_type = root.attribute("header_type").value();
  if (!header_type.empty() && header_type != "UInt32" && header_type != "UInt64")
    fail_input(path, "invalid header_type '" + header_type + "'");
  const std::size_t word = header_type == "UInt64" ? 8 : 4;
  const std::string compressor = root.attribute("compressor").value();
  if (!compressor.empty() && compressor != "vtkZLibDataCompressor")
    fail(Status::unsupported, path + ": compressor " + compressor + " is not supported (only vtkZLibDataCompressor)");
  const bool compressed = !compressor.empty();

  const pugi::xml_node image = root.child("ImageData");
  if (!image) fail_input(path, "missing ImageData element");
  std::vector<pugi::xml_node> pieces;
  for (pugi::xml_node p : image.children("Piece")) pieces.push_back(p);
  if (pieces.empty()) fail_input(path, "missing Piece element");
  if (pieces.size() > 1)
    fail(Status::unsupported, path + ": " + std::to_string(pieces.size()) + " pieces: only single-piece .vti files are supported");
  const pugi::xml_node piece = pieces[0];
  const char* extent_text = image.attribute("WholeExtent") ? image.attribute("WholeExtent").value()
                                                           : piece.attribute("Extent").value();
  const auto ext = parse_ints(extent_text, 6, path, "WholeExtent");
  if (piece.attribute("Extent") && parse_ints(piece.attribute("Extent").value(), 6, path, "Extent") != ext)
    fail(Status::unsupported, path + ": the Piece Extent differs from the WholeExtent (partial pieces are not supported)");
  for (auto e : ext)
    if (e < -(std::int64_t(1) << 60) || e > (std::int64_t(1) << 60)) fail_input(path, "WholeExtent out of range");
  Grid grid;
  for (int a = 0; a < 3; ++a) grid.dims[a] = ext[2 * a + 1] - ext[2 * a] + 1;
  const auto origin = attr_doubles(path, image, "Origin", 3, {0, 0, 0});
  const auto spacing = attr_doubles(path, image, "Spacing", 3, {1, 1, 1});
  const auto dir = attr_doubles(path, image, "Direction", 9, {1, 0, 0, 0, 1, 0, 0, 0, 1});
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(spacing[a]) || spacing[a] == 0) fail_input(path, "invalid Spacing " + format_number(spacing[a]));
    if (!std::isfinite(origin[a])) fail_input(path, "non-finite Origin");
  }
  const Vec3 cols[3] = {{dir[0], dir[3], dir[6]}, {dir[1], dir[4], dir[7]}, {dir[2], dir[5], dir[8]}};
  set_axes_from_vectors(grid, cols[0] * spacing[0], cols[1] * spacing[1], cols[2] * spacing[2], path,
                        "Spacing/Direction");
  // Sample (0,0,0) is extent index (x0, y0, z0).
  const Vec3 start{double(ext[0]), double(ext[2]), double(ext[4])};
  grid.origin = Vec3{origin[0], origin[1], origin[2]} + grid.index_to_world_matrix() * start;

  // The scalar array.
  const pugi::xml_node point_data = piece.child("PointData");
  pugi::xml_node array;
  if (point_data) {
    const std::string wanted = point_data.attribute("Scalars").value();
    for (pugi::xml_node a : point_data.children("DataArray"))
      if (!array || (!wanted.empty() && wanted == a.attribute("Name").value() &&
                     wanted != array.attribute("Name").value()))
        array = a;
  }
  if (!array) {
    if (piece.child("CellData").child("DataArray"))
      fail(Status::unsupported, path + ": only CellData arrays: point data is needed");
    fail_input(path, "no PointData DataArray");
  }
  const std::string name = array.attribute("Name").value();
  if (array.attribute("NumberOfComponents") && array.attribute("NumberOfComponents").as_llong() != 1)
    fail(Status::unsupported, path + ": array '" + name + "' has " +
                                  array.attribute("NumberOfComponents").value() + " components: only scalars are supported");
  const ScalarType type = array_type(path, array.attribute("type").value());
  const std::string format = array.attribute("format").value();
  const std::size_t bytes = checked_volume_bytes(grid.dims, type, path);
  const std::size_t count = bytes / scalar_size(type);

  if (format == "ascii") {
    const std::string_view text = array.child_value();
    if (text.size() < count) fail_input(path, "truncated data: array '" + name + "' has too few ASCII values");
    Volume v = allocate_volume(grid, type, path);
    v.format = "VTK XML ImageData";
    AsciiSampleParser parser(type, v.data.data(), count, path);
    parser.feed(text);
    parser.finish("ASCII array data");
    return v;
  }

  // Base64 text (inline, or the appended section) or raw appended bytes.
  std::string appended_text;
  std::string_view b64;
  std::uint64_t raw_at = 0;
  bool raw = false;
  if (format == "binary") {
    b64 = array.child_value();
  } else if (format == "appended") {
    if (appended_at == std::string::npos) fail_input(path, "array '" + name + "' is appended but there is no AppendedData");
    const std::string tag = f.read_string(appended_at, 4096);
    const std::size_t gt = tag.find('>');
    const std::size_t us = tag.find('_', gt == std::string::npos ? tag.size() : gt);
    if (gt == std::string::npos || us == std::string::npos) fail_input(path, "malformed AppendedData element");
    const std::string encoding = tag.find("encoding=\"base64\"") < gt ? "base64" : "raw";
    const std::uint64_t base = appended_at + us + 1;
    const std::int64_t offset = array.attribute("offset").as_llong(-1);
    if (offset < 0) fail_input(path, "array '" + name + "' has no valid offset");
    if (encoding == "raw") {
      raw = true;
      raw_at = base + static_cast<std::uint64_t>(offset);
      require_range(f, raw_at, word, "appended data");
    } else {
      if (base + static_cast<std::uint64_t>(offset) >= f.size()) require_range(f, base + offset, 1, "appended data");
      appended_text = f.read_string(base + static_cast<std::uint64_t>(offset), static_cast<std::size_t>(f.size()));
      const std::size_t end = appended_text.find('<');
      if (end != std::string::npos) appended_text.resize(end);
      b64 = appended_text;
    }
  } else {
    fail_input(path, "unknown DataArray format '" + format + "'");
  }

  // Byte sources: base64 decoder, or the file from raw_at on.
  Base64Decoder decoder(b64, path);
  std::uint64_t raw_pos = raw_at;
  auto read_bytes = [&](void* dst, std::size_t n) {
    if (raw) {
      f.read_exact(raw_pos, dst, n, "appended data");
      raw_pos += n;
    } else {
      decoder.read(dst, n, "binary array data");
    }
  };
  const std::uint64_t available = raw ? f.size() - raw_at : b64.size() / 4 * 3 + 3;
  WordReader words{read_bytes, word, big_endian};

  if (!compressed) {
    const std::uint64_t n = words.next();
    if (n != bytes)
      fail_input(path, "array '" + name + "' holds " + std::to_string(n) + " bytes, the extent needs " + std::to_string(bytes));
    if (available < bytes) fail_input(path, "truncated data: array '" + name + "' needs " + std::to_string(bytes) + " bytes");
    Volume v = allocate_volume(grid, type, path);
    v.format = "VTK XML ImageData";
    read_bytes(v.data.data(), bytes);
    fix_byte_order(v, big_endian);
    return v;
  }
  const BlockHeader h = read_block_header(path, words, bytes, available);
  if (h.compressed_total < (std::uint64_t(1) << 52) && h.compressed_total * 1100 + 1024 * h.csize.size() < bytes)
    fail_input(path, "corrupt compression header: " + std::to_string(h.compressed_total) +
                         " compressed bytes cannot inflate to " + std::to_string(bytes));
  Volume v = allocate_volume(grid, type, path);
  v.format = "VTK XML ImageData";
  inflate_blocks(path, h, v.data.data(), [&](std::vector<std::uint8_t>& block, std::uint64_t n) {
    block.resize(static_cast<std::size_t>(n));
    read_bytes(block.data(), block.size());
  });
  fix_byte_order(v, big_endian);
  return v;
}

}  // namespace adamesh::detail
