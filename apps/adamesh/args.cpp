#include "args.h"

#include <charconv>
#include <cmath>
#include <sstream>

#include "adamesh/error.h"

namespace adamesh::cli {

namespace {

[[noreturn]] void usage_error(const std::string& command, const std::string& what) {
  fail(Status::usage, "adamesh " + command + ": " + what + " (see adamesh " + command + " --help)");
}

bool parse_double(const std::string& s, double& out) {
  if (s.empty()) return false;
  try {
    std::size_t used = 0;
    out = std::stod(s, &used);
    return used == s.size() && std::isfinite(out);  // "nan", "inf": no option takes them
  } catch (...) {
    return false;
  }
}

}  // namespace

Args::Args(const std::string& command, const std::vector<std::string>& argv,
           const std::vector<OptionSpec>& specs)
    : command_(command), specs_(specs) {
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a == "--help" || a == "-h") {
      help_ = true;
      continue;
    }
    const bool looks_like_option = a.size() > 1 && a[0] == '-' &&
                                   !(std::isdigit(static_cast<unsigned char>(a[1])) || a[1] == '.');
    if (!looks_like_option) {
      positionals_.push_back(a);
      continue;
    }
    std::string name = a, value;
    bool inline_value = false;
    if (const auto eq = a.find('='); eq != std::string::npos && a.rfind("--", 0) == 0) {
      name = a.substr(0, eq);
      value = a.substr(eq + 1);
      inline_value = true;
    }
    const OptionSpec* spec = nullptr;
    for (const auto& s : specs_)
      if (s.name == name) spec = &s;
    if (!spec) usage_error(command_, "unknown option " + name);
    if (spec->takes_value) {
      if (!inline_value) {
        if (i + 1 >= argv.size()) usage_error(command_, "option " + name + " needs a value");
        value = argv[++i];
      }
      values_[name] = value;
    } else {
      if (inline_value) usage_error(command_, "option " + name + " takes no value");
      values_[name] = "1";
    }
  }
}

