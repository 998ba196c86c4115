#pragma once

// Clocks and summaries shared by the benchmarks. The machines they run on are
// shared and noisy, so CPU time is offered beside wall time.

#include <chrono>
#include <cstddef>
#include <vector>

namespace geodex::bench {

using Clock = std::chrono::steady_clock;

// Seconds of CPU time this thread has used: a single-threaded measurement
// counted this way leaves out the time the thread spends preempted (cache
// interference from other processes still counts).
double ThreadCpuSeconds();

// Seconds of CPU time this process has used (all its threads).
double ProcessCpuSeconds();

// Wall seconds from `start` to `end`, and from `start` to now.
double SecondsBetween(Clock::time_point start, Clock::time_point end);
double SecondsSince(Clock::time_point start);

// The value at fraction `p` (0 to 1) of `values` sorted, nearest rank.
// `values` must not be empty.
double Percentile(std::vector<double> values, double p);

// The mean of the first `n` of `values` (all of them when there are fewer);
// 0 when that is none.
double Mean(const std::vector<double>& values, size_t n);

}  // namespace geodex::bench
