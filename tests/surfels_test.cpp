// Tests of the surfel complex (ALGORITHM.md 2.2): configuration table, asymptotic decider,
// orientation, opposites, fans, border, determinism, degenerate samples.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/surfels.h"
#include "surfel_test_util.h"
#include "surfels/cell_table.h"

using namespace adamesh;
using namespace adamesh::testutil;

namespace {

double sphere(const Vec3& p, const Vec3& c, double r) { return r - distance(p, c); }

Volume corner_cell(const std::array<double, 8>& v) {
  return sample_volume({2, 2, 2}, [&](double i, double j, double k) {
    return v[static_cast<int>(i) + 2 * static_cast<int>(j) + 4 * static_cast<int>(k)];
  });
}

}  // namespace

TEST(CellTable, FacesAreCounterClockwiseFromOutside) {
  const auto& faces = detail::cube_faces();
  auto pos = [](int c) { return Vec3{double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; };
  for (int f = 0; f < 6; ++f) {
    const auto& fc = faces[f].corner;
    const Vec3 n = cross(pos(fc[1]) - pos(fc[0]), pos(fc[2]) - pos(fc[1]));
    Vec3 out{};
    out[f / 2] = f % 2 ? 1 : -1;
    EXPECT_GT(dot(n, out), 0) << "face " << f;
    for (int k = 0; k < 4; ++k) {
      const auto& e = detail::cube_edges()[faces[f].edge[k]];
      const int a = fc[k], b = fc[(k + 1) % 4];
      EXPECT_TRUE((e.corner0 == a && e.corner1 == b) || (e.corner0 == b && e.corner1 == a));
    }
  }
}

TEST(CellTable, EveryConfigurationIsAPartitionIntoCycles) {
  const auto& edges = detail::cube_edges();
  int max_cycles = 0, max_len = 0;
  for (int c = 0; c < 256; ++c) {
    const unsigned amb = detail::ambiguous_faces(c);
    for (unsigned dec = 0; dec < 64; ++dec) {
      if (dec & ~amb) continue;
      for (bool mirrored : {false, true}) {
        const auto& cfg = detail::cell_config(c, dec, mirrored);
        int crossing = 0;
        for (const auto& e : edges) crossing += ((c >> e.corner0) & 1) != ((c >> e.corner1) & 1);
        ASSERT_EQ(cfg.num_entries, crossing) << c;
        std::set<int> used(cfg.edge.begin(), cfg.edge.begin() + cfg.num_entries);
        EXPECT_EQ(static_cast<int>(used.size()), crossing);
        int idx = 0;
        for (int cy = 0; cy < cfg.num_cycles; ++cy) {
          const int len = cfg.cycle_len[cy];
          EXPECT_GE(len, 3);
          max_len = std::max(max_len, len);
          for (int k = 0; k < len; ++k) {
            // Consecutive nodes share the face of their segment.
            const int e0 = cfg.edge[idx + k], e1 = cfg.edge[idx + (k + 1) % len];
            EXPECT_EQ(detail::common_face(e0, e1), cfg.face[idx + k]);
          }
          idx += len;
        }
        max_cycles = std::max(max_cycles, int(cfg.num_cycles));
      }
    }
  }
  EXPECT_EQ(max_cycles, 4);
  EXPECT_EQ(max_len, 12);
}

TEST(Decider, SymmetricAndZeroSaddleIsPositive) {
  // Saddle value s = (ac − bd)/(a + c − b − d); any labelling of the same face agrees.
  const double v[4] = {1.0, -2.0, 3.0, -1.0};  // ac − bd = 3 − 2 = 1 > 0: positive connected
  for (int r = 0; r < 4; ++r) {
    EXPECT_TRUE(detail::positive_diagonal_connected(v[r], v[(r + 1) % 4], v[(r + 2) % 4], v[(r + 3) % 4]));
    EXPECT_TRUE(detail::positive_diagonal_connected(v[(4 - r) % 4], v[(7 - r) % 4], v[(6 - r) % 4], v[(5 - r) % 4]));
  }
  EXPECT_FALSE(detail::positive_diagonal_connected(1, -2, 1, -1));   // 1 − 2 < 0
  EXPECT_TRUE(detail::positive_diagonal_connected(2, -2, 1, -1));    // s = 0 counts as positive
  EXPECT_TRUE(detail::positive_diagonal_connected(-1, 2, -2, 1));    // same, other labelling
  EXPECT_FALSE(detail::positive_diagonal_connected(0, -1, 0, -1e-30));  // 0·0 − 1e-30 < 0
}

TEST(Surfels, SingleCornerTriangleOrientedAwayFromInside) {
  const SurfelComplex cx = build_surfels(corner_cell({1, -1, -1, -1, -1, -1, -1, -1}), 0);
  ASSERT_EQ(cx.num_surfels(), 1u);
  ASSERT_EQ(cx.num_nodes(), 3u);
  EXPECT_EQ(validate_complex(cx), 0);
  const Vec3 n = newell_normal(cx, 0);
  EXPECT_GT(dot(n, Vec3{1, 1, 1}), 0);  // from the positive corner (0,0,0) towards the rest
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(cx.node_position(k)[static_cast<int>(cx.node_key[k] % 3)], 0.5, 1e-7);
    EXPECT_EQ(cx.opposite(0, static_cast<std::size_t>(k)), -1);
  }
  EXPECT_EQ(cx.num_border_segments(), 3u);
  EXPECT_EQ(cx.num_segments(), 3u);
  EXPECT_EQ(cx.euler_characteristic(), 1);
  // Keys: x edge of (0,0,0) = 0, y edge = 1, z edge = 2.
  EXPECT_EQ(cx.find_node(0), 0);
  EXPECT_EQ(cx.find_node(2), 2);
  EXPECT_EQ(cx.find_node(3), -1);
  EXPECT_EQ(cx.surfel_voxel[0], 0u);
  // Inside sign −1 on the negated field gives the identical complex.
  const SurfelComplex neg = build_surfels(corner_cell({-1, 1, 1, 1, 1, 1, 1, 1}), 0, -1);
  EXPECT_EQ(neg.surfel_nodes, cx.surfel_nodes);
  EXPECT_EQ(neg.node_pos, cx.node_pos);
}

