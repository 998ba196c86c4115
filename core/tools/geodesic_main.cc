// geodex-geodesic: exact geodesic distances, with the engine the builder uses;
// its flags and jobs are core/tools/geodesic_cli.h.
//
//   geodex-geodesic MESH --pairs FILE [--threads N] [--weld EPS]
//   geodex-geodesic MESH --source-vertex V [--out FILE] [--weld EPS]
//
// --pairs reads lines "fa a0 a1 a2 fb b0 b1 b2" (see core/mesh/pairs_io.h)
// and prints one exact distance per pair in input order ("inf" when
// unreachable). Pairs are grouped by their first point so that each distinct
// source is propagated once, stopping as soon as all of its targets are
// settled.
//
// --source-vertex writes every vertex's exact distance from vertex V
// (0-based, in the mesh file's order), one per line: the job an exact
// solver's command line does (VTP's, for one), so that the two compare as
// whole processes. The file is written beside its name and renamed into
// place; '-' (the default) is standard output. It runs the builder's rows
// engine (VertexGeodesicSolver); --engine windows runs ExactGeodesicSolver
// instead, the engine of --pairs. --stats prints the propagation's CPU seconds
// and window counts to standard error.

#include <cstdio>

#include "CLI/CLI.hpp"
#include "core/tools/geodesic_cli.h"

int main(int argc, char** argv) {
  using geodex::tools::GeodesicJob;
  geodex::tools::GeodesicCommandLine command_line;
  CLI11_PARSE(command_line.app(), argc, argv);
  const GeodesicJob job = command_line.job();
  if (job == GeodesicJob::kNone) {
    std::fprintf(stderr, "geodex-geodesic: give --pairs FILE or --source-vertex V\n");
    return 2;
  }
  absl::Status status;
  if (job == GeodesicJob::kPairs) {
    const absl::StatusOr<std::string> text = geodex::tools::PairDistancesText(command_line.args());
    if (text.ok()) std::fwrite(text->data(), 1, text->size(), stdout);
    status = text.status();
  } else {
    status = geodex::tools::WriteDistancesFromVertex(command_line.args(), stderr);
  }
  if (!status.ok()) {
    std::fprintf(stderr, "geodex-geodesic: %s\n", status.ToString().c_str());
    return geodex::tools::GeodesicExitCode(status);
  }
  return 0;
}
