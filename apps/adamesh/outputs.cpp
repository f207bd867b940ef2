#include "outputs.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "adamesh/atomic_file.h"
#include "adamesh/error.h"
#include "adamesh/io.h"
#include "adamesh/stats.h"
#include "args.h"

namespace adamesh::cli {

namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace

void check_outputs(const std::string& command, const Args& args,
                   const std::vector<OutputSpec>& outputs) {
  std::vector<std::pair<std::string, std::string>> seen;  // (normalised path, option)
  for (const auto& o : outputs) {
    const auto path = args.get(o.option);
    if (!path) continue;
    const std::string where = "adamesh " + command + ": " + o.option + " " + *path;
    if (path->empty()) fail(Status::usage, "adamesh " + command + ": " + o.option + " needs a file name");
    if (o.kind == OutputKind::mesh) (void)mesh_format_for_writing(*path);  // unsupported (3)
    if (o.kind == OutputKind::hierarchy && lower_extension(*path) != ".amh")
      fail(Status::usage, where + ": a hierarchy file needs the extension .amh");
    const std::string key = std::filesystem::absolute(*path).lexically_normal().string();
    for (const auto& [other, option] : seen)
      if (other == key)
        fail(Status::usage, where + ": the same file is already given to " + option);
    seen.emplace_back(key, o.option);
    try {
      check_output_target(*path);
    } catch (const Error& e) {
      fail(e.status(), "adamesh " + command + ": " + o.option + " " + e.what());
    }
  }
}

void check_iso_in_range(const Input& in, double iso) {
  const VolumeStats st = compute_stats(*in.volume);
  // A surface needs samples on both sides: some ≤ iso < some, or some < iso ≤ some.
  if (!(iso > st.min && iso <= st.max) && !(iso >= st.min && iso < st.max)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "iso-value %g is outside the value range [%g, %g]", iso, st.min,
                  st.max);
    fail_input(in.spec, std::string(buf) + (st.finite == 0 ? " (no finite samples)" : "") +
                            ": the surface would be empty");
  }
}

std::string one_line(const std::string& message) {
  std::string out;
  out.reserve(message.size());
  for (const char ch : message) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\n') out += "\\n";
    else if (c == '\t') out += "\\t";
    else if (c == '\r') out += "\\r";
    else if (c < 0x20 || c == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    } else {
      out += ch;
    }
  }
  return out;
}

}  // namespace adamesh::cli
