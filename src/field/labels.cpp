// Label maps (integer volumes whose values name tissues or objects): the labels present, and the
// 0/1 mask of one label, whose iso-surface at 1/2 is that label's boundary.
#include <algorithm>
#include <map>

#include "adamesh/error.h"
#include "adamesh/field.h"
#include "adamesh/input.h"
#include "adamesh/stats.h"

namespace adamesh {

std::vector<LabelCount> label_counts(const Volume& volume, std::size_t max_labels) {
  if (is_floating(volume.type)) return {};
  const std::int64_t n = volume.grid.num_samples();
  std::map<std::int64_t, std::int64_t> counts;
  bool too_many = false;
  dispatch_scalar(volume.type, [&](auto tag) {
    using T = decltype(tag);
    const T* s = volume.samples<T>();
    // Runs of equal values are common in label maps: count a run at once.
    for (std::int64_t i = 0; i < n && !too_many;) {
      std::int64_t j = i + 1;
      while (j < n && s[j] == s[i]) ++j;
      counts[static_cast<std::int64_t>(s[i])] += j - i;
      too_many = counts.size() > max_labels;
      i = j;
    }
  });
  if (too_many || counts.size() < 2) return {};
  std::vector<LabelCount> out;
  for (const auto& [label, voxels] : counts) out.push_back({label, voxels});
  return out;
}

Input label_input(const Input& in, std::int64_t label) {
  const Volume& v = *in.volume;
  if (is_floating(v.type))
    throw Error(Status::invalid_input, v.source + ": --label needs an integer volume (this one is " +
                                           to_string(v.type) + ")");
  auto mask = std::make_shared<Volume>(allocate_volume(v.grid, ScalarType::u8, v.source));
  mask->format = v.format;
  mask->source = v.source + " (label " + std::to_string(label) + ")";
  std::uint8_t* m = mask->samples<std::uint8_t>();
  const std::int64_t n = v.grid.num_samples();
  std::int64_t inside = 0;
  dispatch_scalar(v.type, [&](auto tag) {
    using T = decltype(tag);
    const T* s = v.samples<T>();
    for (std::int64_t i = 0; i < n; ++i) {
      m[i] = static_cast<std::int64_t>(s[i]) == label;
      inside += m[i];
    }
  });
  if (inside == 0)
    throw Error(Status::invalid_input, v.source + ": no voxel has label " + std::to_string(label));
  Input out;
  out.spec = in.spec;
  out.volume = mask;
  out.field = make_volume_field(std::shared_ptr<const Volume>(mask));
  out.inside_sign = +1;
  out.default_iso = 0.5;
  return out;
}

}  // namespace adamesh
