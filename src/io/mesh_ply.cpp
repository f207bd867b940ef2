// PLY (Stanford polygon format), http://paulbourke.net/dataformats/ply/
// Writer: binary little-endian (default) or ASCII; vertex x y z float, optional nx ny nz,
// per-vertex attributes as float/int properties, faces as `list uchar int vertex_indices`.
// Reader: ascii / binary_little_endian / binary_big_endian, every scalar type, vertex x y z of any
// numeric type, other scalar vertex properties kept as attributes (float and double -> f32,
// integer types -> i32), list properties and unknown elements skipped, faces with any count and
// index types fan-triangulated. Element counts are checked against the file size before anything
// is allocated.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "io/mesh_formats.h"

namespace adamesh::detail::meshfmt {

// ------------------------------------------------------------------------------------------------
// Writer
// ------------------------------------------------------------------------------------------------

void write_ply(const Mesh& m, std::ostream& os, const MeshWriteOptions& opt) {
  const bool normals = opt.write_normals && !m.normals.empty();
  std::vector<const VertexAttribute*> attrs;
  if (opt.write_attributes)
    for (const auto& a : m.attributes) attrs.push_back(&a);
  const std::size_t nv = m.num_vertices(), nt = m.num_triangles();

  OutBuffer out(os);
  out.text("ply\nformat ");
  out.text(opt.ascii ? "ascii" : "binary_little_endian");
  out.text(" 1.0\ncomment written by adamesh\nelement vertex ");
  out.number(static_cast<std::int64_t>(nv));
  out.text("\nproperty float x\nproperty float y\nproperty float z\n");
  if (normals) out.text("property float nx\nproperty float ny\nproperty float nz\n");
  for (const auto* a : attrs) {
    out.text(a->is_integer() ? "property int " : "property float ");
    out.text(a->name);
    out.put('\n');
  }
  out.text("element face ");
  out.number(static_cast<std::int64_t>(nt));
  // `int` as everyone reads it; `uint` only when indices would not fit (2^31 vertices and up).
  out.text(nv > 0x7fffffffu ? "\nproperty list uchar uint vertex_indices\nend_header\n"
                            : "\nproperty list uchar int vertex_indices\nend_header\n");

  if (opt.ascii) {
    for (std::size_t v = 0; v < nv; ++v) {
      for (int k = 0; k < 3; ++k) {
        if (k) out.put(' ');
        out.number(m.positions[3 * v + k]);
      }
      if (normals)
        for (int k = 0; k < 3; ++k) {
          out.put(' ');
          out.number(m.normals[3 * v + k]);
        }
      for (const auto* a : attrs) {
        out.put(' ');
        if (a->is_integer()) out.number(a->i32[v]);
        else out.number(a->f32[v]);
      }
      out.put('\n');
    }
    for (std::size_t t = 0; t < nt; ++t) {
      out.text("3 ");
      out.number(m.triangles[3 * t]);
      out.put(' ');
      out.number(m.triangles[3 * t + 1]);
      out.put(' ');
      out.number(m.triangles[3 * t + 2]);
      out.put('\n');
    }
  } else {
    char row[4 * 64];
    const std::size_t row_bytes = 4 * (3 + (normals ? 3 : 0) + attrs.size());
    std::vector<char> big(row_bytes);  // rows with many attributes
    char* r = row_bytes <= sizeof row ? row : big.data();
    for (std::size_t v = 0; v < nv; ++v) {
      std::memcpy(r, &m.positions[3 * v], 12);
      std::size_t at = 12;
      if (normals) {
        std::memcpy(r + at, &m.normals[3 * v], 12);
        at += 12;
      }
      for (const auto* a : attrs) {
        if (a->is_integer()) std::memcpy(r + at, &a->i32[v], 4);
        else std::memcpy(r + at, &a->f32[v], 4);
        at += 4;
      }
      out.bytes(r, row_bytes);
    }
    for (std::size_t t = 0; t < nt; ++t) {
      char face[13];
      face[0] = 3;
      std::memcpy(face + 1, &m.triangles[3 * t], 12);  // int (or uint) little-endian
      out.bytes(face, sizeof face);
    }
  }
  out.drain();
}

// ------------------------------------------------------------------------------------------------
// Reader
// ------------------------------------------------------------------------------------------------

namespace {

enum class PlyType : std::uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };

std::optional<PlyType> ply_type(std::string_view s) {
  if (s == "char" || s == "int8") return PlyType::i8;
  if (s == "uchar" || s == "uint8") return PlyType::u8;
  if (s == "short" || s == "int16") return PlyType::i16;
  if (s == "ushort" || s == "uint16") return PlyType::u16;
  if (s == "int" || s == "int32") return PlyType::i32;
  if (s == "uint" || s == "uint32") return PlyType::u32;
  if (s == "float" || s == "float32") return PlyType::f32;
  if (s == "double" || s == "float64") return PlyType::f64;
  return std::nullopt;
}

std::size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::i8: case PlyType::u8: return 1;
    case PlyType::i16: case PlyType::u16: return 2;
    case PlyType::i32: case PlyType::u32: case PlyType::f32: return 4;
    case PlyType::f64: return 8;
  }
  return 8;
}

