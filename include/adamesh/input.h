// Inputs named on the command line: a volume file, `shape:NAME` or `expr:'...'`.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "adamesh/field.h"
#include "adamesh/volume.h"

namespace adamesh {

/// Options for headerless raw files (`--dims X,Y,Z --type T [--spacing] [--origin] [--endian]`).
struct RawOptions {
  std::optional<std::array<std::int64_t, 3>> dims;
  std::optional<ScalarType> type;
  Vec3 spacing{1, 1, 1};
  Vec3 origin{};
  bool big_endian = false;
  std::uint64_t header_bytes = 0;  ///< bytes to skip at the start of the file
};

struct InputOptions {
  RawOptions raw;
  std::optional<Box> bounds;         ///< sampling box of implicit inputs (default per shape)
  int resolution = 0;                ///< samples along the longest side of the box; 0 = default (64)
  std::optional<double> nan_value;   ///< replace NaN/Inf samples by this value instead of failing
  bool flip_inside = false;          ///< swap inside and outside
  bool keep_nonfinite = false;       ///< `info`: count NaN/Inf samples instead of failing
};

struct Input {
  std::string spec;                          ///< as given on the command line
  /// Sampled values (implicit inputs: float32 grid). Shared and const so that `field`, which
  /// reads it, stays valid when the Input is moved or copied.
  std::shared_ptr<const Volume> volume;
  std::shared_ptr<const ScalarField> field;  ///< exact field: analytic, or trilinear on `volume`
  double inside_sign = +1;                   ///< +1: inside where f ≥ iso; −1: where f ≤ iso
  std::optional<double> default_iso;         ///< shapes: 0; files: none
  std::int64_t nonfinite_samples = 0;        ///< NaN/Inf samples found (replaced if nan_value)
};

/// Loads a file (format from its extension/magic), or samples `shape:NAME` / `expr:EXPR`.
/// Implicit inputs: box = options.bounds or the shape's default ([-1,1]^3 for expressions),
/// N = options.resolution (default 64) samples along the longest side, isotropic spacing
/// longest/(N−1), dims[a] = round(extent[a]/spacing)+1, grid centred in the box; the field's
/// domain() is the grid's world box. NaN/Inf samples: see docs/CONVENTIONS.md.
/// Throws Error with a one-line message naming the input and the problem.
Input load_input(const std::string& spec, const InputOptions& options = {});

/// True for `shape:NAME` and `expr:EXPR` (implicit inputs: sampled fields, default iso-value 0).
bool is_implicit_spec(const std::string& spec) noexcept;

/// Names of the built-in shapes (`shape:NAME`).
std::vector<std::string> shape_names();

}  // namespace adamesh