TEST(Surfels, OppositeCornersGiveTwoSurfelsInOneVoxel) {
  const SurfelComplex cx = build_surfels(corner_cell({1, -1, -1, -1, -1, -1, -1, 1}), 0);
  ASSERT_EQ(cx.num_surfels(), 2u);
  EXPECT_EQ(cx.surfel_voxel[0], cx.surfel_voxel[1]);
  EXPECT_EQ(validate_complex(cx), 0);
  // Each triangle's normal points away from its own positive corner.
  for (std::size_t s = 0; s < 2; ++s) {
    const Vec3 c = cx.cvertex_position(s);
    const Vec3 inside = c.x < 0.5 ? Vec3{0, 0, 0} : Vec3{1, 1, 1};
    EXPECT_GT(dot(newell_normal(cx, s), c - inside), 0);
  }
}

TEST(Surfels, AmbiguousFaceFollowsTheDecider) {
  // Face z = 0 has corners 0 (+), 1 (−), 3 (+), 2 (−): ambiguous. The top face is all negative.
  auto surfels_for = [](double a, double c) {
    return build_surfels(corner_cell({a, -1, -1, c, -1, -1, -1, -1}), 0).num_surfels();
  };
  EXPECT_EQ(surfels_for(2, 2), 1u);      // saddle 3/6 > 0: positive diagonal connected
  EXPECT_EQ(surfels_for(0.5, 0.5), 2u);  // saddle (0.25 − 1)/3 < 0: separated
  EXPECT_EQ(surfels_for(1, 1), 1u);      // saddle 0: counts as positive
}

TEST(Surfels, SphereInvariantsOrientationAndEuler) {
  Grid g = cube_grid(40, -1.3, 1.3);
  g.spacing = {g.spacing.x, g.spacing.y * 0.9, g.spacing.z * 1.1};  // anisotropic
  const Vec3 c{0.05, -0.02, 0.1};
  const Volume v = sample_world(g, [&](const Vec3& p) { return sphere(p, c, 1.0); });
  const SurfelComplex cx = build_surfels(v, 0);
  EXPECT_EQ(validate_complex(cx), 0);
  EXPECT_EQ(cx.euler_characteristic(), 2);
  EXPECT_EQ(cx.num_border_segments(), 0u);
  for (std::size_t s = 0; s < cx.num_surfels(); ++s) {
    const Vec3 n = normalized(newell_normal(cx, s));
    const Vec3 outward = normalized(cx.cvertex_position(s) - c);  // −∇f
    ASSERT_GT(dot(n, outward), 0.5) << "surfel " << s;
  }
  for (std::size_t n = 0; n < cx.num_nodes(); ++n)
    ASSERT_NEAR(distance(cx.node_position(n), c), 1.0, 0.02);
}

