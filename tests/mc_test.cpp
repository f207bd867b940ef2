// Tests of the reference marching cubes mesh built on the surfel complex: topology of known
// shapes, manifoldness and orientation on adversarial fields, determinism.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/input.h"
#include "adamesh/io.h"
#include "adamesh/metrics.h"
#include "adamesh/surfels.h"
#include "surfel_test_util.h"
#include "testing.h"
#include "surfels/cell_table.h"

using namespace adamesh;
using namespace adamesh::testutil;

namespace {

double sphere(const Vec3& p, const Vec3& c, double r) { return r - distance(p, c); }

double torus(const Vec3& p, const Vec3& c, double R, double r) {
  const Vec3 d = p - c;
  const double q = std::sqrt(d.x * d.x + d.y * d.y) - R;
  return r - std::sqrt(q * q + d.z * d.z);
}

struct Expect {
  std::int64_t euler, components, loops;
};

/// Same vertex and triangle bytes.
void expect_same_mesh(const Mesh& a, const Mesh& b, const std::string& what = "") {
  ASSERT_EQ(a.positions.size(), b.positions.size()) << what;
  ASSERT_EQ(a.triangles.size(), b.triangles.size()) << what;
  EXPECT_EQ(0, std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(float)))
      << what;
  EXPECT_EQ(0, std::memcmp(a.triangles.data(), b.triangles.data(), a.triangles.size() * 4)) << what;
}

/// Builds complex + mesh and checks the invariants every mesh must have, and that the direct
/// path (marching_cubes(volume), no complex) gives the same bytes with 1 and 2 threads.
MeshTopology check_mc(const Volume& v, double iso, double inside_sign = 1) {
  const SurfelComplex cx = build_surfels(v, iso, inside_sign);
  EXPECT_EQ(validate_complex(cx), 0);
  const Mesh m = marching_cubes(cx);
  for (int threads : {1, 2}) {
    std::size_t surfels = 0;
    expect_same_mesh(marching_cubes(v, iso, inside_sign, {threads}, &surfels), m, "direct");
    EXPECT_EQ(surfels, cx.num_surfels());
  }
  EXPECT_EQ(m.num_vertices(), cx.num_nodes());
  EXPECT_EQ(m.num_triangles(), cx.surfel_nodes.size() - 2 * cx.num_surfels());
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.nonmanifold_edges, 0);
  EXPECT_EQ(t.nonmanifold_vertices, 0);
  EXPECT_EQ(t.misoriented_edges, 0);
  EXPECT_EQ(t.degenerate, 0);
  EXPECT_EQ(t.duplicates, 0);
  EXPECT_EQ(t.vertices, static_cast<std::int64_t>(cx.num_nodes()));  // every node used
  EXPECT_EQ(t.euler, cx.euler_characteristic());
  EXPECT_EQ(t.boundary_edges, static_cast<std::int64_t>(cx.num_border_segments()));
  return t;
}

void expect_topology(const MeshTopology& t, Expect e) {
  EXPECT_EQ(t.euler, e.euler);
  EXPECT_EQ(t.components, e.components);
  EXPECT_EQ(t.boundary_loops, e.loops);
}

}  // namespace

// Every configuration's cycles can be triangulated using only the diagonals the voxel owns (a
// diagonal between two nodes on one face could be chosen by the face neighbour too: an edge of
// four triangles). Without the split, 116 cycles have no such triangulation.
TEST(MarchingCubes, EveryCycleHasATriangulationWithOwnedDiagonals) {
  int checked = 0;
  for (int c = 1; c < 255; ++c) {
    const unsigned amb = detail::ambiguous_faces(c);
    for (unsigned dec = 0; dec < 128; ++dec) {
      if ((dec & 63) & ~amb) continue;
      const auto& cfg = detail::cell_config(c, dec & 63, dec >= 64);
      int idx = 0;
      for (int cy = 0; cy < cfg.num_cycles; ++cy) {
        const int len = cfg.cycle_len[cy];
        auto ok = [&](int i, int j) {
          const bool side = j == i + 1 || (i == 0 && j == len - 1);
          return side || detail::diagonal_allowed(cfg.edge[idx + i], cfg.edge[idx + j]);
        };
        // feasible[i][j]: sub-polygon i..j triangulable with allowed diagonals.
        bool feasible[12][12] = {};
        for (int i = 0; i + 1 < len; ++i) feasible[i][i + 1] = true;
        for (int gap = 2; gap < len; ++gap)
          for (int i = 0; i + gap < len; ++i) {
            const int j = i + gap;
            for (int m = i + 1; m < j && !feasible[i][j]; ++m)
              feasible[i][j] = feasible[i][m] && feasible[m][j] && ok(i, m) && ok(m, j);
          }
        EXPECT_TRUE(feasible[0][len - 1]) << "case " << c << " decisions " << dec;
        ++checked;
        idx += len;
      }
    }
  }
  EXPECT_EQ(checked, 2 * 1026);
}

