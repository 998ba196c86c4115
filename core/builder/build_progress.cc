#include "core/builder/build_progress.h"

#include <unistd.h>

#include "absl/strings/str_format.h"

namespace geodex::builder {

ProgressPrinter::ProgressPrinter(std::FILE* out) : out_(out), tty_(isatty(fileno(out))) {}

void ProgressPrinter::operator()(const Progress& p) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto now = std::chrono::steady_clock::now();
  if (!build_start_.has_value()) build_start_ = now;
  if (p.phase != phase_ || p.done == 0) {
    phase_ = p.phase;
    phase_start_ = now;
  }
  const auto seconds = [&](std::chrono::steady_clock::time_point from) {
    return std::chrono::duration<double>(now - from).count();
  };
  const double in_phase = seconds(phase_start_);
  const double fraction = p.total > 0 ? static_cast<double>(p.done) / p.total : 1.0;
  std::string eta = "";
  if (fraction > 0 && fraction < 1) eta = " ETA " + FormatSeconds(in_phase / fraction - in_phase);
  const std::string line =
      absl::StrFormat("[%s] %d/%d (%.1f%%) elapsed %s%s", p.phase, p.done, p.total, 100 * fraction,
                      FormatSeconds(seconds(*build_start_)), eta);
  if (tty_) {
    std::fprintf(out_, "\r\033[K%s%s", line.c_str(), p.done >= p.total ? "\n" : "");
  } else if (p.done >= p.total || std::chrono::duration<double>(now - last_log_).count() >= 10) {
    std::fprintf(out_, "%s\n", line.c_str());
    last_log_ = now;
  }
}

std::string FormatSeconds(double s) {
  if (s < 60) return absl::StrFormat("%.1fs", s);
  return absl::StrFormat("%dm%02ds", static_cast<int>(s / 60), static_cast<int>(s) % 60);
}

}  // namespace geodex::builder