std::optional<std::string> Args::get(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::string Args::get_or(const std::string& name, const std::string& fallback) const {
  auto v = get(name);
  return v ? *v : fallback;
}

std::optional<double> Args::get_double(const std::string& name) const {
  auto v = get(name);
  if (!v) return std::nullopt;
  double d = 0;
  if (!parse_double(*v, d)) usage_error(command_, "option " + name + " expects a finite number, got '" + *v + "'");
  return d;
}

std::optional<std::int64_t> Args::get_int(const std::string& name) const {
  auto v = get(name);
  if (!v) return std::nullopt;
  std::int64_t x = 0;
  const auto* end = v->data() + v->size();
  auto [p, ec] = std::from_chars(v->data(), end, x);
  if (ec != std::errc() || p != end)
    usage_error(command_, "option " + name + " expects an integer, got '" + *v + "'");
  return x;
}

std::optional<std::vector<double>> Args::get_doubles(const std::string& name, std::size_t n) const {
  auto v = get(name);
  if (!v) return std::nullopt;
  std::vector<double> out;
  std::stringstream ss(*v);
  std::string item;
  while (std::getline(ss, item, ',')) {
    double d = 0;
    if (!parse_double(item, d))
      usage_error(command_, "option " + name + " expects " + std::to_string(n) +
                                " comma-separated numbers, got '" + *v + "'");
    out.push_back(d);
  }
  if (out.size() != n)
    usage_error(command_, "option " + name + " expects " + std::to_string(n) +
                              " comma-separated numbers, got '" + *v + "'");
  return out;
}

void Args::expect_positionals(std::size_t min, std::size_t max, const std::string& what) const {
  if (positionals_.size() < min) usage_error(command_, "missing " + what);
  if (positionals_.size() > max)
    usage_error(command_, "unexpected argument '" + positionals_[max] + "'");
}

std::string Args::usage(const std::string& synopsis) const {
  std::ostringstream os;
  os << "usage: adamesh " << command_ << " " << synopsis << "\n\noptions:\n";
  for (const auto& s : specs_) {
    std::string left = "  " + s.name + (s.takes_value ? " V" : "");
    if (left.size() < 24) left.resize(24, ' ');
    os << left << " " << s.help << "\n";
  }
  return os.str();
}

std::vector<OptionSpec> input_option_specs() {
  return {
      {"--dims", true, "raw input: X,Y,Z samples"},
      {"--type", true, "raw input: uint8|int8|uint16|int16|uint32|int32|float32|float64"},
      {"--spacing", true, "raw input: voxel size sx,sy,sz (default 1,1,1)"},
      {"--origin", true, "raw input: world position of the first sample (default 0,0,0)"},
      {"--endian", true, "raw input: little|big (default little)"},
      {"--header-bytes", true, "raw input: bytes to skip before the samples"},
      {"--bounds", true, "implicit input: xmin,ymin,zmin,xmax,ymax,zmax"},
      {"--res", true, "implicit input: samples along the longest side (default 64)"},
      {"--nan-value", true, "replace NaN/Inf samples by this value (default: reject them)"},
      {"--flip", false, "swap inside and outside"},
      {"--label", true,
       "label maps: the boundary of the voxels with this value, or with any value of a set "
       "(1,3,5-9: their union as one surface; iso 0.5 of their 0/1 mask; `adamesh info` lists "
       "the labels)"},
      {"--series", true, "DICOM directory with several series: the SeriesInstanceUID to read"},
  };
}

InputOptions input_options_from(const Args& args) {
  InputOptions o;
  if (auto d = args.get_doubles("--dims", 3)) {
    std::array<std::int64_t, 3> dims{};
    for (int a = 0; a < 3; ++a) {
      if ((*d)[a] != static_cast<double>(static_cast<std::int64_t>((*d)[a])))
        fail(Status::usage, "adamesh: --dims expects integers");
      dims[a] = static_cast<std::int64_t>((*d)[a]);
    }
    o.raw.dims = dims;
  }
  if (auto t = args.get("--type")) {
    o.raw.type = parse_scalar_type(*t);
    if (!o.raw.type) fail(Status::usage, "adamesh: unknown --type '" + *t + "'");
  }
  if (auto s = args.get_doubles("--spacing", 3)) o.raw.spacing = {(*s)[0], (*s)[1], (*s)[2]};
  if (auto s = args.get_doubles("--origin", 3)) o.raw.origin = {(*s)[0], (*s)[1], (*s)[2]};
  if (auto e = args.get("--endian")) {
    if (*e == "big") o.raw.big_endian = true;
    else if (*e == "little") o.raw.big_endian = false;
    else fail(Status::usage, "adamesh: --endian must be little or big, got '" + *e + "'");
  }
  if (auto h = args.get_int("--header-bytes")) {
    if (*h < 0) fail(Status::usage, "adamesh: --header-bytes must be >= 0");
    o.raw.header_bytes = static_cast<std::uint64_t>(*h);
  }
  if (auto b = args.get_doubles("--bounds", 6)) {
    const auto& v = *b;
    o.bounds = Box{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
    if (!(v[0] < v[3] && v[1] < v[4] && v[2] < v[5]))
      fail(Status::usage, "adamesh: --bounds needs xmin<xmax, ymin<ymax, zmin<zmax");
  }
  if (auto r = args.get_int("--res")) {
    if (*r < 2 || *r > 4096) fail(Status::usage, "adamesh: --res must be between 2 and 4096");
    o.resolution = static_cast<int>(*r);
  }
  o.nan_value = args.get_double("--nan-value");
  o.flip_inside = args.has("--flip");
  if (auto l = args.get("--label")) {
    try {
      o.label = parse_label_set(*l);
    } catch (const Error& e) {
      fail(Status::usage, std::string("--label: ") + e.what());
    }
  }
  o.raw.dicom_series = args.get_or("--series", "");
  return o;
}

OptionSpec compress_option_spec() {
  return {"--compress", false, "glTF/GLB: EXT_meshopt_compression (lossless, needs a reader that knows it)"};
}

}  // namespace adamesh::cli
