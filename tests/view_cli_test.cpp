// `adamesh view` without a browser: exit codes, a self-contained page (no external script, style
// or URL), and the embedded data decoded back and compared with the hierarchy / mesh it came
// from. The page in a browser: ctest view_browser (tests/view_browser.sh).
#include <algorithm>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "adamesh/io.h"
#include "adamesh/refine.h"
#include "testing.h"

using namespace adamesh;
using adamesh::testutil::read_bytes;
using adamesh::testutil::run_cli;
using adamesh::testutil::TempDir;

namespace {

std::string unbase64(const std::string& s) {
  auto val = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    return c == '+' ? 62 : 63;
  };
  std::string out;
  for (std::size_t i = 0; i + 3 < s.size(); i += 4) {
    const std::uint32_t n = (val(s[i]) << 18) | (val(s[i + 1]) << 12) |
                            ((s[i + 2] == '=' ? 0 : val(s[i + 2])) << 6) |
                            (s[i + 3] == '=' ? 0 : val(s[i + 3]));
    out.push_back(static_cast<char>(n >> 16));
    if (s[i + 2] != '=') out.push_back(static_cast<char>((n >> 8) & 255));
    if (s[i + 3] != '=') out.push_back(static_cast<char>(n & 255));
  }
  return out;
}

/// The JSON of <script id="adamesh-data">.
nlohmann::json page_data(const std::string& html) {
  const std::string open = "<script id=\"adamesh-data\" type=\"application/json\">";
  const auto a = html.find(open);
  EXPECT_NE(a, std::string::npos);
  const auto b = html.find("</script>", a);
  return nlohmann::json::parse(html.substr(a + open.size(), b - a - open.size()));
}

template <class T>
std::vector<T> array(const nlohmann::json& d, const std::string& blob, const std::string& name) {
  const std::size_t off = d["layout"][name][0], n = d["layout"][name][1];
  std::vector<T> v(n);
  std::memcpy(v.data(), blob.data() + off, n * sizeof(T));
  return v;
}

/// True when this build has the viewer; false (and the reason checked) when it does not.
bool viewer_built(const testutil::CliResult& r) {
  if (r.exit_code == 3 && r.err.find("no viewer") != std::string::npos) return false;
  return true;
}

}  // namespace

TEST(ViewCli, BadArguments) {
  TempDir tmp;
  EXPECT_EQ(run_cli("view missing.amh").exit_code, 1);
  auto r = run_cli("view missing.amh -o " + tmp.file("v.png"));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("HTML"), std::string::npos) << r.err;
  r = run_cli("view " + tmp.file("missing.amh") + " -o " + tmp.file("v.html"));
  if (!viewer_built(r)) GTEST_SKIP() << "built without the viewer bundle: " << r.err;
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp.file("v.html")));
}

TEST(ViewCli, HierarchyPageIsSelfContainedAndHoldsTheSplitList) {
  TempDir tmp;
  const std::string head = testutil::source_dir() + "/data/ct_headsq/quarter.nhdr";
  auto r = run_cli("extract '" + head + "' --iso 500.5 --quiet --triangles 12000 --hierarchy " +
                   tmp.file("h.amh") + " --report " + tmp.file("r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli("view " + tmp.file("h.amh") + " -o " + tmp.file("v.html") + " --report " +
              tmp.file("r.json"));
  if (!viewer_built(r)) GTEST_SKIP() << "built without the viewer bundle: " << r.err;
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::string html = read_bytes(tmp.file("v.html"));
  for (const char* external : {"<script src", "<link", "https://cdn", "import(", "fetch("})
    EXPECT_EQ(html.find(external), std::string::npos)
        << "page refers to something outside: " << external;
  const nlohmann::json d = page_data(html);
  EXPECT_EQ(d["kind"], "hierarchy");
  EXPECT_TRUE(d["report"].is_object());
  EXPECT_EQ(d["report"]["iso"], 500.5);
  const Hierarchy h = read_hierarchy(tmp.file("h.amh"));
  const std::string blob = unbase64(d["blob"]);
  EXPECT_EQ(d["base_vertices"], h.base_positions.size());
  ASSERT_GT(h.splits.size(), 1000u);
  const auto pos = array<float>(d, blob, "positions");
  ASSERT_EQ(pos.size(), 3 * h.num_vertices());
  for (std::size_t v = 0; v < h.num_vertices(); v += 97)
    EXPECT_EQ(pos[3 * v + 2], static_cast<float>(h.vertex(v).z));
  const auto base = array<std::uint32_t>(d, blob, "base_triangles");
  ASSERT_EQ(base.size(), 3 * h.base_triangles.size());
  EXPECT_EQ(base[3], h.base_triangles[1][0]);
  const auto edges = array<std::uint32_t>(d, blob, "split_edges");
  const auto want = split_edges(h);
  ASSERT_EQ(edges.size(), 2 * want.size());
  for (std::size_t s = 0; s < want.size(); ++s) {
    ASSERT_EQ(edges[2 * s], want[s][0]);
    ASSERT_EQ(edges[2 * s + 1], want[s][1]);
  }
  const auto err = array<float>(d, blob, "split_errors");
  ASSERT_EQ(err.size(), h.splits.size());
  EXPECT_EQ(err.front(), h.splits.front().error);
  // Split levels: the deepest split is one level above the finest mesh's depth.
  const auto lv = array<std::uint8_t>(d, blob, "split_levels");
  ASSERT_EQ(lv.size(), h.splits.size());
  EXPECT_EQ(*std::max_element(lv.begin(), lv.end()) + 1, extract_all(h).max_level);
}

TEST(ViewCli, MeshPage) {
  TempDir tmp;
  const std::string head = testutil::source_dir() + "/data/ct_headsq/quarter.nhdr";
  auto r = run_cli("mc '" + head + "' --iso 500.5 --quiet -o " + tmp.file("m.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli("view " + tmp.file("m.ply") + " -o " + tmp.file("m.html"));
  if (!viewer_built(r)) GTEST_SKIP() << "built without the viewer bundle: " << r.err;
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const Mesh m = read_mesh(tmp.file("m.ply"));
  const nlohmann::json d = page_data(read_bytes(tmp.file("m.html")));
  EXPECT_EQ(d["kind"], "mesh");
  const std::string blob = unbase64(d["blob"]);
  EXPECT_EQ(array<std::uint32_t>(d, blob, "triangles"), m.triangles);
  EXPECT_EQ(array<float>(d, blob, "positions"), m.positions);
}
