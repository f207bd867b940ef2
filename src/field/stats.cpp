// Volume statistics without a sorted copy (see stats.h for the definitions).
//
// Passes over the samples (each parallel over fixed blocks of 64Ki samples, so sums are added in
// a fixed order and results do not depend on the thread count):
//  * 8/16-bit integers: one exact histogram over the type's whole range gives everything.
//  * other types: pass 1 = min, max, sum, NaN/Inf count. Integer data whose range is < 65536
//    then gets one exact histogram pass. Otherwise a 65536-bin histogram over [min, max] (also
//    used for Otsu) locates each percentile's bin; up to 4 refinement passes then histogram
//    (4096 bins, recording each sub-bin's smallest and largest member) only the samples inside
//    each percentile's current interval, and the next interval is the member range of the
//    sub-bin holding the rank. A percentile is exact as soon as that range is a single value;
//    since the range shrinks to the members at every level, outliers cannot stall this. If the
//    passes run out, the range's midpoint is reported and its half width is the error bound.
// Otsu: N. Otsu, "A threshold selection method from gray-level histograms", IEEE Trans. SMC 9(1),
// 1979 — maximise w0·w1·(m0 − m1)² over the thresholds between histogram bins.
#include "adamesh/stats.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>
#include <vector>

namespace adamesh {

namespace {

constexpr std::int64_t kBlock = std::int64_t(1) << 16;
constexpr int kBins = 65536;
constexpr int kRefineBins = 4096;
constexpr int kRefinePasses = 4;
constexpr std::size_t kLevels = VolumeStats::kPercentileLevels.size();

/// Calls f(begin, end) for fixed blocks of kBlock samples, in parallel.
template <class F>
void for_blocks(std::int64_t n, F&& f) {
  const std::int64_t blocks = (n + kBlock - 1) / kBlock;
  tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, blocks), [&](const auto& r) {
    for (std::int64_t b = r.begin(); b < r.end(); ++b) f(b, b * kBlock, std::min(n, (b + 1) * kBlock));
  });
}

template <class T>
bool finite(T v) {
  if constexpr (std::is_floating_point_v<T>) return std::isfinite(v);
  else return true;
}

/// ceil(level/100 · n) in integer arithmetic (the levels are whole percents), at least 1.
std::int64_t nearest_rank(double level, std::int64_t n) {
  const auto l = static_cast<std::int64_t>(level);
  return std::max<std::int64_t>(1, (l * n + 99) / 100);
}

/// k bins over [a, c] (a < c): bin b = [edge(b), edge(b+1)), the last one closed. Edges are a
/// monotone function of b and bin() corrects its estimate against them, so bin membership is
/// exactly consistent with edge(): nested bins never lose or double-count a sample. All
/// arithmetic is on halved values, so no difference overflows even for ±DBL_MAX data.
struct Bins {
  double a = 0, c = 0, ah = 0, wh = 0, inv = 0;
  int k = 1;
  Bins() = default;
  Bins(double lo, double hi, int bins)
      : a(lo), c(hi), ah(0.5 * lo), wh((0.5 * hi - 0.5 * lo) / bins), inv(wh > 0 ? 1 / wh : 0), k(bins) {}
  double edge(int b) const {
    if (b <= 0) return a;
    if (b >= k) return c;
    return std::clamp(2 * (ah + b * wh), a, c);
  }
  int bin(double v) const {
    const double t = (0.5 * v - ah) * inv;
    int b = t > 0 ? (t < k - 1 ? static_cast<int>(t) : k - 1) : 0;
    while (b > 0 && v < edge(b)) --b;
    while (b < k - 1 && v >= edge(b + 1)) ++b;
    return b;
  }
};

/// Index b of the bin holding the rank-th (1-based) sample; `below` receives the count before it.
int find_rank(const std::vector<std::int64_t>& h, std::int64_t rank, std::int64_t& below) {
  std::int64_t cum = 0;
  for (std::size_t b = 0; b < h.size(); ++b) {
    if (cum + h[b] >= rank) {
      below = cum;
      return static_cast<int>(b);
    }
    cum += h[b];
  }
  below = cum - (h.empty() ? 0 : h.back());
  return static_cast<int>(h.size()) - 1;
}

