#pragma once

// Pairs of surface points with their exact geodesic distances, drawn at every
// distance scale: what the builder calibrates an index's error bounds on and
// what the accuracy harness measures it with (each with its own seed).
//
// The absolute error of the O(1) answer is roughly the same at every
// distance, so its relative error grows as the points get closer, and
// area-uniform pairs are mostly far apart. Pairs are therefore binned by
// their exact distance d in units of the scale length
//   L = sqrt(2 A / (sqrt(3) m)),
// the edge of an equilateral geodesic triangle when m samples tile the area
// A: d < L, L-3L, 3L-10L, >= 10L; each source gets area-uniform targets and
// targets drawn in every bin on purpose. Half the sources are mesh vertices
// paired with vertices, half points inside faces paired with such points.
//
// Thread safety: the functions are reentrant.

#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"

namespace geodex::validation {

inline constexpr int kNumScaleBins = 4;
// "d<L", "L-3L", "3L-10L", ">=10L".
const char* ScaleBinName(int bin);
// The bin of distance d for scale length L.
int ScaleBinOf(double d, double scale_length);
// L for a surface of area `area` tiled by `num_samples` samples.
double ScaleLength(double area, int32_t num_samples);

// Bins in a unit fixed by the surface, not by m: L1000 = ScaleLength(area,
// 1000). A bin in the index's own L moves closer as m grows, so a target
// set there can never be met; these bins say what a user gets at a
// distance: [0, 0.5), [0.5, 1), [1, 2), [2, 4), [4, 8), [8, 16), [16, inf)
// L1000.
inline constexpr int kNumFixedBins = 7;
inline constexpr int32_t kFixedUnitSamples = 1000;
// "0-0.5", "0.5-1", ..., "8-16", ">=16" (in L1000).
const char* FixedBinName(int bin);
// The lower edge of fixed bin `bin`, in L1000.
double FixedBinLower(int bin);
// The fixed bin of distance d for unit L1000 `unit`.
int FixedBinOf(double d, double unit);

// A pair of surface points and their exact geodesic distance.
struct ExactPair {
  mesh::SurfacePoint p, q;
  double exact = 0;
  bool vertices = false;  // both points are mesh vertices (else both inside faces)
  bool uniform = false;   // q drawn area-uniformly (else in a bin on purpose)
  int bin = 0;            // ScaleBinOf(exact)
  int32_t source = 0;     // the number of p's exact propagation (pairs of one source err together)
};

struct PairOptions {
  int32_t num_sources = 20;      // exact propagations
  int32_t uniform_points = 300;  // area-uniform targets per source
  int32_t per_bin_points = 60;   // targets per source drawn in each bin
  uint64_t seed = 1;
  // Threads for the propagations (0: all hardware threads). Each source
  // draws from its own generator, seeded from `seed` and its number, so the
  // pairs do not depend on the thread count.
  int threads = 1;
  // Draw vertex pairs among vertices [0, vertex_limit) only (0: all). A
  // refined mesh's midpoints come last and are no vertices of the file:
  // vertex pairs stand for the file's vertices, the mesh's corners, where
  // the O(1) answer errs most.
  int32_t vertex_limit = 0;
  // The number of the first source: sources first_source ..
  // first_source + num_sources - 1 are drawn, each the same pairs whatever
  // the range, so a measurement can draw more sources later and add them.
  int32_t first_source = 0;
};

// Draws pairs for an index of `num_samples` samples (which fixes L) on a
// valid mesh: deterministic for a seed, in the order of their sources. Pairs closer than 1e-9 of
// the bounding box diagonal, or in different components, are left out.
std::vector<ExactPair> DrawPairs(const mesh::Mesh& mesh, int32_t num_samples,
                                 const PairOptions& options);

// `count` area-uniform random surface points.
std::vector<mesh::SurfacePoint> RandomSurfacePoints(const mesh::Mesh& mesh, int32_t count,
                                                    uint64_t seed);

}  // namespace geodex::validation
