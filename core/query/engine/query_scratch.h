#pragma once

// Per-thread working memory of the queries that are not O(1): the exact
// solver that refinements and exact neighbourhoods run (its arrays grow with
// the mesh, so a thread keeps it and reuses it), and the near pairs' walks. Optional wherever a query
// takes it: without one, a query makes its own for the call.
//
// Thread safety: one QueryScratch per thread; it is not shared.
//
//   query::QueryScratch scratch;  // per worker thread
//   GEODEX_RETURN_IF_ERROR(queries->DistanceBatch(a, b, out, options, &scratch));

#include <array>
#include <cstdint>
#include <memory>

namespace geodex::query {

struct ExactScratch;  // internal/exact/exact_scratch.h
struct WalkScratch;   // internal/paths/walk_scratch.h

// What the near-pair refinements run with one QueryScratch did, summed over
// its calls (the default mode's walks and the exact solves behind them):
// counts for profiles (tests/bench/query_bench --near-profile), never read
// by the queries themselves.
struct NearPairStats {
  int64_t pairs = 0;               // near pairs refined in the default mode
  int64_t walks = 0;               // chord walks that found a corridor
  int64_t faces_crossed = 0;       // faces of those corridors as walked
  int64_t faces_unfolded = 0;      // faces laid out in the plane, releases included
  int64_t releases = 0;            // corridors moved round a vertex
  int64_t exact_solves = 0;        // pairs sent to the confined exact solver
  int64_t exact_with_walk = 0;     // of those, pruned by a walk's length from the start
  int64_t exact_rounds = 0;        // its propagations
  int64_t exact_region_faces = 0;  // faces of its last regions
  int64_t exact_windows = 0;       // windows it created
  int64_t traces = 0;              // pairs whose walks failed, sent to the gradient trace
  int64_t shots = 0;               // geodesics shot at the other point (chord_walk.h)
  // Pairs whose k-th shot (k = 1..4) was a straight local geodesic to the
  // other point: [k - 1].
  std::array<int64_t, 4> straight_at_shot = {};
  // Pairs refined only by a raised threshold whose walks all failed: their
  // O(1) answer kept.
  int64_t raised_kept = 0;
};

class QueryScratch {
 public:
  QueryScratch();
  ~QueryScratch();
  QueryScratch(QueryScratch&&) noexcept;
  QueryScratch& operator=(QueryScratch&&) noexcept;

  // What the scratch holds: one exact solver over one mesh (and the state of
  // propagations confined to parts of it, which run on that solver), made
  // (empty) on first use, so that a scratch no query needs allocates
  // nothing. Its definition is the query engine's own; callers only pass
  // the scratch along.
  ExactScratch& solvers();
  // The chord walks' corridors and layouts, made on first use.
  WalkScratch& walks();

  NearPairStats& near_pair_stats() { return near_pair_stats_; }

 private:
  std::unique_ptr<ExactScratch> solvers_;
  std::unique_ptr<WalkScratch> walks_;
  NearPairStats near_pair_stats_;
};

}  // namespace geodex::query
