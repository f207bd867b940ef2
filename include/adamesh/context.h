// Execution context: how a call runs — worker threads, progress reporting and cancellation —
// carried once in the options of the whole pipeline instead of a field per option struct.
#pragma once

#include <atomic>
#include <chrono>
#include <functional>

namespace adamesh {

/// Progress report: the stage's name ("read", "handles", "cavities", "surfels", "graph", "disk cover",
/// "dual", "improve M0", "refine", "improve", "measure") and the fraction of it done, in [0, 1].
/// Called on the calling thread, never from a worker thread, with fraction 0 when a stage begins
/// and 1 when it ends.
using ProgressCallback = std::function<void(const char* stage, double fraction)>;

struct ExecutionContext {
  /// Worker threads; 0 = all hardware threads. Results are byte-identical for any value.
  int threads = 0;
  /// Optional progress report (see ProgressCallback). It may throw to abort the call; the
  /// exception propagates to the caller.
  ProgressCallback progress;
  /// Optional cancellation flag, read at stage boundaries and at every progress report: once it
  /// is set the call throws Error(Status::cancelled, "cancelled"). Not owned; must outlive the call.
  const std::atomic<bool>* cancel = nullptr;

  bool cancelled() const noexcept { return cancel && cancel->load(std::memory_order_relaxed); }
  /// Throws Error(Status::cancelled, "cancelled") when cancelled().
  void check_cancelled() const;
  /// check_cancelled(), then progress(stage, fraction) when a callback is set.
  void report(const char* stage, double fraction) const;
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
