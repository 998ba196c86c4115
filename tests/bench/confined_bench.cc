// confined_bench: exact distances of near pairs, by the propagation confined
// to a region that grows until certified (ConfinedGeodesicSolver) against the
// whole-mesh window engine stopped at the second point (ExactGeodesicSolver
// with a stop point, what LocalExact::NearDistance runs), in the same run, on
// the same pairs. Prints a Markdown table, one line per mesh.
//
//   confined_bench [--mesh PATH]... [--pairs N] [--seed S] [--seed-rings K]
//
// Without --mesh: bunny_3k, homer_6k, cheburashka_7k, kitten_9k and
// bunny_closed_30k from the shared mesh directory ($GEODEX_SHARED_MESHES,
// else GEODEX_SHARED_MESHES_DEFAULT); a mesh that is not there is skipped
// with a message. Meshes are repaired as the builder repairs them.
//
// Pairs: p area-uniform on the surface; q a vertex at geodesic distance
// 1L-3L from p (L = sqrt(2A / (sqrt(3) * 1000)), the sample spacing of 1000
// samples), or, every other pair, a point inside a face round such a vertex
// that is 1L-3L away too. Generated before any timing.
//
// Per pair, as CPU time of the thread (steadier than wall time on a shared
// machine), after a warm-up pass over the first pairs:
//  - whole: ExactGeodesicSolver::Propagate({p}, stop_points {q}) and
//    DistanceAt(q), one solver reused (as a QueryScratch keeps it);
//  - chain: ConfinedGeodesicSolver::Distance(p, q) without seed faces (its
//    region starts as a shortest chain of faces from p's to q's);
//  - path: the same seeded with the faces of the exact geodesic's points,
//    standing in for the faces a walk from p to q crossed.
// Reported: median and p99 microseconds per pair, the share of pairs whose
// region had to grow and the mean number of propagations, the median region
// size and windows created (over all rounds), the median cost of making the chain's final region a
// mesh of its own with a solver over it (what running the engine on an extracted sub-mesh would pay
// before propagating), and the largest relative difference of either confined distance from the
// whole-mesh one.

#include <cstdint>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "tests/bench/confined_bench_lib.h"

int main(int argc, char** argv) {
  CLI::App app{"Exact near-pair distances: confined propagation against the whole-mesh engine"};
  std::vector<std::string> meshes;
  int num_pairs = 300;
  uint32_t seed = 1;
  app.add_option("--mesh", meshes, "mesh files (default: five shared meshes)");
  app.add_option("--pairs", num_pairs, "pairs per mesh")->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "random seed of the pairs");
  geodex::geodesic::ConfinedOptions confined_options;
  app.add_option("--seed-rings", confined_options.seed_rings,
                 "vertex rings round the seed faces of the first region")
      ->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  if (meshes.empty()) meshes = geodex::bench::DefaultConfinedMeshes();
  return geodex::bench::RunConfinedBench(meshes, num_pairs, seed, confined_options);
}
