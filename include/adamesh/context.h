// Execution context: how a call runs — worker threads, progress reporting and cancellation —
// carried once for the whole pipeline instead of a field per option struct. Every stage function
// (build_surfels, build_covering, refine, improve_mesh, the metrics, ...) takes one as its last
// argument, default_context() when omitted.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>

#include "adamesh/context_fwd.h"

namespace adamesh {

/// Progress report: the stage's name ("read", "handles", "cavities", "surfels", "graph",
/// "disk cover", "voronoi", "dual", "improve M0", "refine", "improve", "fit", "separate",
/// "measure") and the fraction of it done, in [0, 1]. Called on the calling thread, never from a
/// worker thread, with fraction 0 when a stage begins, at most every 0.1 s during the long
/// stages, and 1 when it ends.
using ProgressCallback = std::function<void(const char* stage, double fraction)>;

struct ExecutionContext {
  /// Worker threads; 0 = all hardware threads. Results are byte-identical for any value.
  int threads = 0;
  /// Optional progress report (see ProgressCallback). It may throw to abort the call; the
  /// exception propagates to the caller.
  ProgressCallback progress;
  /// Optional cancellation flag, read at stage boundaries, at every progress report and every few
  /// thousand iterations of the long loops inside the stages (StageTicker; on the calling thread):
  /// once it is set the call throws Error(Status::cancelled, "cancelled") within a fraction of a
  /// second and frees what it allocated. Not owned; must outlive the call.
  const std::atomic<bool>* cancel = nullptr;

  bool cancelled() const noexcept { return cancel && cancel->load(std::memory_order_relaxed); }
  /// Throws Error(Status::cancelled, "cancelled") when cancelled().
  void check_cancelled() const;
  /// check_cancelled(), then progress(stage, fraction) when a callback is set.
  void report(const char* stage, double fraction) const;
};

/// Polling inside a stage's long loop, on the calling thread: tick() costs a counter increment;
/// every `every` ticks (a tick may weigh more than one) it checks the cancellation flag (throws Error(Status::cancelled)) and, at
/// most every 0.1 s, reports progress(stage, fraction). Results never depend on it.
class StageTicker {
 public:
  StageTicker(const ExecutionContext& ctx, const char* stage, std::uint32_t every = 4096) noexcept
      : ctx_(ctx), stage_(stage), every_(every > 0 ? every : 1),
        // The first due report comes at once (after `every` iterations), then at most every
        // 0.1 s: a stage shorter than 0.1 s still reports from inside.
        last_(std::chrono::steady_clock::now() - std::chrono::seconds(1)) {}
  /// `weight` iterations (default one) of a loop that does not know its fraction: the last one
  /// reported is repeated.
  void tick(std::uint32_t weight = 1) {
    tick_with([this] { return fraction_; }, weight);
  }
  /// The same with `fraction()`, a callable returning the stage's fraction done, evaluated only
  /// when progress is reported.
  template <class Fraction>
  void tick_with(Fraction&& fraction, std::uint32_t weight = 1) {
    count_ += weight;
    if (count_ < every_) return;
    count_ = 0;
    ctx_.check_cancelled();
    if (ctx_.progress && due()) report(fraction());
  }
  /// Sets the fraction that the plain tick() reports from now on (no check, no report): for a
  /// loop whose inner helpers tick without knowing the fraction.
  void set_fraction(double fraction) {
    fraction_ = fraction < 0 ? 0 : fraction > 1 ? 1 : fraction;
  }
  /// Checks cancellation and reports the last fraction (throttled) now, whatever the count.
  void check() { poll(fraction_); }
  /// Checks cancellation and reports `fraction` (throttled) now, whatever the count.
  void poll(double fraction) {
    count_ = 0;
    fraction_ = fraction < 0 ? 0 : fraction > 1 ? 1 : fraction;
    ctx_.check_cancelled();
    if (ctx_.progress && due()) report(fraction_);
  }

 private:
  bool due() {
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::milliseconds(100)) return false;
    last_ = now;
    return true;
  }
  void report(double fraction) {
    fraction_ = fraction < 0 ? 0 : fraction > 1 ? 1 : fraction;
    ctx_.report(stage_, fraction_);
  }

  const ExecutionContext& ctx_;
  const char* stage_;
  std::uint32_t every_;
  std::uint32_t count_ = 0;
  double fraction_ = 0;
  std::chrono::steady_clock::time_point last_;
};

/// Wall-clock stopwatch in seconds: lap() returns the time since construction or the last lap.
class Stopwatch {
 public:
  double lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - t0_).count();
    t0_ = now;
    return s;
  }

 private:
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

}  // namespace adamesh
