// `adamesh view FILE.amh|MESH -o view.html [--report r.json]`: one self-contained HTML page
// (three.js bundled at build time by esbuild, viewer/src/main.js) showing the mesh with orbit
// controls; for a hierarchy, a slider over its split prefixes and a uniform-level selector, every
// cut computed in the page from the embedded split list (no volume, nothing fetched).
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "adamesh/atomic_file.h"
#include "adamesh/error.h"
#include "adamesh/io.h"
#include "adamesh/refine.h"
#include "args.h"
#include "commands.h"
#include "outputs.h"
#include "viewer_bundle.h"

namespace adamesh::cli {

namespace {

/// Little-endian arrays appended to one blob, each 4-byte aligned; layout[name] = [offset, count].
class Blob {
 public:
  template <class T>
  void add(const std::string& name, const T* data, std::size_t count) {
    while (bytes_.size() % 4) bytes_.push_back('\0');
    layout_[name] = {bytes_.size(), count};
    bytes_.append(reinterpret_cast<const char*>(data), count * sizeof(T));
  }
  const std::string& bytes() const { return bytes_; }
  const nlohmann::json& layout() const { return layout_; }

 private:
  std::string bytes_;
  nlohmann::json layout_ = nlohmann::json::object();
};

std::string base64(const std::string& in) {
  static const char* abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const auto n = (std::uint32_t(std::uint8_t(in[i])) << 16) |
                   (std::uint32_t(std::uint8_t(in[i + 1])) << 8) | std::uint8_t(in[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out.push_back(abc[(n >> s) & 63]);
  }
  if (i < in.size()) {
    std::uint32_t n = std::uint32_t(std::uint8_t(in[i])) << 16;
    if (i + 1 < in.size()) n |= std::uint32_t(std::uint8_t(in[i + 1])) << 8;
    out.push_back(abc[(n >> 18) & 63]);
    out.push_back(abc[(n >> 12) & 63]);
    out.push_back(i + 1 < in.size() ? abc[(n >> 6) & 63] : '=');
    out.push_back('=');
  }
  return out;
}

/// JSON text safe inside <script>: "</" becomes "<\/" (the same string to a JSON parser).
std::string script_safe(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    out.push_back(s[i]);
    if (s[i] == '<' && i + 1 < s.size() && s[i + 1] == '/') out.push_back('\\');
  }
  return out;
}

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out.push_back(c);
    }
  }
  return out;
}

const char* kPageHead = R"(<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>)";

const char* kPageBody = R"(</title>
<style>
html, body { margin: 0; height: 100%; font: 14px/1.35 system-ui, sans-serif; color: #222; }
body { display: flex; }
#view { flex: 1; min-width: 0; height: 100%; display: block; }
#panel { width: 340px; padding: 12px 14px; overflow: auto; background: #fff; border-left: 1px solid #ccc; }
h1 { font-size: 16px; margin: 0 0 8px; word-break: break-all; }
label { display: block; margin: 8px 0 2px; }
input[type=range] { width: 100%; }
.big { font-size: 20px; font-weight: 600; }
#legend { color: #555; font-size: 12px; min-height: 1em; }
table { border-collapse: collapse; margin-top: 10px; font-size: 12px; width: 100%; }
th, td { text-align: left; padding: 2px 4px; border-bottom: 1px solid #eee; vertical-align: top; }
td { overflow-wrap: anywhere; }
.levels td, .levels th { text-align: right; }
.note { color: #666; font-size: 12px; margin-top: 10px; }
</style></head>
<body>
<canvas id="view"></canvas>
<div id="panel">
<h1 id="name">)";

const char* kPageControls = R"(</h1>
<div><span class="big" id="triangles">0</span> triangles <span id="cut"></span></div>
<div id="hierarchy-controls">
<label for="splits">refinement: prefix of the split list (any prefix is a valid mesh)</label>
<input type="range" id="splits" min="0" max="0" step="1" value="0">
<label for="level">uniform level</label>
<select id="level"><option value="">—</option></select>
</div>
<label for="colour">colour</label>
<select id="colour"><option value="plain">plain</option><option value="quality">triangle quality (minimum angle)</option><option value="error">distance bound (hierarchy)</option></select>
<label><input type="checkbox" id="wireframe"> wireframe</label>
<div id="legend"></div>
<div id="report"></div>
<p class="note">Drag to rotate, wheel to zoom, right-drag to pan. Written by adamesh view; nothing is loaded from the network.</p>
</div>
<script id="adamesh-data" type="application/json">)";

}  // namespace

