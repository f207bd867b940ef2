// `adamesh level`: cuts a mesh from a stored refinement hierarchy (.amh) without the volume —
// a uniform level, an error bound, or a triangle budget (docs/HIERARCHY.md).
#include <cmath>
#include <iostream>
#include <sstream>
#include <vector>

#include "adamesh/error.h"
#include "adamesh/extract.h"
#include "adamesh/improve.h"
#include "adamesh/input.h"
#include "adamesh/io.h"
#include "adamesh/refine.h"
#include "args.h"
#include "commands.h"
#include "outputs.h"

namespace adamesh::cli {

namespace {

std::vector<OptionSpec> level_specs() {
  std::vector<OptionSpec> s = {
                      {"--level", true, "uniform level K: splits of triangles of level < K"},
                      {"--max-error", true, "the splits whose error bound exceeds E (world units)"},
                      {"--triangles", true, "the longest prefix of splits with at most N triangles"},
                      {"--all", false, "every split: the finest mesh"},
                      {"-o", true,
                       "output mesh (.ply .obj .off .stl .glb .gltf); - for standard output "
                       "(needs --format)"},
                      {"--format", true,
                       "format of -o -: ply obj off stl glb (a file's format comes from its "
                       "extension)"},
                      {"--partial", false, "accept a file cut short in its split list"},
                      {"--improve", false,
                       "shape improvement without the volume (flips within 0.25 voxel of the "
                       "cut, tangential moves, needle collapses; last, after any fit, pushes that "
                       "separate intersecting triangles; docs/QUALITY.md)"},
                      {"--fit", true,
                       "least-squares vertex offsets along the normals against the volume INPUT "
                       "the hierarchy was made from (what extract writes by default; "
                       "docs/QUALITY.md \"Fit\"); input options as for extract"},
                      {"--fit-finest", false,
                       "the same fit without the volume: against the hierarchy's finest mesh "
                       "(every split), which stands for the surface"},
                      {"--ascii", false, "ASCII PLY instead of binary"},
                      {"--quiet", false, "no summary line"},
                      compress_option_spec(),
  };
  for (auto& o : input_option_specs()) s.push_back(o);
  return s;
}

}  // namespace

int cmd_level(const Argv& argv) {
  const Args args("level", argv, level_specs());
  if (args.help_requested()) {
    std::cout << args.usage("FILE.amh (--level K | --max-error E | --triangles N | --all) "
                            "-o mesh.ply|- [--format F] [--fit INPUT | --fit-finest]")
              << "\n-o - --format ply writes the mesh to standard output (ply obj off stl glb; "
                 "binary formats\nare refused on a terminal); the summary then goes to stderr.\n";
    return 0;
  }
  args.expect_positionals(1, 1, "FILE.amh");
  const int cuts = args.has("--level") + args.has("--max-error") + args.has("--triangles") +
                   args.has("--all");
  if (cuts != 1)
    fail(Status::usage, "adamesh level: give exactly one of --level, --max-error, --triangles, --all");
  const auto out = args.get("-o");
  if (!out) fail(Status::usage, "adamesh level: -o FILE is required");
  check_outputs("level", args, {{"-o", OutputKind::mesh, true}});
  const MeshWriteOptions wo = mesh_output_options(args, "-o");
  std::ostream& info = is_stdout(*out) ? std::cerr : std::cout;  // stdout: the mesh alone

  const std::string path = args.positionals()[0];
  HierarchyReadOptions ro;
  ro.allow_partial = args.has("--partial");
  const Hierarchy h = read_hierarchy(path, ro);

  CutMesh cut;
  std::string what;
  if (auto k = args.get_int("--level")) {
    if (*k < 0 || *k > 255) fail(Status::usage, "adamesh level: --level must be 0..255");
    cut = extract_level(h, static_cast<int>(*k));
    what = "level " + std::to_string(*k);
  } else if (auto e = args.get_double("--max-error")) {
    if (!(*e >= 0)) fail(Status::usage, "adamesh level: --max-error must be >= 0");
    cut = extract_max_error(h, *e);
    what = "max error " + args.get("--max-error").value();
  } else if (auto n = args.get_int("--triangles")) {
    if (*n < 0) fail(Status::usage, "adamesh level: --triangles must be >= 0");
    cut = extract_triangles(h, static_cast<std::size_t>(*n));
    what = "at most " + std::to_string(*n) + " triangles";
  } else {
    cut = extract_all(h);
    what = "all splits";
  }
  if (args.has("--improve")) {
    // Without the volume: flips are judged against the cut's own surface, moves stay in the
    // vertex's tangent plane; the triangle count is kept.
    ImproveOptions io;
    io.voxel = h.voxel;
    io.box = h.bounds;
    io.target_triangles = cut.mesh.num_triangles();
    std::vector<std::uint32_t> map;
    improve_mesh(cut.mesh, cut.vertex_border, nullptr, h.iso, io, &map);
    cut.vertex_border = remap_vertex_flags(cut.vertex_border, map, cut.mesh.num_vertices());  // for --fit
    what += ", improved";
  }
  if (args.has("--fit") && args.has("--fit-finest"))
    fail(Status::usage, "adamesh level: give --fit INPUT or --fit-finest, not both");
  if (args.has("--fit-finest")) {
    const FitStats st = fit_cut_to_finest(cut, h);
    std::ostringstream w;
    w << ", fitted to the finest mesh: RMS distance to it " << st.rms_before << " -> " << st.rms_after;
    what += w.str();
  }
  if (const auto spec = args.get("--fit")) {
    const Input in = load_input(*spec, input_options_from(args));
    // The wrong volume would pull the vertices towards another surface: its box must be the
    // hierarchy's (to a voxel).
    const Box b = in.field->domain();
    for (int k = 0; k < 3; ++k)
      if (!(std::abs(b.lo[k] - h.bounds.lo[k]) <= h.voxel && std::abs(b.hi[k] - h.bounds.hi[k]) <= h.voxel))
        fail(Status::usage, "adamesh level: --fit " + in.spec + ": its box is not the box of " + path +
                                " (a different volume, or other input options than extract had)");
    FitOptions fo;
    fo.max_step = 0.25 * h.voxel;
    fo.box = b;
    if (in.volume) fo.faces = oblique_faces(in.volume->grid);
    const FitStats st = fit_least_squares(cut.mesh, cut.vertex_border, *in.field, h.iso, fo);
    std::ostringstream w;
    w << ", fitted: RMS distance " << st.rms_before << " -> " << st.rms_after;
    what += w.str();
  }
  if (args.has("--improve")) {
    // Last, as extract does: the intersecting pairs a small push separates.
    SeparateOptions so;
    so.voxel = h.voxel;
    so.box = h.bounds;
    const SeparateStats st = separate_crossings(cut.mesh, cut.vertex_border, so);
    std::ostringstream w;
    w << ", intersecting triangle pairs " << st.intersections_before << " -> " << st.intersections_after;
    what += w.str();
  }
  write_mesh_output(cut.mesh, *out, wo);
  if (!args.has("--quiet")) {
    info << path << " (" << what << "): " << cut.mesh.num_triangles() << " triangles, "
              << cut.mesh.num_vertices() << " vertices, depth " << cut.max_level << ", "
              << cut.splits_applied << " of " << h.splits.size() << " splits";
    if (cut.max_error > 0) info << ", error bound " << cut.max_error;
    info << "\n";
  }
  return 0;
}

}  // namespace adamesh::cli
