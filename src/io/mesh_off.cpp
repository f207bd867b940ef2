// Object File Format (Geomview OFF), ASCII. Writer: `OFF` (or `NOFF` with per-vertex normals).
// Reader: OFF with the optional ST/C/N prefixes (texture, colour, normal columns; normals kept),
// counts on the header line or the next one, `#` comments and blank lines anywhere, face lines
// `n i1 .. in [colour]` fan-triangulated. Binary OFF and 4D/nD variants are rejected as
// unsupported. Counts are checked against the file size before allocating.
#include <cmath>

#include "io/mesh_formats.h"

namespace adamesh::detail::meshfmt {

void write_off(const Mesh& m, std::ostream& os, const MeshWriteOptions& opt) {
  const bool normals = opt.write_normals && !m.normals.empty();
  const std::size_t nv = m.num_vertices(), nt = m.num_triangles();
  OutBuffer out(os);
  out.text(normals ? "NOFF\n" : "OFF\n");
  out.number(static_cast<std::int64_t>(nv));
  out.put(' ');
  out.number(static_cast<std::int64_t>(nt));
  out.text(" 0\n");
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
  out.drain();
}

namespace {

/// Next line with content (comments stripped); false at the end.
bool content_line(LineReader& lines, std::string_view& line) {
  while (lines.next(line)) {
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    std::string_view probe = line;
    if (!next_token(probe).empty()) return true;
  }
  return false;
}

}  // namespace

Mesh read_off(const std::string& path, std::string_view data) {
  LineReader lines(data);
  std::string_view line;
  if (!content_line(lines, line)) bad_mesh(path, "empty file");
  std::string_view rest = line;
  const std::string_view magic = next_token(rest);
  if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF")
    bad_mesh(path, "not an OFF file (no OFF keyword on the first line)");
  bool normals = false;
  for (char c : magic.substr(0, magic.size() - 3)) {
    if (c == 'N') normals = true;
    else if (c == '4' || c == 'n')
      fail(Status::unsupported, path + ": " + std::string(magic) + " (4D/nD OFF) is not supported");
    else if (c != 'S' && c != 'T' && c != 'C')
      bad_mesh(path, "unknown OFF variant '" + std::string(magic) + "'");
  }
  std::string_view counts = rest;
  {
    std::string_view probe = rest;
    const std::string_view tok = next_token(probe);
    if (tok == "BINARY") fail(Status::unsupported, path + ": binary OFF is not supported");
    if (tok.empty()) {
      if (!content_line(lines, counts)) bad_mesh(path, "missing vertex and face counts");
    }
  }
  std::int64_t nv = 0, nf = 0, ne = 0;
  if (!parse_number(next_token(counts), nv) || !parse_number(next_token(counts), nf) || nv < 0 ||
      nf < 0)
    bad_mesh(path, "line " + std::to_string(lines.line_no()) + ": expected 'NV NF NE' counts");
  std::string_view ne_tok = next_token(counts);
  if (!ne_tok.empty() && !parse_number(ne_tok, ne)) bad_mesh(path, "bad edge count");
  // A vertex line takes at least 6 bytes ("0 0 0\n"), a face line at least 8 ("3 0 1 2\n").
  const long double need = 6.0L * nv + 8.0L * nf;
  if (need > static_cast<long double>(data.size() - lines.offset()) + 2)
    bad_mesh(path, "counts " + std::to_string(nv) + " vertices, " + std::to_string(nf) +
                       " faces do not fit in the file (truncated file or absurd counts)");
  if (nv > 0xffffffffll) bad_mesh(path, "more than 2^32-1 vertices");

  Mesh m;
  m.positions.resize(3 * static_cast<std::size_t>(nv));
  if (normals) m.normals.resize(3 * static_cast<std::size_t>(nv));
  auto where = [&] { return "line " + std::to_string(lines.line_no()); };
  for (std::int64_t v = 0; v < nv; ++v) {
    if (!content_line(lines, line))
      bad_mesh(path, "truncated: expected " + std::to_string(nv) + " vertices, found " + std::to_string(v));
    std::string_view r = line;
    for (int k = 0; k < (normals ? 6 : 3); ++k) {
      float c = 0;
      if (!parse_number(next_token(r), c)) bad_mesh(path, where() + ": bad vertex line");
      if (!std::isfinite(c)) bad_mesh(path, where() + ": non-finite coordinate");
      if (k < 3) m.positions[3 * v + k] = c;
      else m.normals[3 * v + k - 3] = c;
    }
  }
  m.triangles.reserve(3 * static_cast<std::size_t>(nf));
  std::vector<std::uint32_t> poly;
  for (std::int64_t f = 0; f < nf; ++f) {
    if (!content_line(lines, line))
      bad_mesh(path, "truncated: expected " + std::to_string(nf) + " faces, found " + std::to_string(f));
    std::string_view r = line;
    std::int64_t n = 0;
    if (!parse_number(next_token(r), n)) bad_mesh(path, where() + ": bad face line");
    if (n < 3) bad_mesh(path, where() + ": face with " + std::to_string(n) + " vertices (at least 3 needed)");
    poly.clear();
    for (std::int64_t k = 0; k < n; ++k) {
      std::int64_t idx = 0;
      const std::string_view tok = next_token(r);
      if (tok.empty()) bad_mesh(path, where() + ": face has fewer indices than its count " + std::to_string(n));
      if (!parse_number(tok, idx)) bad_mesh(path, where() + ": bad vertex index '" + std::string(tok) + "'");
      if (idx < 0 || idx >= nv)
        bad_mesh(path, where() + ": vertex index " + std::to_string(idx) + " out of range (" +
                           std::to_string(nv) + " vertices)");
      poly.push_back(static_cast<std::uint32_t>(idx));
    }
    for (std::size_t k = 1; k + 1 < poly.size(); ++k) m.add_triangle(poly[0], poly[k], poly[k + 1]);
  }
  return m;
}

}  // namespace adamesh::detail::meshfmt
