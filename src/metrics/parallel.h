// Deterministic parallel helpers for the metrics: a thread-count scope and chunked reductions
// whose floating-point results do not depend on the number of threads (fixed chunk boundaries,
// partial results combined in chunk order).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include "adamesh/context.h"

namespace adamesh::detail {

/// Runs f() with at most `context.threads` worker threads (0 = the default arena).
template <class F>
decltype(auto) with_threads(const ExecutionContext& context, F&& f) {
  const int threads = context.threads;
  if (threads <= 0) return f();
  tbb::task_arena arena(threads);
  return arena.execute(std::forward<F>(f));
}

constexpr std::size_t kChunk = 1 << 14;

/// Calls body(begin, end) on the fixed chunks [k·chunk, min(n, (k+1)·chunk)) in parallel.
template <class F>
void for_chunks(std::size_t n, F&& body, std::size_t chunk = kChunk) {
  const std::size_t chunks = (n + chunk - 1) / chunk;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t k = r.begin(); k != r.end(); ++k)
                        body(k * chunk, std::min(n, (k + 1) * chunk));
                    });
}

/// Deterministic reduction: part = body(begin, end) per fixed chunk, then
/// acc = combine(acc, part) over the chunks in order, starting from `zero`.
template <class T, class Body, class Combine>
T chunked_reduce(std::size_t n, const T& zero, Body&& body, Combine&& combine,
                 std::size_t chunk = kChunk) {
  const std::size_t chunks = (n + chunk - 1) / chunk;
  std::vector<T> parts(chunks, zero);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t k = r.begin(); k != r.end(); ++k)
                        parts[k] = body(k * chunk, std::min(n, (k + 1) * chunk));
                    });
  T acc = zero;
  for (const T& p : parts) acc = combine(acc, p);
  return acc;
}

/// Sum of f(i) for i in [0, n), deterministic.
template <class F>
double chunked_sum(std::size_t n, F&& f, std::size_t chunk = kChunk) {
  return chunked_reduce(
      n, 0.0,
      [&](std::size_t b, std::size_t e) {
        double s = 0;
        for (std::size_t i = b; i < e; ++i) s += f(i);
        return s;
      },
      [](double a, double b) { return a + b; }, chunk);
}

/// Nearest-rank percentile (p in [0, 100]) of `v`, which it partially reorders; 0 when empty.
template <class Vector>
double percentile(Vector& v, double p) {
  if (v.empty()) return 0;
  const double rank = std::ceil(p / 100.0 * static_cast<double>(v.size()));
  const std::size_t k = static_cast<std::size_t>(std::clamp(rank, 1.0, double(v.size()))) - 1;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return static_cast<double>(v[k]);
}

}  // namespace adamesh::detail
