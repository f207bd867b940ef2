// Small helpers shared by the subcommands: stage timing, progress on stderr, peak memory.
#pragma once

#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "adamesh/context.h"

namespace adamesh::cli {

/// Peak resident set size of this process in MiB.
inline double peak_rss_mb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

/// Progress of the stages on stderr, unless quiet. On a terminal a stage's line is updated in
/// place ("  surfels       40%") and erased if an error interrupts the stage; elsewhere (logs,
/// pipes) a stage prints one complete line when it finishes. Either way an error message is never
/// preceded by a half-written progress line.
class Progress {
 public:
  explicit Progress(bool quiet) : quiet_(quiet), tty_(isatty_stderr()) {}
  ~Progress() {
    if (!quiet_ && open_ && tty_) {  // an error interrupted the stage: erase its line
      std::fputs("\r\033[K", stderr);
      std::fflush(stderr);
    }
  }
  void stage(const char* name) {
    if (quiet_) return;
    finish();
    current_ = name;
    if (tty_) {
      std::fprintf(stderr, "  %-12s", name);
      std::fflush(stderr);
    }
    open_ = true;
    last_pct_ = -1;
    t0_ = std::chrono::steady_clock::now();
  }
  void fraction(double f) {
    if (quiet_ || !open_ || !tty_) return;
    const int pct = static_cast<int>(f * 100);
    if (pct / 10 == last_pct_ / 10 && last_pct_ >= 0) return;
    last_pct_ = pct;
    std::fprintf(stderr, "\r  %-12s %3d%%", current_.c_str(), pct);
    std::fflush(stderr);
  }
  void finish() {
    if (quiet_ || !open_) return;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
    if (tty_) std::fprintf(stderr, "\r  %-12s done %.3f s\n", current_.c_str(), s);
    else std::fprintf(stderr, "  %-12s done %.3f s\n", current_.c_str(), s);
    std::fflush(stderr);
    open_ = false;
  }

 private:
  static bool isatty_stderr();
  bool quiet_, tty_;
  bool open_ = false;
  int last_pct_ = -1;
  std::string current_;
  std::chrono::steady_clock::time_point t0_;
};

inline bool Progress::isatty_stderr() { return isatty(2) != 0; }

}  // namespace adamesh::cli