/// Otsu on a histogram: the plateau [k1, k2] of thresholds "after bin k" with maximal between-class
/// variance (k2 > k1 only when the optimum is flat, e.g. across empty bins). False if degenerate.
template <class Center>
bool otsu_plateau(const std::vector<std::int64_t>& h, Center center, int& k1, int& k2) {
  const int n = static_cast<int>(h.size());
  double total = 0, sum = 0;
  for (int b = 0; b < n; ++b) {
    total += double(h[b]);
    sum += double(h[b]) * center(b);
  }
  std::vector<double> var(std::max(n - 1, 0), -1.0);
  double w0 = 0, s0 = 0, best = -1;
  k1 = -1;
  for (int k = 0; k + 1 < n; ++k) {
    w0 += double(h[k]);
    s0 += double(h[k]) * center(k);
    if (w0 <= 0 || w0 >= total) continue;
    const double m0 = s0 / w0, m1 = (sum - s0) / (total - w0);
    var[k] = w0 * (total - w0) * (m0 - m1) * (m0 - m1);
    if (var[k] > best) {
      best = var[k];
      k1 = k;
    }
  }
  if (k1 < 0 || !(best > 0)) return false;
  k2 = k1;
  while (k2 + 2 < n && var[k2 + 1] >= best * (1 - 1e-12)) ++k2;
  return true;
}

/// Exact statistics from a histogram of integer values base + b.
void from_integer_histogram(const std::vector<std::int64_t>& h, double base, VolumeStats& s) {
  std::int64_t n = 0;
  double sum = 0;
  int lo = -1, hi = -1;
  for (int b = 0; b < int(h.size()); ++b) {
    if (!h[b]) continue;
    if (lo < 0) lo = b;
    hi = b;
    n += h[b];
    sum += double(h[b]) * (base + b);
  }
  s.finite = n;
  if (n == 0) return;
  s.min = base + lo;
  s.max = base + hi;
  s.mean = sum / double(n);
  for (std::size_t q = 0; q < kLevels; ++q) {
    std::int64_t below = 0;
    s.percentiles[q] = base + find_rank(h, nearest_rank(VolumeStats::kPercentileLevels[q], n), below);
  }
  int k1 = 0, k2 = 0;
  if (otsu_plateau(h, [&](int b) { return base + b; }, k1, k2))
    s.otsu = std::floor(base + (double(k1) + double(k2)) / 2) + 0.5;
  else
    s.otsu = s.min;
}

template <class T>
std::vector<std::int64_t> integer_histogram(const T* v, std::int64_t n, double base, int bins) {
  tbb::enumerable_thread_specific<std::vector<std::int64_t>> local(
      [&] { return std::vector<std::int64_t>(bins, 0); });
  for_blocks(n, [&](std::int64_t, std::int64_t b, std::int64_t e) {
    auto& h = local.local();
    for (std::int64_t i = b; i < e; ++i) ++h[static_cast<std::size_t>(double(v[i]) - base)];
  });
  std::vector<std::int64_t> h(bins, 0);
  for (const auto& l : local)
    for (int i = 0; i < bins; ++i) h[i] += l[i];
  return h;
}

struct Pass1 {
  double min = INFINITY, max = -INFINITY, sum = 0;
  std::int64_t finite = 0, nonfinite = 0;
};

template <class T>
Pass1 pass1(const T* v, std::int64_t n) {
  std::vector<Pass1> part(static_cast<std::size_t>((n + kBlock - 1) / kBlock));
  for_blocks(n, [&](std::int64_t blk, std::int64_t b, std::int64_t e) {
    Pass1 p;
    for (std::int64_t i = b; i < e; ++i) {
      const T x = v[i];
      if (!finite(x)) {
        ++p.nonfinite;
        continue;
      }
      const double d = static_cast<double>(x);
      p.min = std::min(p.min, d);
      p.max = std::max(p.max, d);
      p.sum += d;
      ++p.finite;
    }
    part[blk] = p;
  });
  Pass1 r;
  for (const auto& p : part) {
    r.min = std::min(r.min, p.min);
    r.max = std::max(r.max, p.max);
    r.sum += p.sum;
    r.finite += p.finite;
    r.nonfinite += p.nonfinite;
  }
  return r;
}

/// One percentile being narrowed down: the rank-th smallest of the finite samples v with
/// lo ≤ v ≤ hi (v < hi when open_hi).
struct Target {
  std::int64_t rank = 0;
  double lo = 0, hi = 0;
  bool open_hi = false;
  bool done() const { return lo == hi && !open_hi; }
};

/// Count-only histogram of the finite samples over `bins` (level 0).
template <class T>
std::vector<std::int64_t> value_histogram(const T* v, std::int64_t n, const Bins& bins) {
  tbb::enumerable_thread_specific<std::vector<std::int64_t>> local(
      [&] { return std::vector<std::int64_t>(bins.k, 0); });
  for_blocks(n, [&](std::int64_t, std::int64_t b, std::int64_t e) {
    auto& h = local.local();
    const Bins bb = bins;
    for (std::int64_t i = b; i < e; ++i)
      if (finite(v[i])) ++h[bb.bin(static_cast<double>(v[i]))];
  });
  std::vector<std::int64_t> h(bins.k, 0);
  for (const auto& l : local)
    for (int i = 0; i < bins.k; ++i) h[i] += l[i];
  return h;
}