int cmd_view(const Argv& argv) {
  const Args args(
      "view", argv,
      {
          {"-o", true, "output page (.html), self-contained"},
          {"--report", true, "JSON report of adamesh extract --report: figures shown in the page"},
          {"--partial", false, ".amh: accept a file cut short in its split list"},
          {"--quiet", false, "no summary line"},
      });
  if (args.help_requested()) {
    std::cout
        << args.usage("FILE.amh|MESH -o view.html [--report report.json]")
        << "\nOne HTML file with the mesh, orbit controls, wireframe and colouring by triangle "
           "quality;\n"
           "for a hierarchy (.amh) a slider over its split prefixes and uniform levels (cuts are\n"
           "computed in the page from the split list) and colouring by distance bound.\n";
    return 0;
  }
  args.expect_positionals(1, 1, "FILE.amh|MESH");
  const auto out = args.get("-o");
  if (!out) fail(Status::usage, "adamesh view: -o FILE.html is required");
  // As every command: the page's name and target are checked before any work (an .html/.htm
  // extension; absent or a regular file, no symlink, in an existing writable folder).
  check_outputs("view", args, {{"-o", OutputKind::page}});
  const std::string_view bundle = viewer_bundle();
  if (bundle.empty())
    fail(Status::unsupported,
         "adamesh view: this build has no viewer (the npm packages three and esbuild were not "
         "installed when it was built: run scripts/install-deps.sh with network access, then "
         "rebuild)");

  const std::string path = args.positionals()[0];
  nlohmann::json data;
  Blob blob;
  std::string summary;
  std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".amh") {
    HierarchyReadOptions ro;
    ro.allow_partial = args.has("--partial");
    const Hierarchy h = read_hierarchy(path, ro);
    const std::size_t v0 = h.base_positions.size(), f0 = h.base_triangles.size(),
                      ns = h.splits.size();
    std::vector<float> pos;
    pos.reserve(3 * (v0 + ns));
    for (std::size_t v = 0; v < v0 + ns; ++v) {
      const Vec3 p = h.vertex(v);
      pos.insert(pos.end(),
                 {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
    }
    std::vector<std::uint32_t> base;
    for (const auto& t : h.base_triangles) base.insert(base.end(), t.begin(), t.end());
    std::vector<std::uint32_t> edges;
    for (const auto& e : split_edges(h)) edges.insert(edges.end(), {e[0], e[1]});
    // Level of split s: the level of the triangle it bisects (base 0; children one deeper).
    std::vector<std::uint8_t> level(ns);
    std::vector<float> error(ns);
    for (std::size_t s = 0; s < ns; ++s) {
      const std::uint32_t t = h.splits[s].triangle;
      level[s] = t < f0 ? 0 : static_cast<std::uint8_t>(std::min(255, level[(t - f0) / 4] + 1));
      error[s] = h.splits[s].error;
    }
    blob.add("positions", pos.data(), pos.size());
    blob.add("base_triangles", base.data(), base.size());
    blob.add("split_edges", edges.data(), edges.size());
    blob.add("split_levels", level.data(), level.size());
    blob.add("split_errors", error.data(), error.size());
    data["kind"] = "hierarchy";
    data["base_vertices"] = v0;
    summary = std::to_string(f0) + " base triangles, " + std::to_string(ns) + " splits, " +
              std::to_string(prefix_triangle_counts(h).back()) + " triangles with every split";
  } else {
    const Mesh m = read_mesh(path);
    blob.add("positions", m.positions.data(), m.positions.size());
    blob.add("triangles", m.triangles.data(), m.triangles.size());
    data["kind"] = "mesh";
    summary = std::to_string(m.num_triangles()) + " triangles";
  }
  data["layout"] = blob.layout();
  data["blob"] = base64(blob.bytes());
  if (auto r = args.get("--report")) {
    std::ifstream in(*r, std::ios::binary);
    if (!in) fail_input(*r, "cannot open the report");
    try {
      data["report"] = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
      fail_input(*r, std::string("not a JSON report: ") + e.what());
    }
    if (!data["report"].is_object()) fail_input(*r, "not a JSON report (expected an object)");
  }
  std::string name = path;
  if (const auto slash = name.find_last_of('/'); slash != std::string::npos)
    name = name.substr(slash + 1);

  write_file_atomically(*out, [&](std::ostream& os) {
    os << kPageHead << html_escape(name) << " — adamesh view" << kPageBody << html_escape(name)
       << kPageControls << script_safe(data.dump()) << "</script>\n<script>";
    os.write(bundle.data(), static_cast<std::streamsize>(bundle.size()));
    os << "</script>\n</body></html>\n";
  });
  if (!args.has("--quiet"))
    std::cout << "view: " << path << " (" << summary << ") -> " << *out << "\n"
              << "open it in a browser: file://" << std::filesystem::absolute(*out).string()
              << "\n";
  return 0;
}

}  // namespace adamesh::cli
