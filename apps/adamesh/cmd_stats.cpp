// `adamesh stats MESH [--field INPUT [--iso V]] [--reference MESH] [--json]`: topology, triangle
// quality, area and volume of a mesh; with --field its distance to the input's iso-surface and
// the edge/normal deviations ε_e, ε_n; with --reference the Hausdorff distances to another mesh.
// Every number is defined in docs/METRICS.md.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>

#include "adamesh/context.h"
#include "adamesh/error.h"
#include "adamesh/input.h"
#include "adamesh/io.h"
#include "adamesh/metrics.h"
#include "args.h"
#include "commands.h"

namespace adamesh::cli {

int cmd_stats(const Argv& argv) {
  std::vector<OptionSpec> specs = input_option_specs();
  specs.push_back({"--field", true, "INPUT whose iso-surface the mesh approximates (file, shape:, expr:)"});
  specs.push_back({"--iso", true, "iso-value of --field (default: the input's own, e.g. 0 for shapes)"});
  specs.push_back({"--reference", true, "MESH to measure Hausdorff distances against"});
  specs.push_back({"--samples", true, "sample points for the distances (default: triangles, 2e5..2e6)"});
  specs.push_back({"--threads", true, "worker threads, 0 = all (default); results are identical"});
  specs.push_back({"--json", false, "print a JSON object (keys in docs/METRICS.md)"});
  const Args args("stats", argv, specs);
  if (args.help_requested()) {
    std::cout << args.usage("MESH [--field INPUT [--iso V]] [--reference MESH] [--json]")
              << "\nReports topology (Euler characteristic, components, boundary loops, genus,\n"
                 "non-manifold edges and vertices, degenerate and duplicate triangles, "
                 "orientation),\ntriangle quality (angles, radius ratio histogram), area and "
                 "volume. With --field:\ndistance of area-weighted sample points to the "
                 "iso-surface, eps_e and eps_n.\nWith --reference: one-sided and symmetric "
                 "Hausdorff distances. Definitions:\ndocs/METRICS.md.\n";
    return 0;
  }
  args.expect_positionals(1, 1, "MESH");
  const std::int64_t threads = args.get_int("--threads").value_or(0);
  if (threads < 0 || threads > 4096)
    fail(Status::usage, "adamesh stats: --threads must be between 0 and 4096");
  const std::int64_t samples = args.get_int("--samples").value_or(0);
  if (samples < 0 || samples > 1'000'000'000)
    fail(Status::usage, "adamesh stats: --samples must be between 0 (default) and 1e9");
  if (args.has("--iso") && !args.has("--field"))
    fail(Status::usage, "adamesh stats: --iso needs --field INPUT");

  const auto t0 = std::chrono::steady_clock::now();
  const std::string& path = args.positionals()[0];
  const Mesh mesh = read_mesh(path);
  ExecutionContext ctx;
  ctx.threads = static_cast<int>(threads);
  MeshReport report = mesh_report(mesh, ctx);

  if (const auto spec = args.get("--field")) {
    const Input in = load_input(*spec, input_options_from(args));
    double iso = 0;
    if (const auto v = args.get_double("--iso")) iso = *v;
    else if (in.default_iso) iso = *in.default_iso;
    else
      fail(Status::usage, "adamesh stats: " + in.spec +
                              " has no default iso-value; give --iso V (adamesh info suggests one)");
    FieldErrorOptions fo;
    fo.inside_sign = in.inside_sign;
    fo.max_step = in.volume->grid.min_spacing();  // one voxel per Newton step
    fo.tolerance = 1e-5 * fo.max_step;
    fo.samples = samples;
    report.field = field_error(mesh, *in.field, iso, fo, ctx);
    report.volume_bounds = vertices_outside_volume(mesh, in.volume->grid);
  }
  if (const auto ref_path = args.get("--reference")) {
    const Mesh ref = read_mesh(*ref_path);
    HausdorffOptions ho;
    ho.samples = samples;
    report.hausdorff = hausdorff(mesh, ref, ho, ctx);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  if (args.has("--json")) {
    std::cout << report_json(report);
  } else {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3f", seconds);
    std::cout << path << "\n" << report_text(report) << "time: " << buf << " s\n";
  }
  return 0;
}

}  // namespace adamesh::cli
