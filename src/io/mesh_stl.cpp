// STL. Writer: binary (80-byte header, uint32 count, per triangle the unit normal computed from
// the triangle, three float vertices and a zero attribute word). Reader: binary (recognised by
// its exact size 84 + 50·n) or ASCII (`solid` / `facet` / `vertex`); STL has no shared vertices,
// so corners with bit-identical positions (−0 = +0) are merged into one vertex, numbered in
// order of first appearance.
#include <cmath>
#include <span>
#include <unordered_map>

#include "io/mesh_formats.h"

namespace adamesh::detail::meshfmt {

void write_stl(const Mesh& m, std::ostream& os) {
  OutBuffer out(os);
  char header[80] = {};
  const char text[] = "binary STL written by adamesh";
  std::memcpy(header, text, sizeof text - 1);
  out.bytes(header, sizeof header);
  const std::size_t nt = m.num_triangles();
  out.binary(static_cast<std::uint32_t>(nt));
  for (std::size_t t = 0; t < nt; ++t) {
    const Vec3 a = m.vertex(m.triangles[3 * t]), b = m.vertex(m.triangles[3 * t + 1]),
               c = m.vertex(m.triangles[3 * t + 2]);
    const Vec3 n = normalized(cross(b - a, c - a));
    char rec[50];
    const float nf[3] = {static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z)};
    std::memcpy(rec, nf, 12);
    for (int k = 0; k < 3; ++k) std::memcpy(rec + 12 + 12 * k, &m.positions[3 * m.triangles[3 * t + k]], 12);
    rec[48] = rec[49] = 0;
    out.bytes(rec, sizeof rec);
  }
  out.drain();
}

namespace {

struct Key {
  std::uint32_t x, y, z;
  bool operator==(const Key&) const = default;
};
struct KeyHash {
  std::size_t operator()(const Key& k) const noexcept {
    std::uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
    h ^= (h >> 29) + k.y * 0xBF58476D1CE4E5B9ull;
    h ^= (h >> 31) + k.z * 0x94D049BB133111EBull;
    return static_cast<std::size_t>(h ^ (h >> 32));
  }
};

/// Merges corners with identical positions.
class Welder {
 public:
  explicit Welder(std::size_t corners) { map_.reserve(corners / 4 + 16); }
  std::uint32_t add(float p[3], Mesh& m) {
    Key k{};
    for (float& c : std::span<float>(p, 3))
      if (c == 0) c = 0;  // -0 -> +0
    std::memcpy(&k.x, &p[0], 4);
    std::memcpy(&k.y, &p[1], 4);
    std::memcpy(&k.z, &p[2], 4);
    auto [it, inserted] = map_.try_emplace(k, static_cast<std::uint32_t>(m.num_vertices()));
    if (inserted) m.positions.insert(m.positions.end(), p, p + 3);
    return it->second;
  }

 private:
  std::unordered_map<Key, std::uint32_t, KeyHash> map_;
};

Mesh read_binary_stl(const std::string& path, std::string_view data, std::uint32_t n) {
  Mesh m;
  m.triangles.reserve(3ull * n);
  Welder weld(3ull * n);
  for (std::uint32_t t = 0; t < n; ++t) {
    const char* rec = data.data() + 84 + 50ull * t;
    std::uint32_t idx[3];
    for (int k = 0; k < 3; ++k) {
      float p[3];
      std::memcpy(p, rec + 12 + 12 * k, 12);
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
        bad_mesh(path, "triangle " + std::to_string(t) + " has a non-finite coordinate");
      idx[k] = weld.add(p, m);
    }
    m.add_triangle(idx[0], idx[1], idx[2]);
  }
  return m;
}

Mesh read_ascii_stl(const std::string& path, std::string_view data) {
  Mesh m;
  Welder weld(data.size() / 64);
  LineReader lines(data);
  std::string_view line;
  std::uint32_t corner[3];
  int corners = 0;
  bool in_facet = false;
  auto where = [&] { return "line " + std::to_string(lines.line_no()); };
  while (lines.next(line)) {
    std::string_view rest = line;
    const std::string_view key = next_token(rest);
    if (key == "facet") {
      if (in_facet) bad_mesh(path, where() + ": 'facet' inside a facet");
      in_facet = true;
      corners = 0;
    } else if (key == "vertex") {
      if (!in_facet || corners == 3) bad_mesh(path, where() + ": unexpected 'vertex'");
      float p[3];
      for (float& c : p)
        if (!parse_number(next_token(rest), c) || !std::isfinite(c))
          bad_mesh(path, where() + ": bad vertex line");
      corner[corners++] = weld.add(p, m);
    } else if (key == "endfacet") {
      if (!in_facet || corners != 3) bad_mesh(path, where() + ": facet without 3 vertices");
      m.add_triangle(corner[0], corner[1], corner[2]);
      in_facet = false;
    }
  }
  if (in_facet) bad_mesh(path, "truncated: last facet has no 'endfacet'");
  if (data.find("endsolid") == std::string_view::npos)
    bad_mesh(path, "truncated ASCII STL (no 'endsolid') or a binary STL of the wrong size");
  return m;
}

}  // namespace

Mesh read_stl(const std::string& path, std::string_view data) {
  if (data.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, data.data() + 80, 4);
    if (84 + 50ull * n == data.size()) return read_binary_stl(path, data, n);
  }
  std::string_view probe = data.substr(0, 1024);
  if (next_token(probe) == "solid") return read_ascii_stl(path, data);
  if (data.size() < 84) bad_mesh(path, "truncated: a binary STL needs at least 84 bytes");
  std::uint32_t n = 0;
  std::memcpy(&n, data.data() + 80, 4);
  bad_mesh(path, "binary STL with " + std::to_string(n) + " triangles needs " +
                     std::to_string(84 + 50ull * n) + " bytes, the file has " +
                     std::to_string(data.size()));
}

}  // namespace adamesh::detail::meshfmt
