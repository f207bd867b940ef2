// Benchmark peer (bench-full only): VTK's vtkFlyingEdges3D (Schroeder, Maynard & Geveci 2015)
// on the same samples adamesh reads, then vtkQuadricDecimation (Garland & Heckbert 1997) to each
// triangle budget — the 3D Slicer / VTK route. Times are in memory: the copy of the samples into
// a vtkImageData and the conversion of the output are not timed.
//
//   peer_vtk INPUT [--iso V] [--res N] --out DIR --budgets 5000,20000,100000 [--threads N]
//
// Writes DIR/flying_edges.ply and DIR/vtkquadric_<budget>.ply, prints the JSON line of
// peer_common.h ("extract_s" is the Flying Edges time, "meshes" the decimated meshes).
// Debian's VTK uses its TBB SMP backend (the system oneTBB, as adamesh does), so --threads caps
// it with a tbb::global_control (vtkSMPTools.h itself does not compile as C++20 in VTK 9.1).
// Flying Edges runs in index space (spacing 1, origin 0) and its points are mapped to world
// coordinates with the grid's index-to-world matrix, so oblique grids (NIfTI) come out right.
#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkFlyingEdges3D.h>
#include <vtkIdList.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkQuadricDecimation.h>
#include <vtkVersion.h>

#include <tbb/global_control.h>

#include <memory>

#include "peer_common.h"

namespace {

adamesh::Mesh to_mesh(vtkPolyData* pd, const adamesh::Grid* grid) {
  adamesh::Mesh m;
  vtkPoints* pts = pd->GetPoints();
  const vtkIdType n = pts ? pts->GetNumberOfPoints() : 0;
  m.positions.reserve(3 * static_cast<std::size_t>(n));
  for (vtkIdType i = 0; i < n; ++i) {
    double p[3];
    pts->GetPoint(i, p);
    adamesh::Vec3 w{p[0], p[1], p[2]};
    if (grid) w = grid->to_world(w);
    m.add_vertex(w);
  }
  vtkCellArray* polys = pd->GetPolys();
  vtkNew<vtkIdList> ids;
  polys->InitTraversal();
  while (polys->GetNextCell(ids)) {
    if (ids->GetNumberOfIds() != 3) continue;
    m.add_triangle(static_cast<std::uint32_t>(ids->GetId(0)), static_cast<std::uint32_t>(ids->GetId(1)),
                   static_cast<std::uint32_t>(ids->GetId(2)));
  }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  peer::Options opt = peer::parse(argc, argv);
  return peer::run_main(argv[0], [&] {
    std::unique_ptr<tbb::global_control> limit;
    if (opt.threads > 0)
      limit = std::make_unique<tbb::global_control>(
          tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(opt.threads));
    const adamesh::Input in = peer::load(opt);
    const adamesh::Volume& vol = *in.volume;
    const auto& d = vol.grid.dims;

    vtkNew<vtkImageData> image;
    image->SetDimensions(static_cast<int>(d[0]), static_cast<int>(d[1]), static_cast<int>(d[2]));
    image->SetSpacing(1, 1, 1);
    image->SetOrigin(0, 0, 0);
    vtkNew<vtkFloatArray> scalars;
    scalars->SetName("f");
    scalars->SetNumberOfTuples(vol.grid.num_samples());
    float* s = scalars->GetPointer(0);
    for (std::int64_t i = 0; i < vol.grid.num_samples(); ++i) s[i] = static_cast<float>(vol.at(i));
    image->GetPointData()->SetScalars(scalars);

    const peer::Stopwatch fe_clock;
    vtkNew<vtkFlyingEdges3D> fe;
    fe->SetInputData(image);
    fe->SetValue(0, opt.iso);
    fe->ComputeNormalsOff();
    fe->ComputeGradientsOff();
    fe->ComputeScalarsOff();
    fe->Update();
    const double fe_s = fe_clock.seconds();
    vtkPolyData* surface = fe->GetOutput();
    const adamesh::Mesh full = to_mesh(surface, &vol.grid);
    adamesh::write_mesh(full, opt.out_dir + "/flying_edges.ply");

    nlohmann::json out;
    out["method"] = "vtkFlyingEdges3D+vtkQuadricDecimation";
    out["vtk_version"] = vtkVersion::GetVTKVersion();
    out["threads"] = opt.threads;
    out["extract_s"] = fe_s;
    out["extract_triangles"] = full.num_triangles();
    out["extract_path"] = opt.out_dir + "/flying_edges.ply";
    out["meshes"] = nlohmann::json::array();
    const double tris = static_cast<double>(full.num_triangles());
    for (std::size_t budget : opt.budgets) {
      if (static_cast<double>(budget) >= tris) continue;
      const peer::Stopwatch clock;
      vtkNew<vtkQuadricDecimation> dec;
      dec->SetInputData(surface);
      dec->SetTargetReduction(1.0 - static_cast<double>(budget) / tris);
      dec->Update();
      const double dec_s = clock.seconds();
      const adamesh::Mesh m = to_mesh(dec->GetOutput(), &vol.grid);
      const std::string path = opt.out_dir + "/vtkquadric_" + std::to_string(budget) + ".ply";
      adamesh::write_mesh(m, path);
      out["meshes"].push_back({{"budget", budget},
                               {"triangles", m.num_triangles()},
                               {"time_s", fe_s + dec_s},
                               {"decimate_s", dec_s},
                               {"path", path}});
    }
    out["peak_rss_mb"] = peer::peak_rss_mb();
    std::cout << out.dump() << "\n";
  });
}
