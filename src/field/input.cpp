// load_input(): the INPUT argument of every command — a volume file, `shape:NAME` or
// `expr:EXPR` — turned into samples plus an exact field, with the inside/outside and NaN/Inf
// conventions of docs/CONVENTIONS.md applied.
//
// Kept apart from the rest of src/field because it is the only place that calls read_volume():
// code that never loads inputs links without the volume readers.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "adamesh/error.h"
#include "adamesh/input.h"
#include "adamesh/io.h"
#include "adamesh/stats.h"

namespace adamesh {

namespace {

constexpr int kDefaultResolution = 64;
constexpr Box kDefaultExprBox{{-1, -1, -1}, {1, 1, 1}};

/// Isotropic grid with `res` samples along the longest side of `box`, centred in the box.
Grid implicit_grid(const Box& box, int res, const std::string& spec) {
  for (int a = 0; a < 3; ++a)
    if (!(std::isfinite(box.lo[a]) && std::isfinite(box.hi[a]) && box.lo[a] < box.hi[a]))
      fail(Status::usage, spec + ": bounds need finite xmin<xmax, ymin<ymax, zmin<zmax");
  for (int a = 0; a < 3; ++a)
    if (std::abs(box.lo[a]) > kMaxWorldCoordinate || std::abs(box.hi[a]) > kMaxWorldCoordinate)
      fail(Status::usage, spec + ": bounds must lie within ±1e18 world units");
  if (res < 2) fail(Status::usage, spec + ": resolution must be at least 2, got " + std::to_string(res));
  const Vec3 ext = box.size();
  const double longest = std::max({ext.x, ext.y, ext.z});
  const double h = longest / (res - 1);
  Grid g;
  g.spacing = {h, h, h};
  for (int a = 0; a < 3; ++a) {
    const double n = std::round(ext[a] / h) + 1;
    if (n > 1e9) fail_input(spec, "sampling grid too large");
    g.dims[a] = static_cast<std::int64_t>(n);
    g.origin[a] = 0.5 * (box.lo[a] + box.hi[a]) - 0.5 * double(g.dims[a] - 1) * h;
  }
  check_world_range(g, spec);  // e.g. bounds 1e-30 wide: voxels below kMinVoxelEdge
  return g;
}

/// Samples `f` on `grid` as float32, in parallel over rows (each sample independent: deterministic).
Volume sample_field(const ScalarField& f, const Grid& grid, const std::string& spec) {
  Volume v = allocate_volume(grid, ScalarType::f32, spec);
  v.format = "implicit";
  v.source = spec;
  const auto& d = grid.dims;
  float* out = v.samples<float>();
  tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, d[1] * d[2]), [&](const auto& r) {
    for (std::int64_t row = r.begin(); row < r.end(); ++row) {
      const std::int64_t j = row % d[1], k = row / d[1];
      float* dst = out + row * d[0];
      for (std::int64_t i = 0; i < d[0]; ++i) {
        const Vec3 p{grid.origin.x + grid.spacing.x * double(i), grid.origin.y + grid.spacing.y * double(j),
                     grid.origin.z + grid.spacing.z * double(k)};
        dst[i] = static_cast<float>(f.value(p));
      }
    }
  });
  return v;
}

std::string strip_quotes(std::string s) {
  if (s.size() >= 2 && (s.front() == '\'' || s.front() == '"') && s.back() == s.front())
    s = s.substr(1, s.size() - 2);
  return s;
}

/// Applies the NaN/Inf policy; returns the number of non-finite samples found.
std::int64_t handle_nonfinite(Volume& v, const std::string& spec, const InputOptions& o) {
  std::array<std::int64_t, 3> first{};
  const std::int64_t n = count_nonfinite(v, &first);
  if (n == 0) return 0;
  if (o.nan_value) {
    replace_nonfinite(v, *o.nan_value);
  } else if (!o.keep_nonfinite) {
    std::ostringstream os;
    os << n << " NaN/Inf samples (first at voxel " << first[0] << "," << first[1] << "," << first[2]
       << "); use --nan-value V to replace them";
    fail_input(spec, os.str());
  }
  return n;
}

}  // namespace

Input make_input(Volume volume, const std::string& spec, double inside_sign,
                 const InputOptions& options) {
  if (options.nan_value && !std::isfinite(*options.nan_value))
    fail(Status::usage, spec + ": --nan-value must be a finite number");
  if (inside_sign != 1 && inside_sign != -1)
    fail(Status::usage, spec + ": inside_sign must be +1 or -1");
  checked_volume_bytes(volume.grid.dims, volume.type, spec);
  if (volume.data.size() < scalar_size(volume.type) * static_cast<std::size_t>(volume.grid.num_samples()))
    fail(Status::usage, spec + ": fewer samples than the grid has");
  Input in;
  in.spec = spec;
  in.nonfinite_samples = handle_nonfinite(volume, spec, options);
  in.volume = std::make_shared<const Volume>(std::move(volume));
  in.field = make_volume_field(in.volume);
  in.inside_sign = options.flip_inside ? -inside_sign : inside_sign;
  return in;
}

bool is_implicit_spec(const std::string& spec) noexcept {
  return spec.rfind("shape:", 0) == 0 || spec.rfind("expr:", 0) == 0;
}

Input load_input(const std::string& spec, const InputOptions& options) {
  if (options.nan_value && !std::isfinite(*options.nan_value))
    fail(Status::usage, spec + ": --nan-value must be a finite number");
  Input in;
  in.spec = spec;
  Volume v;
  const bool is_shape = spec.rfind("shape:", 0) == 0, is_expr = spec.rfind("expr:", 0) == 0;
  if (is_shape || is_expr) {
    const int res = options.resolution > 0 ? options.resolution : kDefaultResolution;
    std::shared_ptr<const ScalarField> field;
    Grid grid;
    if (is_shape) {
      const std::string name = spec.substr(6);
      const Box box = options.bounds.value_or(make_shape_field(name)->domain());
      grid = implicit_grid(box, res, spec);
      field = make_shape_field(name, grid.world_bounds());
    } else {
      const std::string expr = strip_quotes(spec.substr(5));
      grid = implicit_grid(options.bounds.value_or(kDefaultExprBox), res, spec);
      field = make_expr_field(expr, grid.world_bounds());
    }
    v = sample_field(*field, grid, spec);
    in.field = std::move(field);
    in.inside_sign = -1;
    in.default_iso = 0.0;
  } else {
    v = read_volume(spec, options.raw);
    in.inside_sign = +1;
  }
  in.nonfinite_samples = handle_nonfinite(v, spec, options);
  in.volume = std::make_shared<const Volume>(std::move(v));
  if (!in.field) in.field = make_volume_field(in.volume);
  if (options.label) in = label_input(in, *options.label);
  if (options.flip_inside) in.inside_sign = -in.inside_sign;
  return in;
}

}  // namespace adamesh
