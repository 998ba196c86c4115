#pragma once

// The geodex-geodesic command line (core/tools/geodesic_main.cc): its flags,
// and its two jobs, exact distances of pairs and every vertex's exact
// distance from one vertex.
//
//   GeodesicCommandLine       the CLI11 app, its flags bound to a GeodesicToolArgs
//   ExactPairDistances        the exact distance of every pair, one
//                             propagation per distinct first point
//   PairDistancesText         --pairs: what geodex-geodesic prints
//   WriteDistancesFromVertex  --source-vertex: the file (or stdout) it writes
//   GeodesicExitCode          the process's exit status for an error
//
// Thread safety: the functions are reentrant; a GeodesicCommandLine is used
// by one thread.

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/common/threads.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/pairs_io.h"

namespace geodex::tools {

// What geodex-geodesic is asked, as its flags say.
struct GeodesicToolArgs {
  std::string mesh_path;
  mesh::ReadOptions read;  // --weld
  // --pairs: the file of pairs ("-": standard input), answered by `threads`
  // workers.
  std::string pairs_path;
  int threads = common::ThreadCount(0);
  // --source-vertex: the vertex (0-based, file order), the output file ("-":
  // standard output), the engine ("wavefront" or "windows") and whether to
  // print the propagation's statistics.
  int64_t source_vertex = -1;
  std::string out = "-";
  std::string engine = "wavefront";
  bool stats = false;
};

// Which job the parsed flags ask for.
enum class GeodesicJob {
  kNone,        // neither --pairs nor --source-vertex
  kPairs,       // --pairs
  kFromVertex,  // --source-vertex
};

// The geodex-geodesic app: parsing it (CLI11_PARSE) fills args(); CLI11
// checks ranges, choices, and that --pairs and --source-vertex exclude each
// other.
class GeodesicCommandLine {
 public:
  GeodesicCommandLine();
  GeodesicCommandLine(const GeodesicCommandLine&) = delete;
  GeodesicCommandLine& operator=(const GeodesicCommandLine&) = delete;

  CLI::App& app() { return app_; }
  const GeodesicToolArgs& args() const { return args_; }
  // After parsing: the job given.
  GeodesicJob job() const;

 private:
  GeodesicToolArgs args_;
  CLI::App app_;
  CLI::Option* pairs_ = nullptr;
  CLI::Option* source_ = nullptr;
};

// The exact distance (geodesic::kInfinity when unreachable) of every pair of
// `pairs`, valid points of `mesh`, in their order. Pairs are grouped by their
// first point so that each distinct source is propagated once, stopping when
// its targets are settled; `threads` workers take the groups. Errors: a
// propagation's, prefixed with the line of the group's first pair.
absl::StatusOr<std::vector<double>> ExactPairDistances(const mesh::Mesh& mesh,
                                                       const std::vector<mesh::PointPair>& pairs,
                                                       int threads);

// --pairs: one exact distance per pair ("inf" when unreachable), a line each.
// Errors: the mesh's and the pair file's (naming the line), then
// ExactPairDistances's.
absl::StatusOr<std::string> PairDistancesText(const GeodesicToolArgs& args);

// --source-vertex: every vertex's exact distance from args.source_vertex, a
// line each, written to args.out (beside its name and renamed into place;
// "-": standard output). With args.stats, a line of CPU seconds and window
// counts goes to `stats`. Errors: the mesh's, OutOfRange for a vertex past
// the end, the propagation's, the write's (DataLoss for standard output).
absl::Status WriteDistancesFromVertex(const GeodesicToolArgs& args, std::FILE* stats);

// 2 for bad input (InvalidArgument, OutOfRange), 1 otherwise.
int GeodesicExitCode(const absl::Status& status);

}  // namespace geodex::tools
