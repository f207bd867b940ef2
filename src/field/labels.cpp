// Label maps (integer volumes whose values name tissues or objects): the labels present, and the
// 0/1 mask of a set of labels, whose iso-surface at 1/2 is that set's boundary.
#include <algorithm>
#include <charconv>
#include <cstdint>
#include <limits>
#include <map>
#include <sstream>
#include <type_traits>

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
    if constexpr (sizeof(T) <= 2 && std::is_integral_v<T>) {
      // 8 and 16 bits: a table (intensity images with few levels have short runs; extract
      // calls this on every integer volume).
      constexpr std::int64_t kLow = std::numeric_limits<T>::min();
      std::vector<std::int64_t> table(std::size_t{1} << (8 * sizeof(T)), 0);
      for (std::int64_t i = 0; i < n; ++i) ++table[static_cast<std::size_t>(s[i] - kLow)];
      for (std::size_t k = 0; k < table.size() && !too_many; ++k)
        if (table[k] > 0) {
          counts[static_cast<std::int64_t>(k) + kLow] = table[k];
          too_many = counts.size() > max_labels;
        }
      return;
    }
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

bool LabelSet::contains(std::int64_t value) const {
  for (const auto& [lo, hi] : ranges)
    if (lo <= value && value <= hi) return true;
  return false;
}

std::string LabelSet::to_string() const {
  std::string s;
  for (const auto& [lo, hi] : ranges) {
    if (!s.empty()) s += ',';
    s += std::to_string(lo);
    if (hi != lo) {
      s += '-';
      s += std::to_string(hi);
    }
  }
  return s;
}

LabelSet parse_label_set(const std::string& text) {
  auto bad = [&](const std::string& why) {
    return Error(Status::usage, "label set '" + text + "': " + why +
                                    " (expected values and ranges separated by commas: 5, 1-15, "
                                    "1,3,5-9)");
  };
  // One value at p (an optional minus sign, then digits); advances p.
  auto value = [&](const char*& p, const char* end) {
    std::int64_t x = 0;
    const auto [q, ec] = std::from_chars(p, end, x);
    if (ec == std::errc::result_out_of_range) throw bad("a value beyond 64 bits");
    if (ec != std::errc() || q == p) throw bad("not a number where one should be");
    p = q;
    return x;
  };
  LabelSet set;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const char* p = text.data() + start;
    const char* end = text.data() + comma;
    if (p == end) throw bad("an empty part");
    const std::int64_t lo = value(p, end);
    std::int64_t hi = lo;
    if (p != end) {
      if (*p != '-') throw bad("unexpected '" + std::string(1, *p) + "'");
      hi = value(++p, end);
      if (p != end) throw bad("unexpected '" + std::string(1, *p) + "'");
      if (hi < lo)
        throw bad("the range " + std::to_string(lo) + "-" + std::to_string(hi) +
                  " ends below its start");
    }
    set.ranges.push_back({lo, hi});
    if (comma == text.size()) break;
    start = comma + 1;
  }
  std::sort(set.ranges.begin(), set.ranges.end());
  std::vector<std::pair<std::int64_t, std::int64_t>> merged;
  for (const auto& r : set.ranges) {
    const bool joins = !merged.empty() &&
                       (r.first <= merged.back().second ||
                        (merged.back().second < INT64_MAX && r.first == merged.back().second + 1));
    if (joins)
      merged.back().second = std::max(merged.back().second, r.second);
    else
      merged.push_back(r);
  }
  set.ranges = std::move(merged);
  return set;
}

std::string label_map_iso_note(const Volume& volume, double iso, double inside_sign) {
  const std::vector<LabelCount> labels = label_counts(volume);
  if (labels.size() < 3) return {};
  std::vector<std::int64_t> in, out;
  for (const LabelCount& l : labels)
    (inside_sign * (static_cast<double>(l.label) - iso) > 0 ? in : out).push_back(l.label);
  if (in.empty() || out.empty() || (in.size() < 2 && out.size() < 2)) return {};
  const LabelSet inside{{{in.front(), in.back()}}};  // the inside values are one interval
  std::ostringstream s;
  s << volume.source << ": looks like a label map (" << labels.size() << " integer values, "
    << in.size() << " of them " << (inside_sign > 0 ? "above" : "below") << " the iso-value " << iso
    << "): the surface follows the interpolated label numbers, not one boundary (it is stepped "
       "and creased where labels of different numbers meet the other side); `--label "
    << inside.to_string() << "` meshes ";
  if (in.size() == 1) s << "that label's boundary as a 0/1 mask";
  else s << "the union of those " << in.size() << " labels as one 0/1 mask";
  s << ", `--label L` or `--labels all -o DIR/` one label each";
  return s.str();
}

Input label_input(const Input& in, const LabelSet& labels) {
  const Volume& v = *in.volume;
  if (is_floating(v.type))
    throw Error(Status::invalid_input, v.source + ": --label needs an integer volume (this one is " +
                                           to_string(v.type) + ")");
  auto mask = std::make_shared<Volume>(allocate_volume(v.grid, ScalarType::u8, v.source));
  mask->format = v.format;
  const std::string name = labels.to_string();
  const bool one = labels.ranges.size() == 1 && labels.ranges[0].first == labels.ranges[0].second;
  mask->source = v.source + (one ? " (label " : " (labels ") + name + ")";
  std::uint8_t* m = mask->samples<std::uint8_t>();
  const std::int64_t n = v.grid.num_samples();
  std::int64_t inside = 0;
  dispatch_scalar(v.type, [&](auto tag) {
    using T = decltype(tag);
    const T* s = v.samples<T>();
    for (std::int64_t i = 0; i < n; ++i) {
      m[i] = labels.contains(static_cast<std::int64_t>(s[i]));
      inside += m[i];
    }
  });
  if (inside == 0)
    throw Error(Status::invalid_input,
                v.source + (one ? ": no voxel has label " : ": no voxel has a label in ") + name);
  Input out;
  out.spec = in.spec;
  out.volume = mask;
  out.field = make_volume_field(std::shared_ptr<const Volume>(mask));
  out.inside_sign = +1;
  out.default_iso = 0.5;
  return out;
}

}  // namespace adamesh
