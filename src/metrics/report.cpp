// MeshReport as JSON (the keys `adamesh stats --json` promises, docs/METRICS.md) and as text.
#include <nlohmann/json.hpp>

#include <cstdio>
#include <sstream>

#include "adamesh/metrics.h"

namespace adamesh {

namespace {

using json = nlohmann::ordered_json;  // keys in the order written here

json distance_json(const DistanceStats& d, const DistanceStats& rel) {
  return {{"mean", d.mean}, {"rms", d.rms}, {"max", d.max}, {"p99", d.p99},
          {"mean_rel", rel.mean}, {"rms_rel", rel.rms}, {"max_rel", rel.max}, {"p99_rel", rel.p99},
          {"samples", d.samples}};
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

}  // namespace

std::string report_json(const MeshReport& r) {
  const TopologyReport& t = r.topology;
  const QualityReport& q = r.quality;
  json j;
  j["vertices"] = t.vertices;
  j["edges"] = t.edges;
  j["triangles"] = t.triangles;
  j["euler"] = t.euler;
  j["components"] = t.components;
  j["boundary_loops"] = t.boundary_loops;
  j["genus"] = t.genus;
  json per = json::array();
  for (const auto& c : t.component_list) per.push_back(c.genus ? json(*c.genus) : json(nullptr));
  j["genus_per_component"] = per;
  j["nonmanifold_edges"] = t.nonmanifold_edges;
  j["nonmanifold_vertices"] = t.nonmanifold_vertices;
  j["degenerate_triangles"] = t.degenerate_triangles;
  j["duplicate_triangles"] = t.duplicate_triangles;
  j["oriented"] = t.oriented;
  j["closed"] = t.closed;
  j["boundary_edges"] = t.boundary_edges;
  j["inconsistent_edges"] = t.inconsistent_edges;
  j["unreferenced_vertices"] = t.unreferenced_vertices;
  j["collapsed_triangles"] = t.collapsed_triangles;
  if (r.self_intersecting_pairs >= 0) j["self_intersecting_pairs"] = r.self_intersecting_pairs;
  else j["self_intersecting_pairs"] = nullptr;
  json comps = json::array();
  for (const auto& c : t.component_list)
    comps.push_back({{"vertices", c.vertices}, {"edges", c.edges}, {"triangles", c.triangles},
                     {"euler", c.euler}, {"boundary_loops", c.boundary_loops}, {"closed", c.closed},
                     {"manifold", c.manifold}, {"orientable", c.orientable},
                     {"oriented", c.oriented}, {"genus", c.genus ? json(*c.genus) : json(nullptr)}});
  j["component_list"] = comps;

  j["min_angle_deg"] = {{"min", q.min_angle.min}, {"p1", q.min_angle.p1}, {"p5", q.min_angle.p5},
                        {"median", q.min_angle.median}};
  j["pct_min_angle_below"] = {{"10", q.pct_min_angle_below[0]}, {"20", q.pct_min_angle_below[1]},
                              {"30", q.pct_min_angle_below[2]}};
  j["max_angle_deg"] = q.max_angle;
  j["q_hist"] = q.q_hist;
  j["q_mean"] = q.q_mean;
  j["q_min"] = q.q_min;

  j["area"] = r.area;
  j["volume"] = r.volume ? json(*r.volume) : json(nullptr);
  j["bounds"] = {{"min", {r.bounds.lo.x, r.bounds.lo.y, r.bounds.lo.z}},
                 {"max", {r.bounds.hi.x, r.bounds.hi.y, r.bounds.hi.z}}};
  j["diagonal"] = r.bounds.diagonal();

  if (r.field) {
    const FieldErrorReport& f = *r.field;
    j["distance"] = distance_json(f.distance, f.distance_rel);
    j["eps_e"] = f.eps_e;
    j["eps_e_sqrt_rel"] = f.eps_e_sqrt_rel;
    j["eps_n"] = f.eps_n;
    j["unconverged_projections"] = f.unconverged;
    j["flat_gradient_triangles"] = f.flat_gradient_triangles;
  } else {
    j["distance"] = nullptr;
    j["eps_e"] = nullptr;
    j["eps_e_sqrt_rel"] = nullptr;
    j["eps_n"] = nullptr;
  }
  j["vertices_outside_volume"] = r.volume_bounds ? json(r.volume_bounds->outside) : json(nullptr);
  j["outside_volume_max_voxels"] =
      r.volume_bounds ? json(r.volume_bounds->max_voxels) : json(nullptr);
  if (r.hausdorff) {
    const HausdorffReport& h = *r.hausdorff;
    j["hausdorff"] = {{"a_to_b", h.a_to_b.max}, {"b_to_a", h.b_to_a.max},
                      {"symmetric", h.symmetric}, {"symmetric_rel", h.symmetric_rel},
                      {"a_to_b_mean", h.a_to_b.mean}, {"a_to_b_rms", h.a_to_b.rms},
                      {"a_to_b_p99", h.a_to_b.p99}, {"b_to_a_mean", h.b_to_a.mean},
                      {"b_to_a_rms", h.b_to_a.rms}, {"b_to_a_p99", h.b_to_a.p99},
                      {"samples_a", h.a_to_b.samples}, {"samples_b", h.b_to_a.samples}};
  } else {
    j["hausdorff"] = nullptr;
  }
  return j.dump(2) + "\n";
}

std::string report_text(const MeshReport& r) {
  const TopologyReport& t = r.topology;
  const QualityReport& q = r.quality;
  std::ostringstream os;
  os << "topology\n"
     << "  vertices " << t.vertices << ", edges " << t.edges << ", triangles " << t.triangles
     << "  (euler " << t.euler << ")\n"
     << "  components " << t.components << ", boundary loops " << t.boundary_loops << ", genus "
     << t.genus << (t.closed ? ", closed" : ", open") << (t.oriented ? ", oriented" : ", NOT oriented")
     << "\n";
  if (t.component_list.size() > 1) {
    os << "  genus per component:";
    for (const auto& c : t.component_list) os << " " << (c.genus ? std::to_string(*c.genus) : "-");
    os << "\n";
  }
  os << "  non-manifold edges " << t.nonmanifold_edges << ", non-manifold vertices "
     << t.nonmanifold_vertices << ", degenerate triangles " << t.degenerate_triangles
     << ", duplicate triangles " << t.duplicate_triangles << ", inconsistent edges "
     << t.inconsistent_edges << ", self-intersecting triangle pairs "
     << (r.self_intersecting_pairs >= 0 ? std::to_string(r.self_intersecting_pairs)
                                        : std::string("not measured (triangles piled over one spot)"))
     << "\n";
  if (t.unreferenced_vertices > 0) os << "  unreferenced vertices " << t.unreferenced_vertices << "\n";
  os << "quality\n"
     << "  min angle: min " << fmt("%.2f", q.min_angle.min) << ", p1 " << fmt("%.2f", q.min_angle.p1)
     << ", p5 " << fmt("%.2f", q.min_angle.p5) << ", median " << fmt("%.2f", q.min_angle.median)
     << " deg; max angle " << fmt("%.2f", q.max_angle) << " deg\n"
     << "  min angle < 10/20/30 deg: " << fmt("%.2f", q.pct_min_angle_below[0]) << "% / "
     << fmt("%.2f", q.pct_min_angle_below[1]) << "% / " << fmt("%.2f", q.pct_min_angle_below[2]) << "%\n"
     << "  radius ratio q: mean " << fmt("%.4f", q.q_mean) << ", min " << fmt("%.4f", q.q_min) << "\n"
     << "  q histogram (bins of 0.05):";
  for (auto c : q.q_hist) os << " " << c;
  os << "\ngeometry\n  area " << fmt("%.9g", r.area) << ", volume "
     << (r.volume ? fmt("%.9g", *r.volume) : std::string("- (not closed and oriented)"))
     << ", bounding-box diagonal " << fmt("%.9g", r.bounds.diagonal()) << "\n";
  if (r.field) {
    const FieldErrorReport& f = *r.field;
    os << "distance to the iso-surface (" << f.distance.samples << " samples)\n"
       << "  mean " << fmt("%.4g", f.distance.mean) << ", rms " << fmt("%.4g", f.distance.rms)
       << ", p99 " << fmt("%.4g", f.distance.p99) << ", max " << fmt("%.4g", f.distance.max) << "\n"
       << "  relative to the diagonal: mean " << fmt("%.4g", f.distance_rel.mean) << ", rms "
       << fmt("%.4g", f.distance_rel.rms) << ", p99 " << fmt("%.4g", f.distance_rel.p99) << ", max "
       << fmt("%.4g", f.distance_rel.max) << "\n"
       << "  eps_e " << fmt("%.4g", f.eps_e) << " (sqrt/diagonal " << fmt("%.4g", f.eps_e_sqrt_rel)
       << "), eps_n " << fmt("%.4g", f.eps_n) << "\n";
    if (f.unconverged || f.flat_gradient_triangles)
      os << "  unconverged projections " << f.unconverged << ", flat-gradient triangles "
         << f.flat_gradient_triangles << "\n";
  }
  if (r.volume_bounds) {
    if (r.volume_bounds->outside == 0)
      os << "  every vertex inside the volume's grid\n";
    else
      os << "  " << r.volume_bounds->outside
         << (r.volume_bounds->outside == 1 ? " vertex" : " vertices")
         << " outside the volume's grid, the farthest " << fmt("%.4g", r.volume_bounds->max_voxels)
         << " voxel beyond its face\n";
  }
  if (r.hausdorff) {
    const HausdorffReport& h = *r.hausdorff;
    os << "distance to the reference mesh\n"
       << "  mesh -> reference: max " << fmt("%.4g", h.a_to_b.max) << ", mean "
       << fmt("%.4g", h.a_to_b.mean) << ", rms " << fmt("%.4g", h.a_to_b.rms) << "\n"
       << "  reference -> mesh: max " << fmt("%.4g", h.b_to_a.max) << ", mean "
       << fmt("%.4g", h.b_to_a.mean) << ", rms " << fmt("%.4g", h.b_to_a.rms) << "\n"
       << "  Hausdorff " << fmt("%.4g", h.symmetric) << " (" << fmt("%.4g", h.symmetric_rel)
       << " of the diagonal)\n";
  }
  return os.str();
}

}  // namespace adamesh
