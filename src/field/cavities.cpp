// Topology control in the volume: small cavities (enclosed pockets of outside) are filled before
// the surface is extracted, so their inner surfaces never exist.
//
// A cavity is a 6-connected component of outside samples (not inside: inside_sign·(f − iso) < 0)
// that touches no face of the volume. Filling sets its samples to the most inside value of the
// volume (its maximum for bright-inside data, its minimum otherwise), so the component becomes
// part of the object and the trilinear iso-surface around it disappears. 6-connectivity of the
// outside is the complement of the 26-connectivity of the inside that the surfels' topology
// follows for non-ambiguous configurations; a cavity touching another only across an edge or a
// corner counts on its own.
#include <algorithm>
#include <vector>

#include "adamesh/error.h"
#include "adamesh/input.h"
#include "adamesh/stats.h"

namespace adamesh {

Input fill_cavities(const Input& in, double iso, std::int64_t max_voxels, CavityReport& report) {
  report = {};
  const Volume& src = *in.volume;
  const Grid& g = src.grid;
  const std::int64_t nx = g.dims[0], ny = g.dims[1], nz = g.dims[2], n = g.num_samples();
  auto copy = std::make_shared<Volume>(allocate_volume(g, src.type, src.source));
  copy->format = src.format;
  copy->source = src.source;
  std::copy(src.data.data(), src.data.data() + src.data.size(), copy->data.data());
  const VolumeStats st = compute_stats(src);
  const double fill_value = in.inside_sign > 0 ? st.max : st.min;

  dispatch_scalar(src.type, [&](auto tag) {
    using T = decltype(tag);
    T* s = copy->samples<T>();
    auto outside = [&](std::int64_t i) { return in.inside_sign * (static_cast<double>(s[i]) - iso) < 0; };
    std::vector<std::uint8_t> seen(static_cast<std::size_t>(n), 0);
    std::vector<std::int64_t> stack, members;
    for (std::int64_t start = 0; start < n; ++start) {
      if (seen[start] || !outside(start)) continue;
      // Flood fill one outside component; keep its members only while it may still be small.
      stack.assign(1, start);
      seen[start] = 1;
      members.clear();
      std::int64_t size = 0;
      bool border = false;
      while (!stack.empty()) {
        const std::int64_t i = stack.back();
        stack.pop_back();
        ++size;
        if (size <= max_voxels) members.push_back(i);
        const std::int64_t x = i % nx, y = (i / nx) % ny, z = i / (nx * ny);
        border |= x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1;
        const std::int64_t nb[6] = {x > 0 ? i - 1 : -1,           x < nx - 1 ? i + 1 : -1,
                                    y > 0 ? i - nx : -1,          y < ny - 1 ? i + nx : -1,
                                    z > 0 ? i - nx * ny : -1,     z < nz - 1 ? i + nx * ny : -1};
        for (const std::int64_t j : nb)
          if (j >= 0 && !seen[j] && outside(j)) {
            seen[j] = 1;
            stack.push_back(j);
          }
      }
      if (border || size >= max_voxels) continue;
      for (const std::int64_t i : members) s[i] = static_cast<T>(fill_value);
      ++report.filled;
      report.filled_voxels += size;
      report.largest_filled = std::max(report.largest_filled, size);
    }
  });
  Input out = in;
  out.volume = copy;
  out.field = make_volume_field(std::shared_ptr<const Volume>(copy));
  return out;
}

}  // namespace adamesh
