// `adamesh info INPUT [--json]`: what a volume (or sampled implicit input) contains — format,
// grid geometry, value statistics and a suggested iso-value (Otsu). Conventions:
// docs/CONVENTIONS.md; statistics: include/adamesh/stats.h.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "adamesh/input.h"
#include "adamesh/stats.h"
#include "args.h"
#include "commands.h"

namespace adamesh::cli {

namespace {

/// JSON number, or null for NaN/Inf (JSON has no NaN).
nlohmann::ordered_json num(double v) { return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr); }

nlohmann::ordered_json vec(const Vec3& v) { return {num(v.x), num(v.y), num(v.z)}; }

std::string fmt(double v) {
  std::ostringstream os;
  os << std::setprecision(8) << v;
  return os.str();
}

std::string fmt(const Vec3& v) { return fmt(v.x) + " " + fmt(v.y) + " " + fmt(v.z); }

std::string inside_rule(const Input& in) {
  return in.inside_sign > 0 ? "f >= iso" : "f <= iso";
}

std::string percentile_key(double level) { return std::to_string(static_cast<int>(level)); }

/// NaN/Inf samples found in the input (load_input counts them before any --nan-value replacement).
std::string nonfinite_text(const Input& in, const InputOptions& o) {
  std::string t = std::to_string(in.nonfinite_samples);
  if (in.nonfinite_samples && o.nan_value) t += " (replaced by " + fmt(*o.nan_value) + ")";
  else if (in.nonfinite_samples) t += " (ignored here; other commands need --nan-value V)";
  return t;
}

nlohmann::ordered_json to_json(const Input& in, const VolumeStats& s,
                               const std::vector<LabelCount>& labels) {
  const Volume& v = *in.volume;
  const Grid& g = v.grid;
  nlohmann::ordered_json j;
  j["input"] = in.spec;
  j["format"] = v.format;
  j["dims"] = {g.dims[0], g.dims[1], g.dims[2]};
  j["type"] = to_string(v.type);
  j["spacing"] = vec(g.spacing);
  j["origin"] = vec(g.origin);
  j["direction"] = {vec(g.direction.row(0)), vec(g.direction.row(1)), vec(g.direction.row(2))};
  const Box b = g.world_bounds();
  j["bounds"] = {vec(b.lo), vec(b.hi)};
  j["range"] = {num(s.min), num(s.max)};
  j["mean"] = num(s.mean);
  nlohmann::ordered_json p = nlohmann::ordered_json::object();
  for (std::size_t q = 0; q < s.percentiles.size(); ++q)
    p[percentile_key(VolumeStats::kPercentileLevels[q])] = num(s.percentiles[q]);
  j["percentiles"] = p;
  j["percentile_error"] = num(s.percentile_error);
  // A label map has no iso-value to suggest: its surfaces are the labels' boundaries.
  j["suggested_iso"] = labels.empty() ? num(s.otsu) : nlohmann::ordered_json(nullptr);
  j["label_map"] = !labels.empty();
  if (!labels.empty()) {
    nlohmann::ordered_json l = nlohmann::ordered_json::array();
    for (const auto& c : labels) l.push_back({{"label", c.label}, {"voxels", c.voxels}});
    j["labels"] = l;
  }
  j["default_iso"] = in.default_iso ? num(*in.default_iso) : nlohmann::ordered_json(nullptr);
  j["nonfinite"] = in.nonfinite_samples;
  j["inside"] = inside_rule(in);
  j["analytic"] = in.field && in.field->is_analytic();
  return j;
}

void print_text(const Input& in, const InputOptions& o, const VolumeStats& s,
                const std::vector<LabelCount>& labels) {
  const Volume& v = *in.volume;
  const Grid& g = v.grid;
  auto line = [](const char* key, const std::string& value) {
    std::string k = key;
    k.resize(15, ' ');
    std::cout << k << value << "\n";
  };
  line("input", in.spec);
  line("format", v.format + (in.field && in.field->is_analytic() ? " (exact field available)" : ""));
  std::ostringstream dims, dir, bounds;
  dims << g.dims[0] << " x " << g.dims[1] << " x " << g.dims[2] << "  (" << g.num_samples() << " samples)";
  line("dims", dims.str());
  line("type", to_string(v.type));
  line("spacing", fmt(g.spacing));
  line("origin", fmt(g.origin));
  dir << '[' << fmt(g.direction.row(0)) << "; " << fmt(g.direction.row(1)) << "; "
      << fmt(g.direction.row(2)) << "]  (columns: world axes of i, j, k)";
  line("direction", dir.str());
  const Box b = g.world_bounds();
  bounds << '[' << fmt(b.lo) << "] .. [" << fmt(b.hi) << ']';
  line("bounds", bounds.str());
  if (s.finite == 0) {  // e.g. an all-NaN volume: no statistic exists
    const std::string none = "none (no finite samples)";
    line("range", none);
    line("mean", none);
    line("percentiles", none);
    line("NaN/Inf", nonfinite_text(in, o));
    line("suggested iso", none);
  } else {
    line("range", fmt(s.min) + " .. " + fmt(s.max));
    line("mean", fmt(s.mean));
    std::string p;
    for (std::size_t q = 0; q < s.percentiles.size(); ++q)
      p += (q ? "  " : "") + percentile_key(VolumeStats::kPercentileLevels[q]) + "%: " + fmt(s.percentiles[q]);
    if (s.percentile_error > 0) p += "  (± " + fmt(s.percentile_error) + ")";
    line("percentiles", p);
    line("NaN/Inf", nonfinite_text(in, o));
  }
  if (s.finite > 0 && labels.empty()) {
    line("suggested iso", fmt(s.otsu) + " (Otsu)");
  } else if (s.finite > 0) {
    // With a background 0: every other label as one set (absent values in between change
    // nothing), the surface of all tissues together.
    std::string union_hint;
    const auto is_background = [](const LabelCount& c) { return c.label == 0; };
    if (std::any_of(labels.begin(), labels.end(), is_background)) {
      LabelSet all;
      std::int64_t below = 0, above = 0;  // the largest negative and smallest positive label
      for (const LabelCount& c : labels) {
        if (c.label < 0) below = c.label;
        if (c.label > 0 && above == 0) above = c.label;
      }
      if (below < 0) all.ranges.push_back({labels.front().label, below});
      if (above > 0) all.ranges.push_back({above, labels.back().label});
      union_hint = ", all but 0 as one surface with `extract --label " + all.to_string() + "`";
    }
    line("label map", std::to_string(labels.size()) +
                          " labels (integer values); mesh one with `extract --label L`, each with "
                          "`extract --labels all -o DIR/`" + union_hint);
    for (const auto& c : labels) {
      std::ostringstream t;
      t << std::setw(8) << c.label << "  " << std::setw(12) << c.voxels << " voxels  ("
        << std::fixed << std::setprecision(3)
        << 100.0 * static_cast<double>(c.voxels) / static_cast<double>(g.num_samples()) << " %)";
      line("", t.str());
    }
  }
  if (in.default_iso) line("default iso", fmt(*in.default_iso));
  line("inside", inside_rule(in) + (in.inside_sign > 0 ? " (bright is inside)" : " (negative is inside)"));
}

}  // namespace

int cmd_info(const Argv& argv) {
  std::vector<OptionSpec> specs = input_option_specs();
  specs.push_back({"--json", false, "print a JSON object instead of text"});
  const Args args("info", argv, specs);
  if (args.help_requested()) {
    std::cout << args.usage("INPUT [--json]")
              << "\nINPUT: a volume file, shape:NAME or expr:'EXPR'. Prints format, dims, type, "
                 "spacing, origin,\ndirection (rows of the matrix whose columns are the world "
                 "axes of i, j, k), world bounds,\nvalue range, mean, percentiles, NaN/Inf count "
                 "and a suggested iso-value (Otsu).\n";
    return 0;
  }
  args.expect_positionals(1, 1, "INPUT");
  InputOptions options = input_options_from(args);
  options.keep_nonfinite = true;
  const Input in = load_input(args.positionals()[0], options);
  const VolumeStats s = compute_stats(*in.volume);
  const std::vector<LabelCount> labels = label_counts(*in.volume);
  if (args.has("--json"))
    std::cout << to_json(in, s, labels).dump(2) << "\n";
  else
    print_text(in, options, s, labels);
  return 0;
}

}  // namespace adamesh::cli
