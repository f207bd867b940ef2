// Topology control of handles and tunnels (remove_handles, `extract --max-handle`): thin
// strands of material are cut, thin tunnels plugged, thick ones and the components kept; the
// surface's genus is measured with the surfels' own topology (marching cubes on the result).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>

#include "adamesh/error.h"
#include "adamesh/input.h"
#include "adamesh/surfels.h"
#include "mesh_checks.h"

namespace adamesh {
namespace {

using Fn = std::function<double(double, double, double)>;

/// An n³ float32 volume of f at the voxel indices (inside where f >= 0).
Input volume_of(int n, const Fn& f) {
  Grid g;
  g.dims = {n, n, n};
  g.direction = Mat3::identity();
  Volume v = allocate_volume(g, ScalarType::f32, "<test>");
  float* s = v.samples<float>();
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) s[(z * n + y) * n + x] = static_cast<float>(f(x, y, z));
  return make_input(std::move(v), "<test>");
}

testutil::MeshTopo surface_topology(const Input& in) {
  return testutil::mesh_topo(marching_cubes(build_surfels(*in.volume, 0.0, in.inside_sign)));
}

double ball(double x, double y, double z, double cx, double cy, double cz, double r) {
  return r - std::sqrt((x - cx) * (x - cx) + (y - cy) * (y - cy) + (z - cz) * (z - cz));
}
/// Torus around the axis through (cx, cy, cz) along `axis` (0 x, 1 y, 2 z).
double torus(double x, double y, double z, double cx, double cy, double cz, int axis, double big,
             double tube) {
  double p[3] = {x - cx, y - cy, z - cz};
  const double a = p[axis], u = p[(axis + 1) % 3], w = p[(axis + 2) % 3];
  const double q = std::sqrt(u * u + w * w) - big;
  return tube - std::sqrt(q * q + a * a);
}

std::int64_t changed_samples(const Input& a, const Input& b) {
  const float* s = a.volume->samples<float>();
  const float* t = b.volume->samples<float>();
  std::int64_t k = 0;
  for (std::int64_t i = 0; i < a.volume->grid.num_samples(); ++i) k += s[i] != t[i];
  return k;
}

TEST(Handles, ThinHandleOnABallIsCutThickTorusKept) {
  // A ball with a thin ring (tube radius 1.3 voxels) through it: genus 1; a fat torus (tube 4.5)
  // elsewhere: genus 1, thicker than --max-handle 10 (strands under 10/π ≈ 3.2 voxels go).
  const Input in = volume_of(80, [](double x, double y, double z) {
    return std::max({ball(x, y, z, 30, 40, 40, 18), torus(x, y, z, 48, 40, 40, 1, 12, 1.3),
                     torus(x, y, z, 62, 15, 12, 2, 10, 4.5)});
  });
  const auto before = surface_topology(in);
  ASSERT_EQ(before.components, 2);
  ASSERT_EQ(before.chi, 0);  // two genus-1 surfaces
  HandleReport rep;
  const Input out = remove_handles(in, 0.0, 10, rep);
  const auto after = surface_topology(out);
  EXPECT_EQ(after.components, 2);
  EXPECT_EQ(after.chi, 2);  // the ball is a sphere again, the fat torus is still a torus
  EXPECT_EQ(after.boundary_loops, 0);
  EXPECT_EQ(after.nonmanifold_edges, 0);
  EXPECT_GE(rep.handles_cut, 1);
  EXPECT_EQ(rep.tunnels_filled, 0);
  EXPECT_EQ(rep.inside_euler_before, 0);
  EXPECT_EQ(rep.inside_euler_after, 1);
  // One thin layer of the strand changes side, nothing else.
  EXPECT_GT(changed_samples(in, out), 0);
  EXPECT_LT(changed_samples(in, out), 20);
  EXPECT_EQ(changed_samples(in, out), rep.cut_voxels + rep.plug_voxels);
  // A shorter loop length keeps the handle (1.3-voxel tube: loop ≈ 8 voxels).
  HandleReport none;
  const Input kept = remove_handles(in, 0.0, 5, none);
  EXPECT_EQ(surface_topology(kept).chi, 0);
  EXPECT_EQ(changed_samples(in, kept), 0);
}

TEST(Handles, ThinTunnelThroughASlabIsPlugged) {
  // A 14-voxel-thick slab pierced by a hole of radius 1.2: genus 1 through the outside.
  const Input in = volume_of(48, [](double x, double y, double z) {
    const double slab = std::min({7 - std::abs(z - 24), 16 - std::abs(x - 24), 16 - std::abs(y - 24)});
    const double hole = std::sqrt((x - 24.3) * (x - 24.3) + (y - 23.8) * (y - 23.8)) - 1.2;
    return std::min(slab, hole);
  });
  ASSERT_EQ(surface_topology(in).chi, 0);
  HandleReport rep;
  const Input out = remove_handles(in, 0.0, 12, rep);
  const auto after = surface_topology(out);
  EXPECT_EQ(after.components, 1);
  EXPECT_EQ(after.chi, 2);
  EXPECT_EQ(rep.handles_cut, 0);
  EXPECT_GE(rep.tunnels_filled, 1);
  EXPECT_LT(rep.plug_voxels, 30);  // a plug, not the whole hole
}

TEST(Handles, FloatingThinRingIsCutNotDeleted) {
  // A thin torus on its own: the opening removes all of it; it grows back from its deepest
  // voxel and is cut once, so it stays as one sphere-like component.
  const Input in = volume_of(40, [](double x, double y, double z) {
    return torus(x, y, z, 20, 20, 20, 2, 10, 1.4);
  });
  ASSERT_EQ(surface_topology(in).chi, 0);
  HandleReport rep;
  const Input out = remove_handles(in, 0.0, 12, rep);
  const auto after = surface_topology(out);
  EXPECT_EQ(after.components, 1);
  EXPECT_EQ(after.chi, 2);
  EXPECT_EQ(rep.handles_cut, 1);
}

TEST(Handles, CavitiesAndComponentsAreKept) {
  // A hollow ball (cavity inside) and a small separate ball: no loop anywhere, nothing changes.
  const Input in = volume_of(40, [](double x, double y, double z) {
    const double shell = std::min(ball(x, y, z, 18, 18, 18, 12), -ball(x, y, z, 18, 18, 18, 5));
    return std::max(shell, ball(x, y, z, 34, 34, 34, 2));
  });
  const auto before = surface_topology(in);
  ASSERT_EQ(before.components, 3);
  HandleReport rep;
  const Input out = remove_handles(in, 0.0, 30, rep);
  EXPECT_EQ(changed_samples(in, out), 0);
  EXPECT_EQ(surface_topology(out).components, 3);
  EXPECT_EQ(rep.inside_euler_before, 3);  // two balls and a cavity: b0 − b1 + b2 = 2 + 1
  EXPECT_EQ(rep.inside_euler_after, 3);
}

TEST(Handles, RejectsBadLength) {
  const Input in = volume_of(8, [](double x, double, double) { return x - 3.5; });
  HandleReport rep;
  for (const double bad : {0.0, -1.0, std::nan(""), double(INFINITY)}) {
    try {
      remove_handles(in, 0.0, bad, rep);
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_EQ(e.status(), Status::usage);
    }
  }
}

}  // namespace
}  // namespace adamesh