bool is_float_type(PlyType t) { return t == PlyType::f32 || t == PlyType::f64; }

struct Property {
  std::string name;
  PlyType type = PlyType::f32;
  bool is_list = false;
  PlyType count_type = PlyType::u8;
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> props;
};

enum class Encoding { ascii, binary_le, binary_be };

struct Header {
  Encoding encoding = Encoding::ascii;
  std::vector<Element> elements;
  std::size_t body_offset = 0;
};

Header parse_header(const std::string& path, std::string_view data) {
  LineReader lines(data);
  std::string_view line;
  if (!lines.next(line) || line != "ply") bad_mesh(path, "not a PLY file (first line is not 'ply')");
  Header h;
  bool have_format = false;
  while (true) {
    if (!lines.next(line)) bad_mesh(path, "PLY header has no end_header line");
    const std::string where = "PLY header line " + std::to_string(lines.line_no()) + ": ";
    std::string_view rest = line;
    const std::string_view key = next_token(rest);
    if (key.empty() || key == "comment" || key == "obj_info") continue;
    if (key == "end_header") break;
    if (key == "format") {
      const std::string_view enc = next_token(rest);
      const std::string_view ver = next_token(rest);
      if (enc == "ascii") h.encoding = Encoding::ascii;
      else if (enc == "binary_little_endian") h.encoding = Encoding::binary_le;
      else if (enc == "binary_big_endian") h.encoding = Encoding::binary_be;
      else bad_mesh(path, where + "unknown format '" + std::string(enc) + "'");
      if (ver != "1.0") bad_mesh(path, where + "unsupported version '" + std::string(ver) + "'");
      have_format = true;
    } else if (key == "element") {
      Element e;
      e.name = std::string(next_token(rest));
      if (!parse_number(next_token(rest), e.count) || e.name.empty())
        bad_mesh(path, where + "expected 'element NAME COUNT'");
      h.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (h.elements.empty()) bad_mesh(path, where + "property before any element");
      Property p;
      std::string_view t = next_token(rest);
      if (t == "list") {
        p.is_list = true;
        const auto ct = ply_type(next_token(rest));
        if (!ct || is_float_type(*ct)) bad_mesh(path, where + "bad list count type");
        p.count_type = *ct;
        t = next_token(rest);
      }
      const auto pt = ply_type(t);
      if (!pt) bad_mesh(path, where + "unknown property type '" + std::string(t) + "'");
      p.type = *pt;
      p.name = std::string(next_token(rest));
      if (p.name.empty()) bad_mesh(path, where + "property without a name");
      h.elements.back().props.push_back(std::move(p));
    } else {
      bad_mesh(path, where + "unexpected keyword '" + std::string(key) + "'");
    }
  }
  if (!have_format) bad_mesh(path, "PLY header has no format line");
  h.body_offset = lines.offset();
  return h;
}