TEST(MarchingCubes, SphereIsClosedGenusZeroAndOrientedOutwards) {
  const Grid g = cube_grid(36, -1.2, 1.2);
  const Vec3 c{0.03, 0.01, -0.02};
  const Volume v = sample_world(g, [&](const Vec3& p) { return sphere(p, c, 1); });
  expect_topology(check_mc(v, 0), {2, 1, 0});
  const Mesh m = marching_cubes(build_surfels(v, 0));
  for (std::size_t f = 0; f < m.num_triangles(); ++f) {
    const Vec3 a = m.vertex(m.triangles[3 * f]), b = m.vertex(m.triangles[3 * f + 1]),
               d = m.vertex(m.triangles[3 * f + 2]);
    ASSERT_GT(dot(cross(b - a, d - a), (a + b + d) / 3 - c), 0) << f;
  }
}

TEST(MarchingCubes, TorusTwoToriGenusTwoNestedSpheres) {
  const Grid g = cube_grid(48, -2.4, 2.4);
  expect_topology(check_mc(sample_world(g, [](const Vec3& p) { return torus(p, {0, 0, 0}, 1.4, 0.5); }), 0),
                  {0, 1, 0});
  expect_topology(check_mc(sample_world(g, [](const Vec3& p) {
                             return std::max(torus(p, {-1.1, 0, -0.9}, 0.9, 0.35),
                                             torus(p, {1.1, 0, 0.9}, 0.9, 0.35));
                           }), 0),
                  {0, 2, 0});
  // Two tori whose rings overlap near the origin: a double torus.
  expect_topology(check_mc(sample_world(g, [](const Vec3& p) {
                             return std::max(torus(p, {-0.95, 0, 0}, 0.95, 0.35),
                                             torus(p, {0.95, 0, 0}, 0.95, 0.35));
                           }), 0),
                  {-2, 1, 0});
  // Hollow shell: outer and inner sphere.
  expect_topology(check_mc(sample_world(g, [](const Vec3& p) {
                             const double d = norm(p);
                             return std::min(2.0 - d, d - 1.2);
                           }), 0),
                  {4, 2, 0});
}

