#pragma once

// The confined exact solver against the whole-mesh engine on near pairs
// (confined_bench.cc says what is measured and how).

#include <cstdint>
#include <string>
#include <vector>

#include "core/geodesic/confined_geodesic.h"

namespace geodex::bench {

// The five shared meshes the benchmark runs on by default, those present
// (a message on stderr for each one missing).
std::vector<std::string> DefaultConfinedMeshes();

// Prints the Markdown table, a line per mesh. Returns 0, 1 when a mesh
// could not be read, 2 when a confined distance differed from the whole-mesh
// one by more than 1e-9 relative.
int RunConfinedBench(const std::vector<std::string>& meshes, int num_pairs, uint32_t seed,
                     const geodesic::ConfinedOptions& options);

}  // namespace geodex::bench