/// Binary body: bounds-checked reads with optional byte swapping.
class BinarySource {
 public:
  BinarySource(const std::string& path, std::string_view body, bool swap)
      : path_(path), p_(body.data()), end_(body.data() + body.size()), swap_(swap) {}

  double real(PlyType t) {
    switch (t) {
      case PlyType::f32: return get<float>();
      case PlyType::f64: return get<double>();
      default: return static_cast<double>(integer(t));
    }
  }
  std::int64_t integer(PlyType t) {
    switch (t) {
      case PlyType::i8: return get<std::int8_t>();
      case PlyType::u8: return get<std::uint8_t>();
      case PlyType::i16: return get<std::int16_t>();
      case PlyType::u16: return get<std::uint16_t>();
      case PlyType::i32: return get<std::int32_t>();
      case PlyType::u32: return get<std::uint32_t>();
      case PlyType::f32: return whole(get<float>());
      case PlyType::f64: return whole(get<double>());
    }
    return 0;
  }
  void skip(PlyType t, std::uint64_t n) {
    const std::uint64_t bytes = n * type_size(t);
    if (n > static_cast<std::uint64_t>(end_ - p_) || bytes > static_cast<std::uint64_t>(end_ - p_))
      truncated();
    p_ += bytes;
  }
  std::string where() const { return "element '" + elem + "' row " + std::to_string(row); }
  std::string elem;        ///< element being read (messages only)
  std::uint64_t row = 0;   ///< row being read (messages only)

 private:
  template <class T>
  T get() {
    if (static_cast<std::size_t>(end_ - p_) < sizeof(T)) truncated();
    unsigned char b[sizeof(T)];
    std::memcpy(b, p_, sizeof(T));
    if (swap_) std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    p_ += sizeof(T);
    return v;
  }
  std::int64_t whole(double v) {
    if (!(std::fabs(v) < 9e15) || v != std::floor(v))
      bad_mesh(path_, "expected an integer value in " + where());
    return static_cast<std::int64_t>(v);
  }
  [[noreturn]] void truncated() { bad_mesh(path_, "truncated data in " + where()); }

  const std::string& path_;
  const char* p_;
  const char* end_;
  bool swap_;
};

/// ASCII body: whitespace-separated tokens, line breaks carry no meaning.
class AsciiSource {
 public:
  AsciiSource(const std::string& path, std::string_view body) : path_(path), rest_(body) {}

  double real(PlyType t) {
    const std::string_view tok = token();
    if (t == PlyType::f32) {
      float f = 0;
      if (parse_number(tok, f)) return f;
    } else {
      double d = 0;
      if (parse_number(tok, d)) return d;
    }
    bad_value(tok);
  }
  std::int64_t integer(PlyType) {
    const std::string_view tok = token();
    std::int64_t v = 0;
    if (parse_number(tok, v)) return v;
    double d = 0;  // tolerate "3.0" from writers that print every number as a float
    if (parse_number(tok, d) && std::fabs(d) < 9e15 && d == std::floor(d))
      return static_cast<std::int64_t>(d);
    bad_value(tok);
  }
  void skip(PlyType, std::uint64_t n) {
    for (std::uint64_t i = 0; i < n; ++i) token();
  }
  std::string where() const { return "element '" + elem + "' row " + std::to_string(row); }
  std::string elem;        ///< element being read (messages only)
  std::uint64_t row = 0;   ///< row being read (messages only)

 private:
  std::string_view token() {
    const std::string_view tok = next_token(rest_);
    if (tok.empty()) bad_mesh(path_, "truncated data in " + where());
    return tok;
  }
  [[noreturn]] void bad_value(std::string_view tok) {
    bad_mesh(path_, "bad number '" + std::string(tok.substr(0, 40)) + "' in " + where());
  }

  const std::string& path_;
  std::string_view rest_;
};

enum class Role : std::uint8_t { x, y, z, nx, ny, nz, attribute, skip };

