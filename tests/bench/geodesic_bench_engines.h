#pragma once

// The engines geodesic_bench (geodesic_bench.cc) measures, each run apart:
// ours (the wavefront and the window engine) and CGAL in a forked child
// process, so that none sees another's heap; VTP as a process per source.
// What a child measures comes back through a pipe as a ChildResult.

#include <cstdint>
#include <functional>
#include <istream>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"

namespace geodex::bench {

// What a child reports back through its pipe.
struct ChildResult {
  std::string error;  // empty on success
  double setup_seconds = 0;
  std::vector<double> seconds;                 // per source, wall clock
  std::vector<double> cpu_seconds;             // per source, CPU time of the child
  int64_t baseline_kb = 0;                     // ru_maxrss just before the algorithm
  int64_t peak_kb = 0;                         // ru_maxrss after the last propagation
  int64_t windows = 0;                         // ours: windows created, summed over sources
  std::vector<std::vector<double>> distances;  // the first few sources'
};

// The bytes of `r` for the pipe, and `r` again from them. Errors
// (Deserialize): Internal when the bytes are truncated.
std::string SerializeChildResult(const ChildResult& r);
absl::StatusOr<ChildResult> DeserializeChildResult(std::string bytes);

// Runs `work` in a forked child and returns what it reports. Errors:
// Internal when the pipe or the fork fails, or the child does not exit 0
// (killed by a signal, or its own exit status), with which.
absl::StatusOr<ChildResult> InChild(const std::function<ChildResult()>& work);

// Ours from each of `sources` (vertices): the window engine
// (ExactGeodesicSolver, which DistanceAt and PathTo need) or the wavefront
// engine (VertexGeodesicSolver, the builder's rows); the distances of the
// first `keep` sources are kept. Meant to run in a child (InChild): the
// memory figures are the process's.
ChildResult RunOurs(const mesh::Mesh& m, const std::vector<int32_t>& sources, bool wavefront,
                    int keep);

// CGAL's Surface_mesh_shortest_path from each of `sources`; every
// distance field kept. Meant to run in a child (InChild).
ChildResult RunCgal(const mesh::Mesh& m, const std::vector<mesh::SurfacePoint>& sources);

// VTP's figures, one per source.
struct VtpResult {
  std::vector<double> propagation_seconds;  // VTP's own figure
  std::vector<double> process_seconds;      // wall time of the whole process
  int64_t peak_kb = 0;                      // largest peak RSS of the processes
  std::vector<std::vector<double>> distances;
};

// Builds VTP with `vtp_dir`/build.sh into `binary` unless it is there
// already. Errors: Internal when the build fails.
absl::Status BuildVtp(const std::string& vtp_dir, const std::string& binary);

// Runs `binary -m obj -s v -o out` for each source vertex v. Errors:
// Internal when a run fails, prints no propagation time, or writes other
// than `num_vertices` distances.
absl::StatusOr<VtpResult> RunVtp(const std::string& binary, const std::string& obj,
                                 const std::vector<int32_t>& vertices, int32_t num_vertices);

// The propagation seconds VTP printed ("... took S ..."), or -1 when none.
double VtpPropagationSeconds(std::istream& printed);

// The largest relative difference between two distance fields, over the
// vertices both have: infinite where one alone is infinite.
double MaxRelativeDifference(const std::vector<double>& a, const std::vector<double>& b);

}  // namespace geodex::bench