TEST(MarchingCubes, SphereCutByTheVolumeBorder) {
  const Grid g = cube_grid(30, 0, 1);
  const Volume v = sample_world(g, [](const Vec3& p) { return sphere(p, {0.5, 0.5, 0.5}, 0.6); });
  expect_topology(check_mc(v, 0), {-4, 1, 6});
  // A cap cut by one face: a disc.
  const Volume cap = sample_world(g, [](const Vec3& p) { return sphere(p, {0.5, 0.5, -0.2}, 0.6); });
  expect_topology(check_mc(cap, 0), {1, 1, 1});
  // Border vertices lie on the volume faces.
  const Mesh m = marching_cubes(build_surfels(v, 0));
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> count;
  for (std::size_t f = 0; f < m.num_triangles(); ++f)
    for (int k = 0; k < 3; ++k) {
      const auto a = m.triangles[3 * f + k], b = m.triangles[3 * f + (k + 1) % 3];
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  const double h = g.spacing.x;
  int border_vertices = 0;
  for (const auto& [e, n] : count) {
    if (n != 1) continue;
    for (auto vtx : {e.first, e.second}) {
      const Vec3 p = m.vertex(vtx);
      double dmin = 1e9;
      for (int a = 0; a < 3; ++a) dmin = std::min({dmin, std::abs(p[a]), std::abs(p[a] - 1)});
      EXPECT_LT(dmin, 1e-6 * h);
      ++border_vertices;
    }
  }
  EXPECT_GT(border_vertices, 50);
}

TEST(MarchingCubes, NoiseAndAmbiguousFieldsAreCrackFreeManifolds) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_int_distribution<int> coin(0, 1);
  const std::array<std::int64_t, 3> dims{17, 15, 13};
  for (int trial = 0; trial < 12; ++trial) {
    Volume v = sample_volume(dims, [&](double i, double j, double k) -> double {
      switch (trial % 4) {
        case 0: return u(rng);                                                  // noise
        case 1: return coin(rng) ? 1.0 : -1.0;                                  // random ±1
        case 2: return ((int(i + j + k) % 2) ? 1 : -1) * (1 + 0.9 * u(rng));    // checkerboard
        default: return std::sin(i * 1.3) * std::sin(j * 1.7) * std::sin(k * 1.1) + 0.2 * u(rng);
      }
    });
    // Random ±1 closed off by a negative rim, so the interior components are closed.
    if (trial % 4 == 1) {
      for (std::int64_t k = 0; k < dims[2]; ++k)
        for (std::int64_t j = 0; j < dims[1]; ++j)
          for (std::int64_t i = 0; i < dims[0]; ++i)
            if (i == 0 || j == 0 || k == 0 || i == dims[0] - 1 || j == dims[1] - 1 || k == dims[2] - 1)
              v.samples<float>()[v.grid.linear_index(i, j, k)] = -1;
    }
    const MeshTopology t = check_mc(v, trial >= 8 ? 0.3 : 0.0, trial % 3 == 2 ? -1 : 1);
    if (trial % 4 == 1) {
      EXPECT_EQ(t.boundary_edges, 0);
    }
    EXPECT_GT(t.triangles, 100) << trial;
  }
}

TEST(MarchingCubes, IntegerVolumeAtAnIsoValuePresentInTheData) {
  Grid g;
  g.dims = {24, 22, 20};
  Volume v = allocate_volume(g, ScalarType::u8, "ball");
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> jitter(-2, 2);
  for (std::int64_t k = 0; k < 20; ++k)
    for (std::int64_t j = 0; j < 22; ++j)
      for (std::int64_t i = 0; i < 24; ++i) {
        const double d = std::sqrt((i - 11.5) * (i - 11.5) + (j - 10.7) * (j - 10.7) + (k - 9.6) * (k - 9.6));
        v.samples<std::uint8_t>()[g.linear_index(i, j, k)] = static_cast<std::uint8_t>(
            std::clamp(std::lround(120 + 6 * (8 - d)) + (d > 4 && d < 12 ? jitter(rng) : 0), 0L, 255L));
      }
  for (double iso : {120.0, 121.0, 119.0, 120.5}) check_mc(v, iso);
  expect_topology(check_mc(v, 130), {2, 1, 0});
}

TEST(MarchingCubes, ThreadCountGivesIdenticalMeshBytes) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  const Volume v = sample_volume({40, 37, 33}, [&](double i, double j, double k) {
    return std::sin(i * 0.35) + std::cos(j * 0.25) * std::sin(k * 0.4) + u(rng);
  });
  const Mesh a = marching_cubes(build_surfels(v, 0.05, 1, {1}));
  const Mesh b = marching_cubes(build_surfels(v, 0.05, 1, {2}));
  ASSERT_EQ(a.positions.size(), b.positions.size());
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  EXPECT_EQ(0, std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(float)));
  EXPECT_EQ(0, std::memcmp(a.triangles.data(), b.triangles.data(), a.triangles.size() * 4));
}