template <class Src>
void read_vertices(const std::string& path, const Element& e, Src& src, Mesh& m) {
  std::vector<Role> roles;
  std::vector<int> attr_of;  // property -> attribute slot
  bool has[6] = {false, false, false, false, false, false};
  static const char* names[6] = {"x", "y", "z", "nx", "ny", "nz"};
  for (const auto& p : e.props) {
    Role r = Role::skip;
    int slot = -1;
    if (!p.is_list) {
      r = Role::attribute;
      for (int k = 0; k < 6; ++k)
        if (p.name == names[k]) {
          r = static_cast<Role>(k);
          has[k] = true;
        }
      if (r == Role::attribute) {
        slot = static_cast<int>(m.attributes.size());
        VertexAttribute a;
        a.name = p.name;
        m.attributes.push_back(std::move(a));
      }
    }
    roles.push_back(r);
    attr_of.push_back(slot);
  }
  if (!has[0] || !has[1] || !has[2]) bad_mesh(path, "PLY vertex element lacks x, y or z");
  const bool normals = has[3] && has[4] && has[5];
  const std::size_t n = static_cast<std::size_t>(e.count);
  m.positions.resize(3 * n);
  if (normals) m.normals.resize(3 * n);
  for (std::size_t i = 0; i < e.props.size(); ++i)
    if (attr_of[i] >= 0) {
      auto& a = m.attributes[attr_of[i]];
      if (is_float_type(e.props[i].type)) a.f32.resize(n);
      else a.i32.resize(n);
    }
  src.elem = e.name;
  for (std::size_t v = 0; v < n; ++v) {
    src.row = v;
    for (std::size_t i = 0; i < e.props.size(); ++i) {
      const Property& p = e.props[i];
      if (p.is_list) {
        const std::int64_t c = src.integer(p.count_type);
        if (c < 0) bad_mesh(path, "negative list length in " + src.where());
        src.skip(p.type, static_cast<std::uint64_t>(c));
        continue;
      }
      const Role r = roles[i];
      if (r == Role::attribute) {
        auto& a = m.attributes[attr_of[i]];
        if (is_float_type(p.type)) a.f32[v] = static_cast<float>(src.real(p.type));
        else a.i32[v] = static_cast<std::int32_t>(src.integer(p.type));
        continue;
      }
      const double val = src.real(p.type);
      const int k = static_cast<int>(r);
      if (k < 3) {
        if (!std::isfinite(val)) bad_mesh(path, "non-finite coordinate in " + src.where());
        m.positions[3 * v + k] = static_cast<float>(val);
      } else if (normals) {
        m.normals[3 * v + (k - 3)] = static_cast<float>(val);
      }
    }
  }
}

template <class Src>
void read_faces(const std::string& path, const Element& e, Src& src, Mesh& m, std::uint64_t nv,
                std::uint64_t max_triangles) {
  int list = -1;
  for (std::size_t i = 0; i < e.props.size(); ++i)
    if (e.props[i].is_list && (e.props[i].name == "vertex_indices" || e.props[i].name == "vertex_index"))
      list = static_cast<int>(i);
  for (std::size_t i = 0; i < e.props.size() && list < 0; ++i)
    if (e.props[i].is_list && !is_float_type(e.props[i].type)) list = static_cast<int>(i);
  if (list < 0) bad_mesh(path, "PLY face element has no vertex_indices list");
  m.triangles.reserve(3 * static_cast<std::size_t>(std::min(e.count, max_triangles)));
  std::vector<std::uint32_t> poly;
  src.elem = e.name;
  for (std::uint64_t f = 0; f < e.count; ++f) {
    src.row = f;
    for (std::size_t i = 0; i < e.props.size(); ++i) {
      const Property& p = e.props[i];
      if (!p.is_list) {
        src.skip(p.type, 1);
        continue;
      }
      const std::int64_t c = src.integer(p.count_type);
      if (c < 0) bad_mesh(path, "negative list length in " + src.where());
      if (static_cast<int>(i) != list) {
        src.skip(p.type, static_cast<std::uint64_t>(c));
        continue;
      }
      if (c < 3) bad_mesh(path, "face with " + std::to_string(c) + " vertices (at least 3 needed) in " + src.where());
      poly.clear();
      for (std::int64_t k = 0; k < c; ++k) {
        const std::int64_t idx = src.integer(p.type);
        if (idx < 0 || static_cast<std::uint64_t>(idx) >= nv)
          bad_mesh(path, "vertex index " + std::to_string(idx) + " out of range (" +
                             std::to_string(nv) + " vertices) in " + src.where());
        poly.push_back(static_cast<std::uint32_t>(idx));
      }
      for (std::size_t k = 1; k + 1 < poly.size(); ++k) m.add_triangle(poly[0], poly[k], poly[k + 1]);
    }
  }
}

