#pragma once

// One Distance call a pair, each timed and sorted by how the refinement
// answered it (shot k, walk, releases, trace, exact, O(1)): query_bench's
// near-pair and every-distance profiles.

#include <cstddef>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/query/engine/query_engine.h"

namespace geodex::bench {

// One row of the near-pair profile: the pairs at L-3L of the O(1) answer that
// the default mode answered one way, and what they cost.
struct NearProfileRow {
  std::string how;                // "straight walk", "walk with releases", ...
  size_t count = 0;               // pairs answered this way
  double share = 0;               // of the bin's pairs
  double us = 0;                  // microseconds a pair (one Distance call)
  double faces_crossed = 0;       // faces of the walked corridors a pair
  double faces_unfolded = 0;      // faces laid out a pair, releases included
  double releases = 0;            // a pair
  double exact_rounds = 0;        // exact propagations a pair
  double exact_region_faces = 0;  // faces of the exact solver's last region a pair
};

// The near-pair profile's header for the pairs it describes (a title such
// as "Near pairs at L-3L of the O(1) answer"), and one row of it (no
// newline).
std::string NearProfileHeader(const std::string& pairs);
std::string NearProfileRowText(const std::string& label, const NearProfileRow& row);

// The pairs (x[i], y[i]) one Distance call each under `options`, each
// timed (the least of three calls) and sorted by how the refinement
// answered it: a row a class, then a total row named `total_how`, printed
// as NearProfileRowText rows.
void PrintProfileRows(const std::string& label, const query::QueryEngine& engine,
                      const std::vector<mesh::SurfacePoint>& x,
                      const std::vector<mesh::SurfacePoint>& y,
                      const query::DistanceOptions& options, const std::string& total_how);

}  // namespace geodex::bench
