// Benchmark peer (bench-full only): CGAL's Delaunay-refinement surface mesher (Boissonnat & Oudot
// 2005; CGAL::make_surface_mesh, as used by iso2mesh / pygalmesh) with a 30° facet angle bound,
// meshing the same field adamesh meshes (the trilinear interpolant of the samples, or the exact
// shape). The radius bound is calibrated so that the output has about `budget` triangles: one
// untimed calibration run for the first budget, then each budget's radius comes from the
// triangles-per-area ratio of the previous run, with up to two more runs when the count is off
// by more than 15 %. The time is that of the run reported, in memory.
//
//   peer_cgal INPUT [--iso V] [--res N] --out DIR --budgets 5000,20000,100000
//
// The mesher needs a closed surface inside a bounding sphere whose centre is inside the object:
// the function is the field (negative inside) within the grid and positive outside it, so an
// object cut by the grid's faces is closed by caps on them; the cap triangles (all three vertices
// on the grid's faces) are removed afterwards, leaving the open surface marching cubes gives.
// Writes DIR/cgal_<budget>.ply and prints the JSON line of peer_common.h.
#include <CGAL/Complex_2_in_triangulation_3.h>
#include <CGAL/Implicit_surface_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_default_triangulation_3.h>
#include <CGAL/IO/facets_in_complex_2_to_triangle_mesh.h>
#include <CGAL/make_surface_mesh.h>
#include <CGAL/version.h>

#include <cmath>

#include "adamesh/surfels.h"
#include "peer_common.h"

namespace {

using Tr = CGAL::Surface_mesh_default_triangulation_3;
using C2t3 = CGAL::Complex_2_in_triangulation_3<Tr>;
using GT = Tr::Geom_traits;
using Point_3 = GT::Point_3;
using Sphere_3 = GT::Sphere_3;
using FT = GT::FT;

/// Negative inside the object, positive outside it and outside the grid.
struct Function {
  const adamesh::ScalarField* field = nullptr;
  const adamesh::Grid* grid = nullptr;
  double iso = 0, inside_sign = 1;
  FT operator()(const Point_3& p) const {
    const adamesh::Vec3 w{p.x(), p.y(), p.z()};
    const adamesh::Vec3 ijk = grid->to_index(w);
    for (int a = 0; a < 3; ++a)
      if (ijk[a] < 0 || ijk[a] > static_cast<double>(grid->dims[a] - 1)) return FT(1);
    const double v = -inside_sign * (field->value(w) - iso);
    return FT(v == 0 ? 1e-300 : v);  // samples equal to iso count as inside: keep the sign strict
  }
};

using Surface_3 = CGAL::Implicit_surface_3<GT, Function>;

double mesh_area(const adamesh::Mesh& m) {
  double a = 0;
  for (std::size_t t = 0; t < m.num_triangles(); ++t) {
    const adamesh::Vec3 p = m.vertex(m.triangles[3 * t]), q = m.vertex(m.triangles[3 * t + 1]),
                        r = m.vertex(m.triangles[3 * t + 2]);
    a += 0.5 * adamesh::norm(adamesh::cross(q - p, r - p));
  }
  return a;
}

/// Meshes the surface with radius bound r; returns the mesh without cap triangles.
adamesh::Mesh mesh_surface(const Surface_3& surface, double r, const adamesh::Grid& grid) {
  Tr tr;
  C2t3 c2t3(tr);
  CGAL::Surface_mesh_default_criteria_3<Tr> criteria(30.0, r, r / 5.0);
  CGAL::make_surface_mesh(c2t3, surface, criteria, CGAL::Manifold_tag(), 30);
  CGAL::Surface_mesh<Point_3> sm;
  CGAL::facets_in_complex_2_to_triangle_mesh(c2t3, sm);

  adamesh::Mesh all;
  std::vector<std::uint32_t> index(sm.number_of_vertices() + sm.number_of_removed_vertices());
  for (auto v : sm.vertices()) {
    const Point_3& p = sm.point(v);
    index[v.idx()] = all.add_vertex({p.x(), p.y(), p.z()});
  }
  const double tol = 1e-4 * std::max<double>({1.0, double(grid.dims[0]), double(grid.dims[1]),
                                               double(grid.dims[2])});  // index units
  std::vector<std::uint32_t> tris;
  for (auto f : sm.faces()) {
    std::uint32_t v[3];
    int k = 0;
    for (auto h : CGAL::halfedges_around_face(sm.halfedge(f), sm)) v[k++] = index[sm.target(h).idx()];
    // A cap triangle has its three vertices on the grid's boundary (one face, or two faces
    // where it wraps around an edge of the grid); the iso-surface's own triangles have at most
    // their rim edge there.
    bool cap = true;
    for (int c = 0; c < 3 && cap; ++c) {
      const adamesh::Vec3 ijk = grid.to_index(all.vertex(v[c]));
      bool on_face = false;
      for (int a = 0; a < 3; ++a)
        on_face = on_face || std::abs(ijk[a]) < tol ||
                  std::abs(ijk[a] - double(grid.dims[a] - 1)) < tol;
      cap = on_face;
    }
    if (!cap) tris.insert(tris.end(), {v[0], v[1], v[2]});
  }
  return peer::compact(all.positions, tris);
}

}  // namespace

