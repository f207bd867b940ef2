// The refinement stage of `adamesh extract` (-o, --levels, --max-error, --triangles,
// --hierarchy): runs the 4-8 refinement on the base mesh, writes the mesh and the hierarchy, and
// measures each level for the report.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "adamesh/graph.h"
#include "adamesh/input.h"
#include "adamesh/simplify.h"
#include "adamesh/surfels.h"
#include "args.h"
#include "cli_util.h"

namespace adamesh::cli {

/// Options of the refinement stage, for extract's option table.
std::vector<OptionSpec> refine_option_specs();

struct RefineStage {
  nlohmann::json levels = nlohmann::json::array();  ///< report "levels" (when measured)
  nlohmann::json info;                               ///< report "refine"
  double refine_s = 0;  ///< refinement and extraction
  double improve_s = 0;  ///< shape improvement of the written mesh
  double write_s = 0;   ///< writing -o and --hierarchy
  std::string summary;  ///< one line for the terminal
};

/// Refines `base` as the options say (default --max-error 0.25 h) and writes -o / --hierarchy.
/// `measure`: compute the per-level figures of the report (distance, ε_e, ε_n, angles).
RefineStage run_refine_stage(const Args& args, const Input& in, double iso, const SurfelComplex& sc,
                             const ConnectivityGraph& g, const BaseMesh& base, int threads,
                             Progress& progress, bool measure);

}  // namespace adamesh::cli
