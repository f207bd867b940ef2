// Adjacency construction: corners by vertex (counting sort), then per vertex the sides whose
// smaller endpoint it is, sorted by the other endpoint, which numbers the edges in (lo, hi)
// order. Two parallel passes over the vertices (count, then fill) around a prefix sum, so the
// numbering never depends on the thread count.
#include "metrics/adjacency.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>

#include "adamesh/error.h"

namespace adamesh::detail {

Adjacency build_adjacency(const Mesh& m) {
  const std::size_t nv = m.num_vertices(), nt = m.num_triangles();
  if (3 * nt >= kNone) fail(Status::unsupported, "mesh: more than 1.4 billion triangles");
  const std::uint32_t* tri = m.triangles.data();
  Adjacency a;

  a.proper.resize(nt);
  a.side_edge.resize(3 * nt);  // filled below; sides of collapsed triangles get kNone here
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, 1 << 14), [&](const auto& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const std::uint32_t* v = tri + 3 * t;
      a.proper[t] = v[0] != v[1] && v[1] != v[2] && v[2] != v[0];
      if (!a.proper[t]) a.side_edge[3 * t] = a.side_edge[3 * t + 1] = a.side_edge[3 * t + 2] = kNone;
    }
  });

  // Corners by vertex: counting sort in corner order (sequential, memory bound).
  a.corner_offset.assign(nv + 1, 0);
  for (std::size_t t = 0; t < nt; ++t)
    if (a.proper[t])
      for (int k = 0; k < 3; ++k) ++a.corner_offset[tri[3 * t + k] + 1];
  for (std::size_t v = 0; v < nv; ++v) a.corner_offset[v + 1] += a.corner_offset[v];
  a.vertex_corners.resize(a.corner_offset[nv]);
  {
    RawVector<std::uint32_t> cursor(a.corner_offset.begin(), a.corner_offset.end() - 1);
    for (std::size_t t = 0; t < nt; ++t)
      if (a.proper[t])
        for (int k = 0; k < 3; ++k)
          a.vertex_corners[cursor[tri[3 * t + k]]++] = static_cast<std::uint32_t>(3 * t + k);
  }

  // Sides whose smaller endpoint is v: the outgoing side of a corner at v when v < next, the
  // incoming side when v < prev.
  auto gather = [&](std::size_t v, std::vector<std::pair<std::uint32_t, std::uint32_t>>& out) {
    out.clear();
    for (std::uint32_t i = a.corner_offset[v]; i < a.corner_offset[v + 1]; ++i) {
      const std::uint32_t c = a.vertex_corners[i];
      const std::uint32_t base = c - c % 3, k = c % 3;
      const std::uint32_t next = tri[base + (k + 1) % 3], prev = tri[base + (k + 2) % 3];
      if (v < next) out.emplace_back(next, c);                      // side c: v -> next
      if (v < prev) out.emplace_back(prev, base + (k + 2) % 3);     // side prev -> v
    }
    std::sort(out.begin(), out.end());
  };

  RawVector<std::uint32_t> side_count(nv + 1), edge_count(nv + 1);
  side_count[0] = edge_count[0] = 0;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1024), [&](const auto& r) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> buf;
    for (std::size_t v = r.begin(); v != r.end(); ++v) {
      gather(v, buf);
      side_count[v + 1] = static_cast<std::uint32_t>(buf.size());
      std::uint32_t edges = 0;
      for (std::size_t i = 0; i < buf.size(); ++i) edges += i == 0 || buf[i].first != buf[i - 1].first;
      edge_count[v + 1] = edges;
    }
  });
  for (std::size_t v = 0; v < nv; ++v) {
    side_count[v + 1] += side_count[v];
    edge_count[v + 1] += edge_count[v];
  }
  const std::size_t ne = edge_count[nv];
  a.edge_sides.resize(side_count[nv]);
  a.edge_offset.resize(ne + 1);
  a.edge_offset[ne] = side_count[nv];
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1024), [&](const auto& r) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> buf;
    for (std::size_t v = r.begin(); v != r.end(); ++v) {
      gather(v, buf);
      std::uint32_t pos = side_count[v], next_edge = edge_count[v];
      for (std::size_t i = 0; i < buf.size(); ++i, ++pos) {
        if (i == 0 || buf[i].first != buf[i - 1].first) a.edge_offset[next_edge++] = pos;
        a.edge_sides[pos] = buf[i].second;
        a.side_edge[buf[i].second] = next_edge - 1;
      }
    }
  });
  return a;
}

}  // namespace adamesh::detail