TEST(MarchingCubes, DirectPathGivesTheComplexPathsBytes) {
  // marching_cubes(volume) against marching_cubes(build_surfels(volume)): many slab splits
  // (threads 1..5 and all cores), thin grids, a mirrored grid, every scalar type, no voxels.
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  const Volume v = sample_volume({41, 29, 37}, [&](double i, double j, double k) {
    return std::sin(i * 0.45) * std::cos(j * 0.3) + std::sin(k * 0.55) + u(rng);
  });
  for (double sign : {1.0, -1.0}) {
    const Mesh ref = marching_cubes(build_surfels(v, 0.1, sign, {1}));
    EXPECT_GT(ref.num_triangles(), 1000u);
    for (int threads : {0, 1, 2, 3, 4, 5})
      expect_same_mesh(marching_cubes(v, 0.1, sign, {threads}), ref, std::to_string(threads));
  }
  for (std::array<std::int64_t, 3> d : {std::array<std::int64_t, 3>{2, 2, 9}, {9, 2, 2}, {2, 9, 2},
                                        {3, 2, 17}, {17, 3, 2}, {19, 18, 2}, {2, 23, 21}}) {
    const Volume t = sample_volume(d, [&](double, double, double) { return u(rng); });
    for (int threads : {1, 2, 3})
      expect_same_mesh(marching_cubes(t, 0.1, 1, {threads}),
                       marching_cubes(build_surfels(t, 0.1, 1, {threads})),
                       std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" + std::to_string(d[2]));
  }
  Grid g = cube_grid(20, -1.3, 1.3);
  g.direction = Mat3::from_columns({-1, 0, 0}, {0, 1, 0}, {0, 0, 1});
  g.origin.x = 1.3;
  const Volume mirrored = sample_world(g, [](const Vec3& p) { return norm(p) - 1.0; });
  expect_same_mesh(marching_cubes(mirrored, 0, -1, {2}),
                   marching_cubes(build_surfels(mirrored, 0, -1, {2})), "mirrored");
  for (ScalarType type : {ScalarType::u8, ScalarType::i16, ScalarType::u32, ScalarType::f64}) {
    Volume w = allocate_volume(v.grid, type, "t");
    dispatch_scalar(type, [&](auto zero) {
      using T = decltype(zero);
      for (std::int64_t x = 0; x < v.grid.num_samples(); ++x)
        w.samples<T>()[x] = static_cast<T>(std::round(60 + 40 * v.samples<float>()[x]));
    });
    expect_same_mesh(marching_cubes(w, 60.5, 1, {2}),
                     marching_cubes(build_surfels(w, 60.5, 1, {2})), to_string(type));
  }
  std::size_t surfels = 7;
  const Volume flat = sample_volume({5, 5, 1}, [](double i, double, double) { return i - 2; });
  EXPECT_EQ(marching_cubes(flat, 0.5, 1, {}, &surfels).num_triangles(), 0u);
  EXPECT_EQ(surfels, 0u);
  EXPECT_THROW(marching_cubes(v, std::nan(""), 1), Error);
  EXPECT_THROW(marching_cubes(v, 0, 0), Error);
}

TEST(MarchingCubes, TriangulationMaximisesTheMinimumAngle) {
  // Two positive corners on one edge: a quad; the chosen diagonal must give the larger min angle.
  for (double t : {0.1, 0.3, 0.7, 0.9}) {
    const Volume v = sample_volume({2, 2, 2}, [&](double i, double j, double k) {
      if (j == 0 && k == 0) return i == 0 ? 1.0 : (1 - t) / t;  // nodes at different heights
      return -1.0;
    });
    const SurfelComplex cx = build_surfels(v, 0);
    ASSERT_EQ(cx.num_surfels(), 1u);
    ASSERT_EQ(cx.nodes_of(0).size(), 4u);
    const Mesh m = marching_cubes(cx);
    auto min_angle = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
      const Vec3 p[3] = {m.vertex(a), m.vertex(b), m.vertex(c)};
      double best = 10;
      for (int k = 0; k < 3; ++k) {
        const Vec3 e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
        best = std::min(best, std::acos(dot(e1, e2) / (norm(e1) * norm(e2))));
      }
      return best;
    };
    const auto n = cx.nodes_of(0);
    const double d02 = std::min(min_angle(n[0], n[1], n[2]), min_angle(n[0], n[2], n[3]));
    const double d13 = std::min(min_angle(n[1], n[2], n[3]), min_angle(n[1], n[3], n[0]));
    const double got = std::min(min_angle(m.triangles[0], m.triangles[1], m.triangles[2]),
                                min_angle(m.triangles[3], m.triangles[4], m.triangles[5]));
    EXPECT_NEAR(got, std::max(d02, d13), 1e-6) << t;
  }
}