/// Per-thread state of a refinement pass: for each of up to kLevels disjoint intervals, a
/// kRefineBins histogram plus each sub-bin's smallest and largest member.
struct RefineHist {
  std::vector<std::int64_t> count;
  std::vector<double> lo, hi;
  explicit RefineHist(int intervals)
      : count(intervals * kRefineBins, 0),
        lo(intervals * kRefineBins, INFINITY),
        hi(intervals * kRefineBins, -INFINITY) {}
};

/// One refinement pass for the distinct unresolved intervals `iv` (disjoint: bins of one level;
/// sorted by lo).
template <class T>
RefineHist refine_pass(const T* v, std::int64_t n, const std::vector<Target>& iv) {
  const int m = static_cast<int>(iv.size());
  // The intervals are disjoint and sorted by lo: the candidate for d is the last one with
  // lo ≤ d, found by counting (a fixed number of compares the compiler vectorises; unused
  // slots have lo = +inf). A branchy scan mispredicted badly on random data.
  constexpr int kSlots = 8;
  std::array<Bins, kSlots> bins{};
  std::array<double, kSlots> lo, hi;
  std::array<bool, kSlots> open{};
  lo.fill(INFINITY);
  hi.fill(-INFINITY);
  for (int o = 0; o < m; ++o) {
    bins[o] = Bins(iv[o].lo, iv[o].hi, kRefineBins);
    lo[o] = iv[o].lo;
    hi[o] = iv[o].hi;
    open[o] = iv[o].open_hi;
  }
  tbb::enumerable_thread_specific<RefineHist> local([m] { return RefineHist(m); });
  for_blocks(n, [&](std::int64_t, std::int64_t b, std::int64_t e) {
    RefineHist& h = local.local();
    const auto lo_ = lo, hi_ = hi;  // local copies: no aliasing with the histogram stores
    const auto open_ = open;
    for (std::int64_t i = b; i < e; ++i) {
      const double d = static_cast<double>(v[i]);  // NaN/Inf are in no interval
      int count = 0;
      for (int o = 0; o < kSlots; ++o) count += d >= lo_[o];
      if (count == 0) continue;
      const int o = count - 1;
      if (!(d <= hi_[o]) || (open_[o] && d == hi_[o])) continue;
      const int k = o * kRefineBins + bins[o].bin(d);
      ++h.count[k];
      h.lo[k] = std::min(h.lo[k], d);
      h.hi[k] = std::max(h.hi[k], d);
    }
  });
  RefineHist r(m);
  for (const auto& l : local)
    for (std::size_t k = 0; k < r.count.size(); ++k) {
      r.count[k] += l.count[k];
      r.lo[k] = std::min(r.lo[k], l.lo[k]);
      r.hi[k] = std::max(r.hi[k], l.hi[k]);
    }
  return r;
}

