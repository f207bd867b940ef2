// Volume statistics for `adamesh info` and iso-value suggestions: range, mean, percentiles,
// NaN/Inf count and an Otsu threshold. No full-size temporary copy: everything comes from
// histograms built in a few parallel passes over the samples.
#pragma once

#include <array>
#include <cstdint>
#include <limits>

#include "adamesh/volume.h"

namespace adamesh {

struct VolumeStats {
  /// The percentile levels reported, in percent.
  static constexpr std::array<double, 7> kPercentileLevels{1, 5, 25, 50, 75, 95, 99};

  std::int64_t samples = 0;    ///< all samples
  std::int64_t finite = 0;     ///< samples that are not NaN/Inf (all of them for integer types)
  std::int64_t nonfinite = 0;  ///< NaN/Inf samples (floating types only); ignored below
  double min = std::numeric_limits<double>::quiet_NaN();  ///< over finite samples
  double max = std::numeric_limits<double>::quiet_NaN();
  double mean = std::numeric_limits<double>::quiet_NaN();
  /// Nearest-rank percentiles of the finite samples: the smallest sample value v such that at
  /// least P% of the samples are ≤ v (rank ceil(P/100 · finite), at least 1).
  /// NaN when there are no finite samples.
  std::array<double, 7> percentiles = filled_nan();
  /// Bound on |reported − exact| over all percentiles: 0 when exact (always for 8/16-bit data
  /// and integer data with range < 65536; other data: exact unless, after a 65536-bin histogram
  /// and 4 refinement passes of 4096 bins over the members' range, the percentile's bin still
  /// holds several distinct values — only for pathological value distributions).
  double percentile_error = 0;
  /// Otsu threshold (maximum between-class variance) of the value histogram (exact histogram for
  /// integer data with range < 65536, else 65536 bins over [min, max]), to use as the iso-value.
  /// Integer data: a half-integer, so no sample equals it. When the optimum is a plateau (empty
  /// bins between two modes) the middle of the plateau is taken. NaN when there are no finite
  /// samples; min when all finite samples are equal.
  double otsu = std::numeric_limits<double>::quiet_NaN();

 private:
  static constexpr std::array<double, 7> filled_nan() {
    std::array<double, 7> a{};
    for (double& x : a) x = std::numeric_limits<double>::quiet_NaN();
    return a;
  }
};

/// Statistics of `volume`'s samples. Parallel (oneTBB); results do not depend on the thread count.
VolumeStats compute_stats(const Volume& volume);

/// Number of NaN/Inf samples (0 for integer types). When `first` is given and the count is
/// non-zero, it receives the (i, j, k) index of the first one in storage order.
std::int64_t count_nonfinite(const Volume& volume, std::array<std::int64_t, 3>* first = nullptr);

/// Replaces NaN/Inf samples by `value` (converted to the sample type); returns how many.
std::int64_t replace_nonfinite(Volume& volume, double value);

}  // namespace adamesh