// ---- Built-in shapes through load_input, and the `adamesh mc` command. ----

TEST(MarchingCubes, BuiltInShapesHaveTheirKnownTopology) {
  const std::map<std::string, Expect> expected = {
      {"sphere", {2, 1, 0}},   {"torus", {0, 1, 0}},   {"two_tori", {0, 2, 0}},
      {"linked_tori", {0, 2, 0}}, {"genus2", {-2, 1, 0}}, {"cube_minus_sphere", {-8, 1, 0}},
      {"wavy_sheet", {1, 1, 1}}};
  for (const std::string& name : shape_names()) {
    SCOPED_TRACE(name);
    for (int res : {48, 96}) {
      InputOptions o;
      o.resolution = res;
      const Input in = load_input("shape:" + name, o);
      const MeshTopology t = check_mc(*in.volume, in.default_iso.value_or(0), in.inside_sign);
      if (auto it = expected.find(name); it != expected.end()) expect_topology(t, it->second);
      else EXPECT_GT(t.triangles, 1000);  // gyroid: open, consistent manifold (checked above)
      // Orientation: triangle normals agree with −inside_sign·∇f (area-weighted) on the smooth
      // shapes (cube_minus_sphere's creases make centroid gradients ambiguous).
      if (name == "cube_minus_sphere") continue;
      const Mesh m = marching_cubes(build_surfels(*in.volume, in.default_iso.value_or(0), in.inside_sign));
      double agree = 0, total = 0;
      for (std::size_t f = 0; f < m.num_triangles(); ++f) {
        const Vec3 a = m.vertex(m.triangles[3 * f]), b = m.vertex(m.triangles[3 * f + 1]),
                   c = m.vertex(m.triangles[3 * f + 2]);
        const Vec3 n = cross(b - a, c - a);
        const Vec3 g = in.field->gradient((a + b + c) / 3) * -in.inside_sign;
        if (dot(n, g) > 0) agree += norm(n);
        total += norm(n);
      }
      EXPECT_GT(agree / total, 0.999) << res;
    }
  }
}

TEST(MarchingCubesCli, WritesAMeshAndReportsSpeed) {
  TempDir tmp;
  const std::string out = tmp.file("torus.ply");
  const CliResult r = run_cli("mc shape:torus --res 40 -o '" + out + "' --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("triangles"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("voxels/s"), std::string::npos) << r.out;
  const Mesh m = read_mesh(out);
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.euler, 0);
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.nonmanifold_edges, 0);
  // Same bytes with one thread; --quiet prints nothing; ASCII PLY.
  const std::string out1 = tmp.file("torus1.ply");
  const CliResult q = run_cli("mc shape:torus --res 40 -o '" + out1 + "' --threads 1 --quiet");
  ASSERT_EQ(q.exit_code, 0) << q.err;
  EXPECT_TRUE(q.out.empty()) << q.out;
  EXPECT_EQ(read_bytes(out), read_bytes(out1));
  const std::string ascii = tmp.file("torus.ply.txt.ply");
  ASSERT_EQ(run_cli("mc shape:torus --res 40 -o '" + ascii + "' --ascii --quiet").exit_code, 0);
  EXPECT_NE(read_bytes(ascii).find("format ascii"), std::string::npos);
}

TEST(MarchingCubesCli, UsageErrors) {
  TempDir tmp;
  // A volume file has no default iso-value.
  const std::string raw = tmp.file("v.raw");
  write_bytes(raw, std::string(64, '\x07'));
  const CliResult no_iso =
      run_cli("mc '" + raw + "' --dims 4,4,4 --type uint8 -o '" + tmp.file("x.ply") + "'");
  EXPECT_EQ(no_iso.exit_code, 1);
  EXPECT_NE(no_iso.err.find("--iso"), std::string::npos) << no_iso.err;
  EXPECT_EQ(run_cli("mc shape:sphere").exit_code, 1);  // no -o
  EXPECT_EQ(run_cli("mc shape:sphere -o x.ply --threads -2").exit_code, 1);
  EXPECT_EQ(run_cli("mc -o x.ply").exit_code, 1);  // no INPUT
  EXPECT_EQ(run_cli("mc --help").exit_code, 0);
}

