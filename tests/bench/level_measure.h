#pragma once

// What levels of samples would cost and gain, measured on built indexes:
// the O(1) answer's error as a function of d / L at each index's own scale
// length (does a finer level serve a band of d / L as well as a coarser
// one serves the same band?), and the bytes a table of exact distances
// between one level's samples costs per sample as a function of the radius
// it keeps (in units of that level's L).
//
// Thread safety: pure functions.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/index/index.h"
#include "tests/accuracy/accuracy.h"

namespace geodex::bench {

// Bins of d / L, doubling: [0, 1), [1, 2), [2, 4), ..., [32, 64), [64, inf).
inline constexpr int kNumRatioBins = 8;
int RatioBin(double ratio);
std::string RatioBinName(int bin);

// Bins of d in units of L1000 = sqrt(2 A / (sqrt(3) 1000)), fixed whatever
// m is: [0, 0.5), [0.5, 1), [1, 2), [2, 4), [4, 8), [8, 16), [16, inf).
inline constexpr int kNumFixedBins = 7;
int FixedBin(double d_over_l1000);
std::string FixedBinName(int bin);

// Signed relative errors of one index's answers, binned two ways, vertex
// and interior pairs apart ([0] vertex, [1] interior).
struct LevelErrors {
  std::array<std::array<std::vector<double>, kNumRatioBins>, 2> by_ratio;
  std::array<std::array<std::vector<double>, kNumFixedBins>, 2> by_fixed;
};

// Bins the errors of `answers` (one per pair) against `pairs`' exact
// distances, with the index's scale length `l` and L1000 `l1000`.
LevelErrors BinErrors(const std::vector<validation::ExactPair>& pairs,
                      const std::vector<double>& answers, double l, double l1000);

// Mean number of other samples within k L of a sample, for each k of
// `radii` (the matrix is the index's exact sample distances).
std::vector<double> MeanNeighbours(const index::Index& index, double l,
                                   const std::vector<double>& radii);

// Bytes per sample of a neighbour table that stores each pair within the
// radius once: `mean_neighbours` / 2 entries of `entry_bytes` each.
inline double TableBytesPerSample(double mean_neighbours, int entry_bytes) {
  return mean_neighbours / 2 * entry_bytes;
}

// Markdown rows: p99 (vertex / interior, in %) per bin, "-" under `min_count`
// pairs.
std::string RatioRow(const std::string& label, const LevelErrors& e, int min_count);
std::string FixedRow(const std::string& label, const LevelErrors& e, int min_count);

}  // namespace geodex::bench