TEST(Surfels, OrientationWithInsideSignMinusOneAndMirroredGrid) {
  for (bool mirror : {false, true}) {
    Grid g = cube_grid(24, -1.3, 1.3);
    if (mirror) {
      g.direction = Mat3::from_columns({-1, 0, 0}, {0, 1, 0}, {0, 0, 1});
      g.origin.x = 1.3;
    }
    const Vec3 c{0.1, 0, 0};
    // Implicit convention: f = |p − c| − 1 < 0 inside, inside_sign = −1.
    const Volume v = sample_world(g, [&](const Vec3& p) { return distance(p, c) - 1.0; });
    const SurfelComplex cx = build_surfels(v, 0, -1);
    EXPECT_EQ(validate_complex(cx), 0);
    EXPECT_EQ(cx.euler_characteristic(), 2);
    for (std::size_t s = 0; s < cx.num_surfels(); ++s)
      ASSERT_GT(dot(newell_normal(cx, s), cx.cvertex_position(s) - c), 0) << mirror << " " << s;
  }
}

TEST(Surfels, SphereCutByTheBorder) {
  // Sphere of radius 0.6 L centred in the box: cut by all six faces, six border loops.
  const Grid g = cube_grid(30, 0, 1);
  const Volume v = sample_world(g, [](const Vec3& p) { return sphere(p, {0.5, 0.5, 0.5}, 0.6); });
  const SurfelComplex cx = build_surfels(v, 0);
  EXPECT_EQ(validate_complex(cx), 0);
  EXPECT_EQ(cx.euler_characteristic(), 2 - 6);
  EXPECT_GT(cx.num_border_segments(), 0u);
}

TEST(Surfels, RandomAndCheckerboardFieldsAreConsistent) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 6; ++trial) {
    const Volume v = sample_volume({9, 8, 7}, [&](double i, double j, double k) {
      if (trial % 2) return u(rng);
      const double sign = (int(i + j + k) % 2) ? 1.0 : -1.0;  // checkerboard: all faces ambiguous
      return sign * (0.5 + 0.5 * std::abs(u(rng)));
    });
    const SurfelComplex cx = build_surfels(v, trial == 4 ? 0.25 : 0.0);
    EXPECT_EQ(validate_complex(cx), 0) << trial;
  }
}

TEST(Surfels, IntegerSamplesEqualToIsoAreDeterministicAndManifold) {
  Grid g;
  g.dims = {20, 21, 19};
  Volume v = allocate_volume(g, ScalarType::u8, "ball");
  for (std::int64_t k = 0; k < 19; ++k)
    for (std::int64_t j = 0; j < 21; ++j)
      for (std::int64_t i = 0; i < 20; ++i) {
        const double d = std::sqrt((i - 9.5) * (i - 9.5) + (j - 10.2) * (j - 10.2) + (k - 9.0) * (k - 9.0));
        v.samples<std::uint8_t>()[g.linear_index(i, j, k)] =
            static_cast<std::uint8_t>(std::clamp(std::lround(100 + 8 * (7 - d)), 0L, 255L));
      }
  int equal = 0;
  for (std::int64_t x = 0; x < g.num_samples(); ++x) equal += v.samples<std::uint8_t>()[x] == 100;
  ASSERT_GT(equal, 50);
  const SurfelComplex cx = build_surfels(v, 100);
  EXPECT_EQ(validate_complex(cx), 0);
  EXPECT_EQ(cx.euler_characteristic(), 2);
  // Nodes at samples equal to iso are clamped off the corner.
  for (std::size_t n = 0; n < cx.num_nodes(); ++n) {
    const Vec3 idx = cx.grid.to_index(cx.node_position(n));
    const double t = idx[static_cast<int>(cx.node_key[n] % 3)];
    const double frac = t - std::floor(t);
    ASSERT_GE(std::min(frac, 1 - frac), SurfelComplex::kNodeEps * 0.99);
  }
}

