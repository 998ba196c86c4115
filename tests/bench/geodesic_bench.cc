// geodesic_bench: single-source exact geodesic propagation, ours against
// VTP (Qin et al. 2016, the fastest published exact solver) and CGAL's
// Surface_mesh_shortest_path, in the same run, on the same mesh and the same
// sources. Ours is two engines: the wavefront engine (VertexGeodesicSolver,
// vertex distances only: the builder's rows and sampling) and the window
// engine (ExactGeodesicSolver, which DistanceAt and PathTo need). Prints a
// Markdown table, one line per engine and mesh.
//
//   geodesic_bench [--mesh PATH]... [--sources K] [--cgal-large-sources K]
//                  [--large-vertices N] [--vtp-dir DIR] [--no-cgal]
//                  [--no-windows]
//
// Without --mesh: bunny_closed_30k.obj and igea_134k.obj from the shared mesh
// directory ($GEODEX_SHARED_MESHES, else GEODEX_SHARED_MESHES_DEFAULT), or,
// when neither is there, a generated icosphere (6 subdivisions, 40962
// vertices). A mesh of 500K vertices and more: `split_mesh` (igea_134k split
// once has 537K), with --no-cgal --no-windows.
//
// What is measured, per mesh: each algorithm runs in its own forked child
// process, so none sees another's heap.
//  - time: seconds per source, mean over the sources, as wall clock and as
//    CPU time of the child (steadier when the machine is shared). One source
//    is the propagation plus reading every vertex distance into a vector.
//    Setup (our solvers' per-mesh tables; CGAL's Surface_mesh copy) is not
//    included and is printed separately. The ratio to VTP is of CPU times:
//    VTP prints clock(), its CPU time.
//  - memory: the increase of the child's peak RSS (getrusage RUSAGE_SELF
//    ru_maxrss) from just before the solver is made to the end of the last
//    propagation. The mesh is loaded in the parent before the fork, so it is
//    in the baseline; CGAL's own copy of it (its Surface_mesh) is built
//    in the child before the baseline, as the counterpart of our Mesh. The
//    peak is reset to the current RSS at the baseline (/proc/self/clear_refs,
//    "5") so that transient allocations made earlier do not hide the increase.
//  - the largest relative difference between each engine's distance field
//    and VTP's, as a check that all are exact.
// CGAL's sequence tree needs ~9 GB on the 134k-vertex Igea, so on meshes with
// at least --large-vertices vertices CGAL runs only --cgal-large-sources
// sources (default 1); ours still runs --sources.
//
// VTP is built from its sources (--vtp-dir, default the shared directory's
// anchors/vtp, with its own build.sh: g++ -O3 -march=native) into the working
// directory, and run as a process per source on the mesh as OBJ (written to
// a temporary file when the input is not one), as its command line does:
// whole mesh, every vertex distance written to a file. Measured per source:
// its own printed propagation time, the wall time of the whole process, and
// the process's peak RSS (wait4), mesh included; its distances are compared
// with ours. Skipped, with a note, when its directory is absent.
//
// The harness is in geodesic_bench_lib.h, the engines' runs in
// geodesic_bench_engines.h.

#include <utility>

#include "tests/bench/bench_flags.h"
#include "tests/bench/geodesic_bench_lib.h"

int main(int argc, char** argv) {
  geodex::bench::GeodesicBenchOptions options;
  const auto app = geodex::bench::GeodesicBenchFlags(&options);
  if (const auto exit_code = geodex::bench::ParseFlags(*app, argc, argv)) return *exit_code;
  return geodex::bench::RunGeodesicBench(std::move(options));
}
