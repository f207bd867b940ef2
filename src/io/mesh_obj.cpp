// Wavefront OBJ (geometry subset): `v x y z`, `vn x y z`, `f` with 1-based indices.
// Writer: `v`, `vn` when the mesh has normals (one per vertex, same index), `f a b c` or
// `f a//a b//b c//c`. Reader: `v` (extra w/colour values ignored), `f` corners in the forms i,
// i/t, i//n, i/t/n, negative (relative) indices, polygons fan-triangulated; other statements
// (vt, g, o, s, usemtl, l, ...) ignored. Normals are kept only when they map one-to-one onto the
// vertices (every corner uses the same index for v and vn), as this writer produces.
#include <cmath>
#include <cstdio>
#include <limits>

#include "io/mesh_formats.h"

namespace adamesh::detail::meshfmt {

void write_obj(const Mesh& m, std::ostream& os, const MeshWriteOptions& opt) {
  const bool normals = opt.write_normals && !m.normals.empty();
  OutBuffer out(os);
  out.text("# written by adamesh\n");
  const std::size_t nv = m.num_vertices(), nt = m.num_triangles();
  for (std::size_t v = 0; v < nv; ++v) {
    out.text("v ");
    out.number(m.positions[3 * v]);
    out.put(' ');
    out.number(m.positions[3 * v + 1]);
    out.put(' ');
    out.number(m.positions[3 * v + 2]);
    out.put('\n');
  }
  if (normals)
    for (std::size_t v = 0; v < nv; ++v) {
      out.text("vn ");
      out.number(m.normals[3 * v]);
      out.put(' ');
      out.number(m.normals[3 * v + 1]);
      out.put(' ');
      out.number(m.normals[3 * v + 2]);
      out.put('\n');
    }
  for (std::size_t t = 0; t < nt; ++t) {
    out.put('f');
    for (int k = 0; k < 3; ++k) {
      const std::int64_t i = static_cast<std::int64_t>(m.triangles[3 * t + k]) + 1;
      out.put(' ');
      out.number(i);
      if (normals) {
        out.text("//");
        out.number(i);
      }
    }
    out.put('\n');
  }
  out.drain();
}

namespace {

/// One face corner "i", "i/t", "i//n" or "i/t/n": resolves i (and n when present) to 0-based
/// indices. Positive indices are checked against the final counts later (forward references).
struct Corner {
  std::int64_t v = -1;
  std::int64_t n = -1;  ///< -1: no normal index
};

bool parse_index(std::string_view s, std::int64_t count, std::int64_t& out) {
  std::int64_t i = 0;
  if (!parse_number(s, i) || i == 0) return false;
  out = i > 0 ? i - 1 : count + i;  // -1 is the last one defined so far
  return out >= 0;
}

}  // namespace

Mesh read_obj(const std::string& path, std::string_view data) {
  // OBJ is text: a control byte (other than tab, CR, LF, VT, FF) means a binary file named .obj,
  // which would otherwise read as an empty mesh since unknown statements are skipped.
  for (std::size_t i = 0; i < data.size(); ++i) {
    const auto c = static_cast<unsigned char>(data[i]);
    if ((c < 0x20 && c != '\t' && c != '\n' && c != '\r' && c != '\v' && c != '\f') || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", c);
      bad_mesh(path, std::string("not a text OBJ file: control byte ") + hex + " at offset " +
                         std::to_string(i));
    }
  }
  Mesh m;
  std::vector<float> vn;
  bool normals_match = true;  // every corner uses the same v and vn index
  bool any_normal_index = false;
  std::int64_t max_v = -1, max_v_line = 0, max_n = -1;
  std::vector<Corner> poly;
  LineReader lines(data);
  std::string_view line;
  auto where = [&] { return "line " + std::to_string(lines.line_no()); };
  while (lines.next(line)) {
    std::string_view rest = line;
    const std::string_view key = next_token(rest);
    if (key == "v" || key == "vn") {
      float xyz[3];
      for (float& c : xyz) {
        const std::string_view tok = next_token(rest);
        if (!parse_number(tok, c))
          bad_mesh(path, where() + ": expected 3 numbers after '" + std::string(key) + "'");
        if (!std::isfinite(c)) bad_mesh(path, where() + ": non-finite coordinate");
      }
      auto& dst = key == "v" ? m.positions : vn;
      dst.insert(dst.end(), xyz, xyz + 3);
    } else if (key == "f") {
      poly.clear();
      const auto nv_now = static_cast<std::int64_t>(m.positions.size() / 3);
      const auto nn_now = static_cast<std::int64_t>(vn.size() / 3);
      for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
        Corner c;
        const std::size_t s1 = tok.find('/');
        const std::string_view vs = tok.substr(0, s1);
        if (!parse_index(vs, nv_now, c.v))
          bad_mesh(path, where() + ": bad vertex index '" + std::string(vs) + "'");
        if (s1 != std::string_view::npos) {
          const std::size_t s2 = tok.find('/', s1 + 1);
          if (s2 != std::string_view::npos && s2 + 1 < tok.size()) {
            const std::string_view ns = tok.substr(s2 + 1);
            if (!parse_index(ns, nn_now, c.n))
              bad_mesh(path, where() + ": bad normal index '" + std::string(ns) + "'");
            any_normal_index = true;
          }
        }
        if (c.v > max_v) {
          max_v = c.v;
          max_v_line = static_cast<std::int64_t>(lines.line_no());
        }
        max_n = std::max(max_n, c.n);
        if (c.n != c.v) normals_match = false;
        poly.push_back(c);
      }
      if (poly.size() < 3)
        bad_mesh(path, where() + ": face with " + std::to_string(poly.size()) +
                           " vertices (at least 3 needed)");
      if (max_v > static_cast<std::int64_t>(std::numeric_limits<std::uint32_t>::max()) - 1)
        bad_mesh(path, where() + ": vertex index too large");
      for (std::size_t k = 1; k + 1 < poly.size(); ++k)
        m.add_triangle(static_cast<std::uint32_t>(poly[0].v), static_cast<std::uint32_t>(poly[k].v),
                       static_cast<std::uint32_t>(poly[k + 1].v));
    }
    // Everything else (comments, vt, groups, materials, lines, points) is ignored.
  }
  const auto nv = static_cast<std::int64_t>(m.num_vertices());
  if (max_v >= nv)
    bad_mesh(path, "line " + std::to_string(max_v_line) + ": vertex index " +
                       std::to_string(max_v + 1) + " out of range (" + std::to_string(nv) +
                       " vertices)");
  if (max_n >= static_cast<std::int64_t>(vn.size() / 3))
    bad_mesh(path, "normal index " + std::to_string(max_n + 1) + " out of range (" +
                       std::to_string(vn.size() / 3) + " normals)");
  if (any_normal_index && normals_match && vn.size() == m.positions.size()) m.normals = std::move(vn);
  return m;
}

}  // namespace adamesh::detail::meshfmt