TEST(Surfels, AllScalarTypesAgree) {
  const Volume f = sample_volume({12, 11, 10}, [](double i, double j, double k) {
    return std::round(40 - std::sqrt((i - 5) * (i - 5) + (j - 5) * (j - 5) + (k - 4) * (k - 4)) * 7);
  });
  const SurfelComplex ref = build_surfels(f, 10.5);
  for (ScalarType t : {ScalarType::u8, ScalarType::i8, ScalarType::u16, ScalarType::i16,
                       ScalarType::u32, ScalarType::i32, ScalarType::f64}) {
    Volume v = allocate_volume(f.grid, t, "t");
    dispatch_scalar(t, [&](auto zero) {
      using T = decltype(zero);
      for (std::int64_t x = 0; x < f.grid.num_samples(); ++x)
        v.samples<T>()[x] = static_cast<T>(std::max(0.0, double(f.samples<float>()[x])));
    });
    const SurfelComplex cx = build_surfels(v, 10.5);
    EXPECT_EQ(cx.surfel_nodes, ref.surfel_nodes) << to_string(t);
    EXPECT_EQ(cx.node_pos, ref.node_pos) << to_string(t);
  }
}

TEST(Surfels, ThreadCountDoesNotChangeTheResult) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  const Volume v = sample_volume({33, 30, 41}, [&](double i, double j, double k) {
    return std::sin(i * 0.4) * std::cos(j * 0.3) + std::sin(k * 0.5) + u(rng);
  });
  const SurfelComplex a = build_surfels(v, 0.1, 1, {1});
  const SurfelComplex b = build_surfels(v, 0.1, 1, {2});
  const SurfelComplex c = build_surfels(v, 0.1, 1, {0});
  for (const SurfelComplex* x : {&b, &c}) {
    EXPECT_EQ(a.node_key, x->node_key);
    EXPECT_EQ(a.node_pos, x->node_pos);
    EXPECT_EQ(a.node_fan, x->node_fan);
    EXPECT_EQ(a.node_turn, x->node_turn);
    EXPECT_EQ(a.surfel_offset, x->surfel_offset);
    EXPECT_EQ(a.surfel_nodes, x->surfel_nodes);
    EXPECT_EQ(a.surfel_voxel, x->surfel_voxel);
    EXPECT_EQ(a.cvertex, x->cvertex);
  }
  EXPECT_EQ(validate_complex(a), 0);
}

TEST(Surfels, EmptyConstantAndFlatVolumes) {
  EXPECT_EQ(build_surfels(sample_volume({5, 5, 5}, [](double, double, double) { return 1.0; }), 0)
                .num_surfels(), 0u);
  EXPECT_EQ(build_surfels(sample_volume({5, 5, 5}, [](double, double, double) { return 0.0; }), 0)
                .num_nodes(), 0u);  // all equal to iso: all positive
  const SurfelComplex flat =
      build_surfels(sample_volume({5, 5, 1}, [](double i, double, double) { return i - 2; }), 0.5);
  EXPECT_EQ(flat.num_surfels(), 0u);
  EXPECT_EQ(flat.surfel_offset.size(), 1u);
  EXPECT_THROW(build_surfels(sample_volume({3, 3, 3}, [](double, double, double) { return 0.0; }),
                             std::nan("")),
               Error);
  EXPECT_THROW(build_surfels(sample_volume({3, 3, 3}, [](double, double, double) { return 0.0; }), 0, 0),
               Error);
}

TEST(Surfels, ThinGridsAndManySlabs) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  for (std::array<std::int64_t, 3> d : {std::array<std::int64_t, 3>{2, 2, 9}, {9, 2, 2}, {2, 9, 2},
                                        {3, 2, 17}, {17, 3, 2}, {19, 18, 2}, {2, 23, 21}}) {
    const Volume v = sample_volume(d, [&](double, double, double) { return u(rng); });
    for (int threads : {1, 2}) {
      const SurfelComplex cx = build_surfels(v, 0.1, 1, {threads});
      EXPECT_EQ(validate_complex(cx), 0) << d[0] << "x" << d[1] << "x" << d[2];
      EXPECT_GT(cx.num_surfels(), 0u);
    }
  }
}
