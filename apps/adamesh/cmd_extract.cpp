// `adamesh extract`: parses the options into ExtractOptions, runs the library's pipeline
// (adamesh/extract.h: surfels → graph → covering → base mesh → 4-8 refinement) and writes the
// files asked for.
#include <cmath>
#include <filesystem>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "adamesh/atomic_file.h"
#include "adamesh/error.h"
#include "adamesh/extract.h"
#include "adamesh/io.h"
#include "args.h"
#include "cli_util.h"
#include "commands.h"
#include "outputs.h"

namespace adamesh::cli {

namespace {

std::vector<OptionSpec> extract_specs() {
  std::vector<OptionSpec> s = {
      {"--iso", true, "iso-value (default: the input's default, 0 for shape:/expr:)"},
      {"--base", true, "write the base mesh M0 here (.ply .obj .off .stl .glb .gltf)"},
      {"--rmax", true, "largest disk radius, world units (default sqrt(area/1000))"},
      {"--rmin", true, "smallest disk radius, world units (default 2 voxels)"},
      {"--voxels", false, "--rmax/--rmin are in voxel edge lengths instead of world units"},
      {"--min-component", true, "drop components with fewer surfels (default 0: keep all)"},
      {"--threads", true, "worker threads (default: all cores); output does not depend on it"},
      {"--report", true, "write a JSON report (sizes, topology, timings, peak memory)"},
      {"--validate", false, "run the covering validator (slow) and add it to the report"},
      {"--attributes", false, "write per-vertex border/component attributes (PLY)"},
      {"--ascii", false, "ASCII PLY instead of binary"},
      {"--quiet", false, "no progress or summary output"},
      {"-o", true,
       "write the refined mesh here (.ply .obj .off .stl .glb .gltf); - for standard output "
       "(needs --format)"},
      {"--levels", true, "uniform refinement: K levels; the output is M_K"},
      {"--max-error", true,
       "adaptive: split until every triangle's estimated distance to the surface is under E, "
       "world units; the summary gives the measured p99 and maximum and says when the p99 is "
       "above E (default: 0.25 voxel, at most as many triangles as marching cubes)"},
      {"--triangles", true, "adaptive: the N-triangle mesh, worst triangles split first"},
      {"--hierarchy", true, "write the refinement hierarchy (.amh, see docs/HIERARCHY.md)"},
      {"--labels", true,
       "label maps: 'all' meshes every label but 0 into -o DIR/ (DIR/label_L.EXT, a summary "
       "table and DIR/labels.json)"},
      {"--format", true,
       "with -o -: the format of standard output (ply obj off stl glb); with --labels all: mesh "
       "format of the files (ply obj off stl; default ply)"},
      {"--min-cavity", true,
       "topology control: fill cavities (enclosed pockets of outside) of fewer voxels than this"},
      {"--max-handle", true,
       "topology control: cut handles and plug tunnels whose shortest loop is shorter than L "
       "voxels (strands thinner than L/pi; docs/TOPOLOGY.md)"},
      {"--fit", true,
       "vertex positions of the written mesh: 'l2' (least-squares offsets along the normals: "
       "error on both sides of the surface, lower RMS; docs/QUALITY.md), 'surface' (on the "
       "iso-surface, as the .amh's cuts have them) or 'auto' (the default: l2 for adaptive "
       "meshes, surface for --levels and --no-improve)"},
      {"--no-improve", false,
       "no shape improvement of M0 and of the written mesh (flips, moves, collapses; "
       "docs/QUALITY.md): the output is the hierarchy's cut as it is"},
      compress_option_spec(),
  };
  for (auto& o : input_option_specs()) s.push_back(o);
  return s;
}

/// The options of the library call, checked with the command line's wording.
ExtractOptions extract_options(const Args& args, const std::string& spec) {
  ExtractOptions opt;
  const int budgets = args.has("--levels") + args.has("--max-error") + args.has("--triangles");
  if (budgets > 1)
    fail(Status::usage, "adamesh extract: give at most one of --levels, --max-error, --triangles");
  if (auto t = args.get_int("--threads")) {
    if (*t < 1 || *t > 1024) fail(Status::usage, "adamesh extract: --threads must be 1..1024");
    opt.context.threads = static_cast<int>(*t);
  }
  if (auto v = args.get_double("--iso")) {
    if (!std::isfinite(*v)) fail(Status::usage, "adamesh extract: --iso must be finite");
    opt.iso = *v;
  } else if (!is_implicit_spec(spec) && !args.has("--label") && !args.has("--labels")) {
    fail(Status::usage, "adamesh extract: " + spec + ": --iso is required for volume files");
  }
  if (auto k = args.get_int("--levels")) {
    if (*k < 0 || *k > 30) fail(Status::usage, "adamesh extract: --levels must be 0..30");
    opt.budget = Budget::levels;
    opt.levels = static_cast<int>(*k);
  } else if (auto n = args.get_int("--triangles")) {
    if (*n < 1) fail(Status::usage, "adamesh extract: --triangles must be >= 1");
    opt.budget = Budget::triangles;
    opt.triangles = static_cast<std::size_t>(*n);
  } else if (auto e = args.get_double("--max-error")) {
    if (!(*e > 0) || !std::isfinite(*e))
      fail(Status::usage, "adamesh extract: --max-error must be > 0");
    opt.budget = Budget::max_error;
    opt.max_error = *e;
  } else if (!args.has("-o") && !args.has("--hierarchy")) {
    opt.budget = Budget::none;  // the base mesh and/or the report only
  }
  if (auto r = args.get_double("--rmax")) opt.r_max = *r;
  if (auto r = args.get_double("--rmin")) opt.r_min = *r;
  if (opt.r_max < 0 || opt.r_min < 0) fail(Status::usage, "adamesh extract: radii must be positive");
  if (args.has("--voxels")) opt.unit = LengthUnit::voxels;
  if (auto m = args.get_int("--min-component")) {
    if (*m < 0) fail(Status::usage, "adamesh extract: --min-component must be >= 0");
    opt.min_component = static_cast<std::size_t>(*m);
  }
  opt.validate = args.has("--validate");
  opt.improve = !args.has("--no-improve");
  if (auto f = args.get("--fit")) {
    if (*f == "l2") opt.fit = ExtractOptions::Fit::l2;
    else if (*f == "surface") opt.fit = ExtractOptions::Fit::surface;
    else if (*f == "auto") opt.fit = ExtractOptions::Fit::automatic;
    else
      fail(Status::usage,
           "adamesh extract: --fit must be 'auto', 'surface' or 'l2', not '" + *f + "'");
  }
  if (auto c = args.get_int("--min-cavity")) {
    if (*c < 0) fail(Status::usage, "adamesh extract: --min-cavity must be >= 0");
    opt.min_cavity = *c;
  }
  if (auto h = args.get_double("--max-handle")) {
    if (!(*h >= 0) || !std::isfinite(*h))
      fail(Status::usage, "adamesh extract: --max-handle must be a length >= 0 (voxels)");
    opt.max_handle = *h;
  }
  opt.measure_levels = args.has("--report");
  return opt;
}

}  // namespace

/// `--labels all -o DIR/`: one extract() per label of a label map (every label but 0, the
/// background), DIR/label_L.EXT each, a table on stdout and DIR/labels.json.
int extract_all_labels(const Args& args, const std::string& spec, const ExtractOptions& opt) {
  const std::string which = *args.get("--labels");
  if (which != "all") fail(Status::usage, "adamesh extract: --labels takes 'all' (one label: --label L)");
  if (args.has("--label") || args.has("--iso"))
    fail(Status::usage, "adamesh extract: --labels all meshes every label at iso 0.5 of its mask; "
                        "drop --label/--iso");
  if (args.has("--base") || args.has("--hierarchy") || args.has("--report"))
    fail(Status::usage, "adamesh extract: --labels all writes one mesh per label into -o DIR/ "
                        "(and DIR/labels.json); --base, --hierarchy and --report are per mesh");
  const auto out = args.get("-o");
  if (!out) fail(Status::usage, "adamesh extract: --labels all needs -o DIR/");
  if (is_stdout(*out))
    fail(Status::usage, "adamesh extract: --labels all writes one file per label into -o DIR/, "
                        "not to standard output");
  const std::filesystem::path dir(*out);
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    fail(Status::output_failed, *out + ": --labels all writes into a folder, and this one does not "
                                       "exist (create it first)");
  check_output_target((dir / "labels.json").string());  // the folder is writable, before any work
  const std::string ext = args.get("--format").value_or("ply");
  if (ext != "ply" && ext != "obj" && ext != "off" && ext != "stl")
    fail(Status::usage, "adamesh extract: --format must be ply, obj, off or stl");
  const bool quiet = args.has("--quiet");
  InputOptions io = input_options_from(args);
  const Input in = load_input(spec, io);
  const std::vector<LabelCount> labels = label_counts(*in.volume);
  if (labels.empty())
    fail_input(spec, "not a label map (a floating volume, or more than 64 distinct values): "
                     "mesh it with --iso V");
  MeshWriteOptions wo;
  wo.ascii = args.has("--ascii");
  nlohmann::json table = nlohmann::json::array();
  if (!quiet)
    std::printf("   label       voxels  triangles  components     χ   seconds  file\n");
  for (const LabelCount& l : labels) {
    if (l.label == 0) continue;
    Stopwatch clock;
    const Input li = label_input(in, l.label);
    ExtractResult res = extract(li, opt);
    const std::string file = (dir / ("label_" + std::to_string(l.label) + "." + ext)).string();
    write_mesh(res.mesh.num_triangles() ? res.mesh : res.base.mesh, file, wo);
    const Mesh& m = res.mesh.num_triangles() ? res.mesh : res.base.mesh;
    const TopologyReport t = topology(m);
    const double secs = clock.lap();
    table.push_back({{"label", l.label}, {"voxels", l.voxels}, {"triangles", m.num_triangles()},
                     {"components", t.components}, {"euler", t.euler},
                     {"boundary_loops", t.boundary_loops}, {"seconds", secs}, {"file", file},
                     {"warnings", res.report.covering.warnings}});
    if (!quiet) {
      std::printf("%8lld %12lld %10zu %11zu %5lld %9.2f  %s\n", static_cast<long long>(l.label),
                  static_cast<long long>(l.voxels), m.num_triangles(),
                  static_cast<std::size_t>(t.components), static_cast<long long>(t.euler), secs,
                  file.c_str());
      std::fflush(stdout);
      for (const auto& w : res.report.covering.warnings)
        std::cerr << "adamesh: warning: label " << l.label << ": " << w << "\n";
    }
  }
  const std::string json = nlohmann::json{{"input", spec}, {"labels", table}}.dump(2) + "\n";
  write_file_atomically((dir / "labels.json").string(), [&](std::ostream& o) { o << json; }, false);
  return 0;
}

int cmd_extract(const Argv& argv) {
  const Args args("extract", argv, extract_specs());
  if (args.help_requested()) {
    std::cout << args.usage("INPUT [--iso V] [-o mesh.ply|- [--format F]] [--levels K | "
                            "--max-error E | --triangles N] [--hierarchy h.amh] [--base base.ply] "
                            "[options]")
              << "\n-o - --format ply writes the refined mesh to standard output (ply obj off stl "
                 "glb; binary\nformats are refused on a terminal); progress and the summary go "
                 "to stderr, so stdout holds\nthe mesh alone. The other outputs are files.\n";
    return 0;
  }
  args.expect_positionals(1, 1, "INPUT");
  const std::string spec = args.positionals()[0];
  const bool quiet = args.has("--quiet");
  if (!args.has("--base") && !args.has("--report") && !args.has("-o") && !args.has("--hierarchy"))
    fail(Status::usage, "adamesh extract: nothing to write: give -o FILE, --hierarchy FILE, "
                        "--base FILE or --report FILE");
  ExtractOptions opt = extract_options(args, spec);
  if (args.has("--labels")) return extract_all_labels(args, spec, opt);
  // Every output is checked before any work (a missing --hierarchy folder used to be found
  // after minutes, with the other outputs already written).
  check_outputs("extract", args,
                {{"-o", OutputKind::mesh, true}, {"--base", OutputKind::mesh},
                 {"--hierarchy", OutputKind::hierarchy}, {"--report", OutputKind::report}});
  if (args.has("--format") && !args.has("-o"))
    fail(Status::usage, "adamesh extract: --format names the format of -o - (standard output) or "
                        "of the files of --labels all; a file's format comes from its extension");
  const InputOptions input = input_options_from(args);
  for (const char* o : {"-o", "--base"})  // refuse unknown mesh formats before computing
    if (args.has(o)) mesh_output_options(args, o);
  const bool streaming = is_stdout(args.get_or("-o", ""));
  std::ostream& info = streaming ? std::cerr : std::cout;  // stdout: the mesh alone

  Progress progress(quiet);
  std::string stage;
  opt.context.progress = [&](const char* name, double f) {
    if (stage != name) {
      stage = name;
      progress.stage(name);
    } else if (f >= 1) {
      progress.finish();
    } else {
      progress.fraction(f);
    }
  };
  ExtractResult res = extract(spec, opt, input);
  ExtractReport& rep = res.report;

  Stopwatch clock;
  progress.stage("write");
  if (auto path = args.get("--base")) {
    if (args.has("--attributes")) {
      VertexAttribute border{"border", {}, {}}, comp{"component", {}, {}};
      for (auto b : res.base.border) border.i32.push_back(b);
      for (auto c : res.base.component) comp.i32.push_back(static_cast<std::int32_t>(c));
      res.base.mesh.attributes.push_back(std::move(border));
      res.base.mesh.attributes.push_back(std::move(comp));
    }
    write_mesh(res.base.mesh, *path, mesh_output_options(args, "--base"));
  }
  if (auto path = args.get("-o")) write_mesh_output(res.mesh, *path, mesh_output_options(args, "-o"));
  if (auto path = args.get("--hierarchy")) write_hierarchy(*res.hierarchy, *path);
  progress.finish();
  rep.timings_s["write"] = clock.lap();

  if (auto path = args.get("--report")) {
    rep.peak_rss_mb = std::max(rep.peak_rss_mb, adamesh::peak_rss_mb());
    const std::string json = report_json(rep);
    write_file_atomically(*path, [&](std::ostream& o) { o << json; }, false);
  }
  if (!quiet) {
    info << base_summary(rep) << "\n";
    if (rep.refined) info << refine_summary(rep) << "\n";
    for (const auto& w : rep.covering.warnings) std::cerr << "adamesh: warning: " << w << "\n";
  }
  return 0;
}

}  // namespace adamesh::cli
