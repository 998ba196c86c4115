#include "tests/bench/bench_timing.h"

#include <time.h>

#include <algorithm>
#include <cassert>

namespace geodex::bench {
namespace {

double ClockSeconds(clockid_t clock) {
  timespec t{};
  clock_gettime(clock, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

}  // namespace

double ThreadCpuSeconds() { return ClockSeconds(CLOCK_THREAD_CPUTIME_ID); }

double ProcessCpuSeconds() { return ClockSeconds(CLOCK_PROCESS_CPUTIME_ID); }

double SecondsBetween(Clock::time_point start, Clock::time_point end) {
  return std::chrono::duration<double>(end - start).count();
}

double SecondsSince(Clock::time_point start) { return SecondsBetween(start, Clock::now()); }

double Percentile(std::vector<double> values, double p) {
  assert(!values.empty());
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, static_cast<size_t>(p * (values.size() - 1) + 0.5))];
}

double Mean(const std::vector<double>& values, size_t n) {
  n = std::min(n, values.size());
  double sum = 0;
  for (size_t i = 0; i < n; ++i) sum += values[i];
  return n == 0 ? 0 : sum / n;
}

}  // namespace geodex::bench