int main(int argc, char** argv) {
  peer::Options opt = peer::parse(argc, argv);
  return peer::run_main(argv[0], [&] {
    const adamesh::Input in = peer::load(opt);
    const adamesh::Volume& vol = *in.volume;
    const adamesh::Grid& grid = vol.grid;

    // Area of the marching cubes surface (for the radius calibration; not timed).
    const double area = mesh_area(
        adamesh::marching_cubes(adamesh::build_surfels(vol, opt.iso, in.inside_sign)));

    // Bounding sphere centred on the deepest inside sample, reaching every grid corner.
    std::int64_t best = 0;
    double best_v = -1e300;
    for (std::int64_t i = 0; i < grid.num_samples(); ++i) {
      const double v = in.inside_sign * (vol.at(i) - opt.iso);
      if (v > best_v) best_v = v, best = i;
    }
    const std::int64_t bi = best % grid.dims[0], bj = (best / grid.dims[0]) % grid.dims[1],
                       bk = best / (grid.dims[0] * grid.dims[1]);
    const adamesh::Vec3 centre = grid.to_world({double(bi), double(bj), double(bk)});
    double radius = 0;
    for (int c = 0; c < 8; ++c) {
      const adamesh::Vec3 corner = grid.to_world({c & 1 ? double(grid.dims[0] - 1) : 0.0,
                                                  c & 2 ? double(grid.dims[1] - 1) : 0.0,
                                                  c & 4 ? double(grid.dims[2] - 1) : 0.0});
      radius = std::max(radius, adamesh::norm(corner - centre));
    }
    radius *= 1.01;
    const Function fn{in.field.get(), &grid, opt.iso, in.inside_sign};
    const Surface_3 surface(fn, Sphere_3(Point_3(centre.x, centre.y, centre.z), radius * radius),
                            1e-6);

    nlohmann::json out;
    out["method"] = "CGAL make_surface_mesh (30 deg)";
    out["cgal_version"] = CGAL_VERSION_STR;
    out["threads"] = 1;
    out["criteria"] = "facet angle >= 30 deg, radius r (calibrated), distance r/5";
    out["meshes"] = nlohmann::json::array();
    // Triangles ≈ k · area / r²; k starts at 1/0.64 (circumradius ≈ 0.7 r, near-equilateral).
    double k = 1.0 / 0.64;
    bool calibrated = false;
    for (std::size_t budget : opt.budgets) {
      double r = std::sqrt(k * area / static_cast<double>(budget));
      if (!calibrated) {
        const adamesh::Mesh trial = mesh_surface(surface, r, grid);
        if (trial.num_triangles() > 0)
          k *= static_cast<double>(trial.num_triangles()) / static_cast<double>(budget);
        r = std::sqrt(k * area / static_cast<double>(budget));
        calibrated = true;
      }
      // Up to three tries to land within 15 % of the budget; the accepted run is the timed one.
      adamesh::Mesh m;
      double s = 0;
      for (int attempt = 0; attempt < 3; ++attempt) {
        const peer::Stopwatch clock;
        m = mesh_surface(surface, r, grid);
        s = clock.seconds();
        if (m.num_triangles() == 0) break;
        k = static_cast<double>(m.num_triangles()) * r * r / area;
        const double off = static_cast<double>(m.num_triangles()) / static_cast<double>(budget);
        if (off > 0.85 && off < 1.15) break;
        r = std::sqrt(k * area / static_cast<double>(budget));
      }
      const std::string path = opt.out_dir + "/cgal_" + std::to_string(budget) + ".ply";
      adamesh::write_mesh(m, path);
      out["meshes"].push_back({{"budget", budget},
                               {"triangles", m.num_triangles()},
                               {"time_s", s},
                               {"radius_bound", r},
                               {"path", path}});
    }
    out["peak_rss_mb"] = peer::peak_rss_mb();
    std::cout << out.dump() << "\n";
  });
}