template <class Src>
void skip_element(const std::string& path, const Element& e, Src& src) {
  src.elem = e.name;
  for (std::uint64_t r = 0; r < e.count; ++r) {
    src.row = r;
    for (const auto& p : e.props) {
      if (!p.is_list) {
        src.skip(p.type, 1);
        continue;
      }
      const std::int64_t c = src.integer(p.count_type);
      if (c < 0) bad_mesh(path, "negative list length in " + src.where());
      src.skip(p.type, static_cast<std::uint64_t>(c));
    }
  }
}

template <class Src>
Mesh read_body(const std::string& path, const Header& h, Src& src, std::uint64_t nv,
               std::uint64_t max_triangles) {
  Mesh m;
  bool have_vertices = false;
  for (const auto& e : h.elements) {
    if (e.props.empty()) continue;  // nothing to read, whatever the count
    if (e.name == "vertex" && !have_vertices) {
      read_vertices(path, e, src, m);
      have_vertices = true;
    } else if (e.name == "face") {
      read_faces(path, e, src, m, nv, max_triangles);
    } else {
      skip_element(path, e, src);
    }
  }
  if (!have_vertices && nv > 0) bad_mesh(path, "PLY vertex element has no properties");
  return m;
}

}  // namespace

Mesh read_ply(const std::string& path, std::string_view data) {
  const Header h = parse_header(path, data);
  const std::string_view body = data.substr(h.body_offset);
  const bool ascii = h.encoding == Encoding::ascii;

  // Counts against the file size: every row needs at least min_row bytes.
  std::uint64_t nv = 0, max_triangles = 0;
  bool seen_vertex = false;
  long double need = 0;
  for (const auto& e : h.elements) {
    if (e.props.empty()) continue;
    std::uint64_t min_row = 0;
    for (const auto& p : e.props)
      min_row += ascii ? 2 : (p.is_list ? type_size(p.count_type) : type_size(p.type));
    need += static_cast<long double>(e.count) * min_row;
    if (e.name == "vertex" && !seen_vertex) {
      nv = e.count;
      seen_vertex = true;
    }
    if (e.name == "face") {
      std::uint64_t tri_row = 0;  // bytes of a triangle row: 3 indices
      for (const auto& p : e.props)
        tri_row += ascii ? 2 : (p.is_list ? type_size(p.count_type) + 3 * type_size(p.type)
                                          : type_size(p.type));
      max_triangles = body.size() / std::max<std::uint64_t>(tri_row, 1) + 1;
    }
  }
  if (need > static_cast<long double>(body.size()) + 1)
    bad_mesh(path, "element counts need at least " + std::to_string(static_cast<double>(need)) +
                       " bytes but the data has " + std::to_string(body.size()) +
                       " (truncated file or absurd counts)");
  if (nv > 0xffffffffull) bad_mesh(path, "more than 2^32-1 vertices");

  if (ascii) {
    AsciiSource src(path, body);
    return read_body(path, h, src, nv, max_triangles);
  }
  BinarySource src(path, body, h.encoding == Encoding::binary_be);
  return read_body(path, h, src, nv, max_triangles);
}

}  // namespace adamesh::detail::meshfmt
