// Inputs named on the command line: a volume file, `shape:NAME` or `expr:'...'`.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
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
  /// DICOM (not raw): SeriesInstanceUID to read from a directory holding several series.
  std::string dicom_series;
};

/// A set of label values: inclusive ranges, sorted and disjoint (parse_label_set() builds it).
struct LabelSet {
  std::vector<std::pair<std::int64_t, std::int64_t>> ranges;

  static LabelSet single(std::int64_t value) { return {{{value, value}}}; }
  bool contains(std::int64_t value) const;
  /// "5", "1-15", "1,3,5-9": the form parse_label_set() reads.
  std::string to_string() const;
};

/// Parses a label set: values and inclusive ranges separated by commas ("5", "1-15",
/// "1,3,5-9"; values may be negative: "-2--1"). Overlapping parts merge. Throws
/// Error(usage) naming the text for anything else (empty parts, a range whose end is below its
/// start, a value beyond 64 bits).
LabelSet parse_label_set(const std::string& text);

struct InputOptions {
  RawOptions raw;
  std::optional<Box> bounds;         ///< sampling box of implicit inputs (default per shape)
  int resolution = 0;                ///< samples along the longest side of the box; 0 = default (64)
  std::optional<double> nan_value;   ///< replace NaN/Inf samples by this value instead of failing
  bool flip_inside = false;          ///< swap inside and outside
  bool keep_nonfinite = false;       ///< `info`: count NaN/Inf samples instead of failing
  /// Label maps: the input becomes the 0/1 mask of the voxels whose value is in this set
  /// (label_input()).
  std::optional<LabelSet> label;
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

/// One value of a label map and how many voxels have it.
struct LabelCount {
  std::int64_t label = 0;
  std::int64_t voxels = 0;
};

/// Label maps: for an integer volume with 2..max_labels distinct values, every value with its
/// voxel count (increasing values); empty for floating volumes and volumes with more values
/// (intensities). One pass over the samples.
std::vector<LabelCount> label_counts(const Volume& volume, std::size_t max_labels = 64);

/// The boundary of a set of labels as an input: a 0/1 uint8 mask of the voxels whose value is in
/// `labels` on the same grid, inside where 1, default iso-value 1/2 (one set of several labels:
/// their union as one surface). Throws Error(invalid_input) for a floating volume or a set no
/// voxel is in.
Input label_input(const Input& in, const LabelSet& labels);
inline Input label_input(const Input& in, std::int64_t label) {
  return label_input(in, LabelSet::single(label));
}

/// For an iso-surface of a volume that looks like a label map (label_counts() finds its
/// values) with more than one value on the inside or more than one on the outside of `iso`
/// (`inside_sign` as in Input): one line saying that the surface follows the interpolated
/// label numbers and which --label set meshes the inside values as one 0/1 mask. Empty
/// otherwise (intensities, binary masks, one value on each side).
std::string label_map_iso_note(const Volume& volume, double iso, double inside_sign);

/// What fill_cavities() did.
struct CavityReport {
  std::int64_t filled = 0;          ///< cavities filled
  std::int64_t filled_voxels = 0;   ///< samples they had
  std::int64_t largest_filled = 0;  ///< samples of the largest one filled
};

/// Topology control: a copy of `in` whose cavities — 6-connected components of outside samples
/// that touch no face of the volume — with fewer than `max_voxels` samples are filled with the
/// volume's most inside value, so their surfaces disappear. Costs one copy of the volume and one
/// byte per sample while it runs.
Input fill_cavities(const Input& in, double iso, std::int64_t max_voxels, CavityReport& report);

/// What remove_handles() did.
struct HandleReport {
  double radius = 0;                    ///< the opening's ball radius, voxels (max_loop / 2π)
  std::int64_t handles_cut = 0;         ///< groups of inside voxels turned outside (strands cut)
  std::int64_t cut_voxels = 0;
  std::int64_t tunnels_filled = 0;      ///< groups of outside voxels turned inside (tunnels plugged)
  std::int64_t plug_voxels = 0;
  /// Euler characteristic of the inside region (the surfels' topology: b0 − b1 + b2) before and
  /// after; the extracted surface's is measured on M0.
  std::int64_t inside_euler_before = 0, inside_euler_after = 0;
};

/// Topology control: a copy of `in` without the handles and tunnels whose shortest
/// non-separating loop is shorter than about `max_loop` voxels (Wood et al. 2004's topology
/// noise): strands of material thinner than max_loop/π at some place are cut there and tunnels
/// as thin are plugged, each by one layer of voxels set to the volume's most outside or most
/// inside value, found by an opening with a ball of radius max_loop/(2π) and a growth back that
/// never closes a loop (docs/TOPOLOGY.md). Components and cavities are kept. Costs one copy of
/// the volume and about 15 bytes per sample while it runs.
Input remove_handles(const Input& in, double iso, double max_loop, HandleReport& report);

/// True for `shape:NAME` and `expr:EXPR` (implicit inputs: sampled fields, default iso-value 0).
bool is_implicit_spec(const std::string& spec) noexcept;

/// An input from samples already in memory (the Python module's numpy volumes), named `spec` in
/// messages: NaN/Inf samples as load_input() treats them (options.nan_value replaces them in
/// place), the trilinear field, inside_sign (+1: bright is inside; -1: negative is inside, as in
/// signed distance fields), options.flip_inside. No default iso-value.
Input make_input(Volume volume, const std::string& spec, double inside_sign = 1,
                 const InputOptions& options = {});

/// Names of the built-in shapes (`shape:NAME`).
std::vector<std::string> shape_names();

}  // namespace adamesh