template <class T>
void general_stats(const T* v, std::int64_t n, VolumeStats& s) {
  const Pass1 p = pass1(v, n);
  s.finite = p.finite;
  s.nonfinite = p.nonfinite;
  if (p.finite == 0) return;
  s.min = p.min;
  s.max = p.max;
  s.mean = p.sum / double(p.finite);
  if constexpr (std::is_integral_v<T>) {
    if (p.max - p.min < kBins) {
      from_integer_histogram(integer_histogram(v, n, p.min, int(p.max - p.min) + 1), p.min, s);
      return;
    }
  }
  if (p.min == p.max) {
    s.percentiles.fill(p.min);
    s.otsu = p.min;
    return;
  }
  // Level 0: kBins bins over [min, max], shared by all percentiles and by Otsu.
  const Bins top(p.min, p.max, kBins);
  const std::vector<std::int64_t> h0 = value_histogram(v, n, top);
  int k1 = 0, k2 = 0;
  s.otsu = otsu_plateau(h0, [&](int b) { return 0.5 * (top.edge(b) + top.edge(b + 1)); }, k1, k2)
               ? 0.5 * (top.edge(k1 + 1) + top.edge(k2 + 1))
               : p.min;
  std::array<Target, kLevels> t;
  for (std::size_t q = 0; q < kLevels; ++q) {
    std::int64_t below = 0;
    const std::int64_t rank = nearest_rank(VolumeStats::kPercentileLevels[q], p.finite);
    const int b = find_rank(h0, rank, below);
    t[q] = Target{rank - below, top.edge(b), top.edge(b + 1), b < kBins - 1};
  }
  // Refinement: each pass histograms the members of every unresolved interval (percentiles in
  // the same interval share it) and moves each percentile to the member range of its sub-bin.
  for (int pass = 0; pass < kRefinePasses; ++pass) {
    std::vector<Target> iv;
    std::array<int, kLevels> slot{};
    for (std::size_t q = 0; q < kLevels; ++q) {
      if (t[q].done()) continue;
      int o = 0;
      while (o < int(iv.size()) && !(iv[o].lo == t[q].lo && iv[o].hi == t[q].hi)) ++o;
      if (o == int(iv.size())) iv.push_back(t[q]);
      slot[q] = o;
    }
    if (iv.empty()) break;
    std::sort(iv.begin(), iv.end(), [](const Target& x, const Target& y) { return x.lo < y.lo; });
    for (std::size_t q = 0; q < kLevels; ++q) {
      if (t[q].done()) continue;
      slot[q] = 0;
      while (!(iv[slot[q]].lo == t[q].lo && iv[slot[q]].hi == t[q].hi)) ++slot[q];
    }
    const RefineHist h = refine_pass(v, n, iv);
    for (std::size_t q = 0; q < kLevels; ++q) {
      if (t[q].done()) continue;
      const std::size_t off = std::size_t(slot[q]) * kRefineBins;
      const std::vector<std::int64_t> sub(h.count.begin() + off, h.count.begin() + off + kRefineBins);
      std::int64_t below = 0;
      const int b = find_rank(sub, t[q].rank, below);
      t[q] = Target{t[q].rank - below, h.lo[off + b], h.hi[off + b], false};
    }
  }
  s.percentile_error = 0;
  for (std::size_t q = 0; q < kLevels; ++q) {
    s.percentiles[q] = t[q].done() ? t[q].lo : 0.5 * t[q].lo + 0.5 * t[q].hi;
    if (!t[q].done()) s.percentile_error = std::max(s.percentile_error, 0.5 * t[q].hi - 0.5 * t[q].lo);
  }
}

}  // namespace

VolumeStats compute_stats(const Volume& volume) {
  VolumeStats s;
  s.samples = volume.grid.num_samples();
  dispatch_scalar(volume.type, [&](auto tag) {
    using T = decltype(tag);
    const T* v = volume.samples<T>();
    if constexpr (std::is_integral_v<T> && sizeof(T) <= 2) {
      const double base = double(std::numeric_limits<T>::min());
      from_integer_histogram(integer_histogram(v, s.samples, base, 1 << (8 * sizeof(T))), base, s);
    } else {
      general_stats(v, s.samples, s);
    }
  });
  return s;
}

std::int64_t count_nonfinite(const Volume& volume, std::array<std::int64_t, 3>* first) {
  if (!is_floating(volume.type)) return 0;
  const std::int64_t n = volume.grid.num_samples();
  std::vector<std::int64_t> count(static_cast<std::size_t>((n + kBlock - 1) / kBlock), 0);
  std::vector<std::int64_t> first_in(count.size(), -1);
  dispatch_scalar(volume.type, [&](auto tag) {
    using T = decltype(tag);
    const T* v = volume.samples<T>();
    for_blocks(n, [&](std::int64_t blk, std::int64_t b, std::int64_t e) {
      for (std::int64_t i = b; i < e; ++i) {
        if (finite(v[i])) continue;
        if (first_in[blk] < 0) first_in[blk] = i;
        ++count[blk];
      }
    });
  });
  std::int64_t total = 0, first_index = -1;
  for (std::size_t b = 0; b < count.size(); ++b) {
    total += count[b];
    if (first_index < 0) first_index = first_in[b];
  }
  if (first && first_index >= 0) {
    const auto& d = volume.grid.dims;
    *first = {first_index % d[0], (first_index / d[0]) % d[1], first_index / (d[0] * d[1])};
  }
  return total;
}

std::int64_t replace_nonfinite(Volume& volume, double value) {
  if (!is_floating(volume.type)) return 0;
  const std::int64_t n = volume.grid.num_samples();
  std::vector<std::int64_t> count(static_cast<std::size_t>((n + kBlock - 1) / kBlock), 0);
  dispatch_scalar(volume.type, [&](auto tag) {
    using T = decltype(tag);
    T* v = volume.samples<T>();
    const T r = static_cast<T>(value);
    for_blocks(n, [&](std::int64_t blk, std::int64_t b, std::int64_t e) {
      for (std::int64_t i = b; i < e; ++i) {
        if (finite(v[i])) continue;
        v[i] = r;
        ++count[blk];
      }
    });
  });
  std::int64_t total = 0;
  for (auto c : count) total += c;
  return total;
}

}  // namespace adamesh