// ---- Every dataset of ../shared/data at each suggested iso-value (and the plain integer value
// for integer data). With ADAMESH_MC_TABLE=FILE set, also writes docs/MC_TABLE.md's table there
// (scripts/mc_table.sh). ----

TEST(MarchingCubesData, EveryDatasetIsAManifoldAtEverySuggestedIso) {
  ADAMESH_REQUIRE_SHARED_DATA(data);
  std::ifstream in(data + "/manifest.json");
  const nlohmann::json manifest = nlohmann::json::parse(in);
  const char* table_path = std::getenv("ADAMESH_MC_TABLE");
  const bool write_table = table_path != nullptr;
  std::ostringstream table;
  table << "| dataset | dims | iso | triangles | vertices | χ | components | boundary loops | "
           "time (s) | M voxels/s | reference (skimage Lewiner): triangles, χ, components |\n"
        << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  int runs = 0;
  for (const auto& ds : manifest["datasets"]) {
    const std::string id = ds["id"];
    const Input input = load_input(data + "/" + ds["primary_file"].get<std::string>());
    const Volume& vol = *input.volume;
    std::vector<std::pair<double, const nlohmann::json*>> isos;
    for (const auto& iv : ds["iso_values"]) {
      isos.push_back({iv["value"].get<double>(), &iv});
      // The integer value (samples equal to it count as inside); above the minimum, so that
      // the surface is not empty (frog labels: 0.5 -> 1).
      const double lo = ds["value_range"][0].get<double>();
      const double integer = std::floor(iv["value"].get<double>());
      if (!is_floating(vol.type)) isos.push_back({integer > lo ? integer : integer + 1, nullptr});
    }
    for (const auto& [iso, meta] : isos) {
      SCOPED_TRACE(id + " iso " + std::to_string(iso));
      // Time: best of three when writing the table (first runs pay thread start-up).
      double secs = 1e30;
      SurfelComplex cx;
      Mesh m;
      for (int rep = 0; rep < (write_table ? 3 : 1); ++rep) {
        const auto t0 = std::chrono::steady_clock::now();
        cx = build_surfels(vol, iso, input.inside_sign);
        m = marching_cubes(cx);
        secs = std::min(secs, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      }
      const TopologyReport t = topology(m);
      EXPECT_EQ(t.nonmanifold_edges, 0);
      EXPECT_EQ(t.nonmanifold_vertices, 0);
      EXPECT_EQ(t.degenerate_triangles, 0);
      EXPECT_EQ(t.duplicate_triangles, 0);
      EXPECT_EQ(t.collapsed_triangles, 0);
      EXPECT_TRUE(t.oriented);
      EXPECT_EQ(t.unreferenced_vertices, 0);
      EXPECT_EQ(t.euler, cx.euler_characteristic());
      EXPECT_EQ(t.boundary_edges, static_cast<std::int64_t>(cx.num_border_segments()));
      EXPECT_GT(t.triangles, 0);
      ++runs;
      const auto& d = vol.grid.dims;
      const double voxels = double(d[0] - 1) * double(d[1] - 1) * double(d[2] - 1);
      char buf[512];
      std::string ref = "—";
      if (meta && meta->contains("reference_mesh")) {
        const auto& r = (*meta)["reference_mesh"];
        ref = std::to_string(r["triangles"].get<std::int64_t>()) + ", " +
              std::to_string(r["euler"].get<std::int64_t>()) + ", " +
              std::to_string(r["components"].get<std::int64_t>());
      }
      std::snprintf(buf, sizeof buf, "| %s | %lldx%lldx%lld | %g%s | %lld | %lld | %lld | %lld | %lld | %.3f | %.0f | %s |\n",
                    id.c_str(), (long long)d[0], (long long)d[1], (long long)d[2], iso,
                    meta ? "" : " (integer)", (long long)t.triangles, (long long)t.vertices,
                    (long long)t.euler, (long long)t.components, (long long)t.boundary_loops, secs,
                    voxels / secs / 1e6, ref.c_str());
      table << buf;
    }
  }
  EXPECT_GE(runs, 20);
  if (write_table) {
    std::ofstream o(table_path);
    o << table.str();
    ASSERT_TRUE(o.good()) << table_path;
  }
}
