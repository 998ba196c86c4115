#pragma once

// The harness of geodesic_bench (geodesic_bench.cc): its flags, the meshes
// and sources, one comparison per mesh (geodesic_bench_engines.h runs the
// engines), and the Markdown table with its notes.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"

namespace geodex::bench {

struct GeodesicBenchOptions {
  std::vector<std::string> meshes;  // empty: the shared meshes, else an icosphere
  int sources = 3;
  int cgal_large_sources = 1;  // CGAL's sources on large meshes
  int large_vertices = 50000;  // vertices from which a mesh counts as large
  std::string vtp_dir;         // empty: the shared directory's anchors/vtp
  bool no_cgal = false;
  bool no_windows = false;  // skip our window engine
};

// The command line of geodesic_bench, writing into `options` when parsed.
std::unique_ptr<CLI::App> GeodesicBenchFlags(GeodesicBenchOptions* options);

// `k` source vertices spread pseudo-randomly (fixed seed) over the vertices
// faces reference.
std::vector<int32_t> PickSources(const mesh::Mesh& m, int k);

// How many sources CGAL runs on a mesh of `num_vertices` vertices: none
// without CGAL, at most --cgal-large-sources on a large mesh.
int CgalSourceCount(const GeodesicBenchOptions& options, int32_t num_vertices);

// "12.3 MB" for `kb` kilobytes.
std::string Megabytes(int64_t kb);

// One engine's figures, before the comparison columns.
struct Measured {
  std::string engine;  // "VTP" names VTP's row
  int sources = 0;
  double wall = 0;  // mean seconds per source
  double cpu = 0;
  std::string memory;
  std::vector<std::vector<double>> distances;  // per source
};

// The table rows of one mesh (no newlines): per engine its figures, its CPU
// time over VTP's, and its largest relative difference from VTP's distances
// (VTP's own row: from the first engine's).
std::vector<std::string> ComparisonRows(const std::string& label, int32_t num_vertices,
                                        const std::vector<Measured>& measured);

// What stdout shows: the table of `rows`, then `notes` and the closing note.
std::string ResultsReport(const std::vector<std::string>& rows,
                          const std::vector<std::string>& notes);

// Runs the whole benchmark as the command line asks and returns the exit
// code: 1 when a mesh cannot be read or an engine fails (the reason on
// stderr).
int RunGeodesicBench(GeodesicBenchOptions options);

}  // namespace geodex::bench
