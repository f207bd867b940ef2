// `adamesh mc INPUT --iso V -o MESH|- [--format F] [--threads N] [--quiet] [--ascii]`: reference marching cubes
// (Lorensen & Cline 1987) on the face-consistent surfel complex (asymptotic decider, Nielson &
// Hamann 1991): watertight where closed, 2-manifold, consistently oriented (ALGORITHM.md 2.2).
#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/input.h"
#include "adamesh/io.h"
#include "adamesh/surfels.h"
#include "args.h"
#include "commands.h"
#include "outputs.h"

namespace adamesh::cli {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

int cmd_mc(const Argv& argv) {
  std::vector<OptionSpec> specs = input_option_specs();
  specs.push_back({"--iso", true, "iso-value (default: the input's own, e.g. 0 for shapes)"});
  specs.push_back({"-o", true,
                   "output mesh (.ply .obj .off .stl .glb .gltf), written atomically; - for "
                   "standard output (needs --format)"});
  specs.push_back({"--format", true,
                   "format of -o -: ply obj off stl glb (a file's format comes from its extension)"});
  specs.push_back({"--threads", true, "worker threads, 0 = all (default); output is identical"});
  specs.push_back({"--ascii", false, "PLY: write ASCII instead of binary"});
  specs.push_back({"--quiet", false, "print nothing on success"});
  specs.push_back(compress_option_spec());
  const Args args("mc", argv, specs);
  if (args.help_requested()) {
    std::cout << args.usage("INPUT [--iso V] -o MESH|- [--format F] [--threads N] [--ascii] [--quiet]")
              << "\nMarching cubes on the surfel complex: one vertex per sign-changing voxel edge, "
                 "ambiguous faces\nresolved by the asymptotic decider, each cell polygon "
                 "triangulated for the largest minimum\nangle. Samples equal to the iso-value "
                 "count as inside. Prints triangles, vertices, time and\nvoxels per second.\n"
                 "\n-o - --format ply writes the mesh to standard output (ply obj off stl glb; "
                 "binary formats\nare refused on a terminal); the summary then goes to stderr, "
                 "so stdout holds the mesh alone.\n";
    return 0;
  }
  args.expect_positionals(1, 1, "INPUT");
  const auto out_path = args.get("-o");
  if (!out_path) fail(Status::usage, "adamesh mc: missing -o MESH (see adamesh mc --help)");
  const std::int64_t threads = args.get_int("--threads").value_or(0);
  if (threads < 0 || threads > 4096)
    fail(Status::usage, "adamesh mc: --threads must be between 0 and 4096");
  check_outputs("mc", args, {{"-o", OutputKind::mesh, true}});  // before any work
  const MeshWriteOptions write_options = mesh_output_options(args, "-o");
  std::ostream& info = is_stdout(*out_path) ? std::cerr : std::cout;  // stdout: the mesh alone

  const auto t_load = std::chrono::steady_clock::now();
  const Input in = load_input(args.positionals()[0], input_options_from(args));
  const double load_s = seconds_since(t_load);
  double iso = 0;
  if (const auto v = args.get_double("--iso")) iso = *v;
  else if (in.default_iso) iso = *in.default_iso;
  else
    fail(Status::usage, "adamesh mc: " + in.spec +
                            " has no default iso-value; give --iso V (adamesh info suggests one)");
  check_iso_in_range(in, iso);  // as extract: an iso-value outside the data is an error

  ExecutionContext ctx;
  ctx.threads = static_cast<int>(threads);
  tbb::task_arena arena(ctx.threads > 0 ? ctx.threads : tbb::task_arena::automatic);
  const auto t_mesh = std::chrono::steady_clock::now();
  Mesh mesh;
  std::size_t surfels = 0;
  // Straight from the volume: the mesh of marching_cubes(build_surfels(...)) without the complex.
  arena.execute([&] { mesh = marching_cubes(*in.volume, iso, in.inside_sign, ctx, &surfels); });
  const double mesh_s = seconds_since(t_mesh);

  const auto t_write = std::chrono::steady_clock::now();
  write_mesh_output(mesh, *out_path, write_options);
  const double write_s = seconds_since(t_write);

  if (!args.has("--quiet")) {
    const auto& d = in.volume->grid.dims;
    const double voxels = double(std::max<std::int64_t>(d[0] - 1, 0)) *
                          double(std::max<std::int64_t>(d[1] - 1, 0)) *
                          double(std::max<std::int64_t>(d[2] - 1, 0));
    info << "mc: " << mesh.num_triangles() << " triangles, " << mesh.num_vertices()
              << " vertices, " << surfels << " surfels at iso " << iso << "\n"
              << "time: " << fixed(mesh_s, 3) << " s extraction ("
              << fixed(voxels / std::max(mesh_s, 1e-9) / 1e6, 1) << " M voxels/s, " << d[0] << "x"
              << d[1] << "x" << d[2] << "), " << fixed(load_s, 3) << " s input, "
              << fixed(write_s, 3) << " s output\n"
              << "wrote " << (is_stdout(*out_path) ? "standard output" : *out_path) << "\n";
  }
  return 0;
}

}  // namespace adamesh::cli
