#pragma once

// How geodex-build shows the builder's progress (BuildOptions::progress) on
// stderr: a live line with an ETA on a terminal, otherwise a log line every
// 10 seconds and at the end of each phase. "elapsed" is the time since the
// build's first progress call, the same clock on every line (it never runs
// backwards from one phase to the next); the ETA is the current phase's,
// timed from when that phase last began (a target-error build runs its
// phases once a round).
//
// Thread safety: operator() may be called from any thread (calls are
// serialised).

#include <chrono>
#include <cstdio>
#include <mutex>
#include <optional>
#include <string>

#include "core/builder/builder.h"

namespace geodex::builder {

class ProgressPrinter {
 public:
  explicit ProgressPrinter(std::FILE* out = stderr);

  void operator()(const Progress& p);

 private:
  std::FILE* out_;
  bool tty_;
  std::mutex mutex_;
  std::optional<std::chrono::steady_clock::time_point> build_start_;
  std::string phase_;  // the phase of the last call
  std::chrono::steady_clock::time_point phase_start_{};
  std::chrono::steady_clock::time_point last_log_{};
};

// "12.3s" under a minute, "4m05s" from there.
std::string FormatSeconds(double seconds);

}  // namespace geodex::builder
