// geodex-accuracy: the full accuracy run, by distance scale.
//
//   geodex-accuracy MESH... --samples 250,500,1000,2000 [--sources S] [--points N]
//                   [--per-bin N] [--index-dir DIR] [--threads T] [--modes unfold,default,...]
//
// For each mesh and each m: builds the index (or reuses DIR/<mesh>-m<M>.gdx),
// draws pairs at every distance scale with their exact distances (see
// accuracy.h), and prints per bin and point kind the error of each answer
// mode, then a summary row with the worst bin. MESH may be builtin:NAME.
// The harness itself is accuracy_harness.h.

#include <cstdio>

#include "CLI/CLI.hpp"
#include "tests/accuracy/accuracy_harness.h"

int main(int argc, char** argv) {
  geodex::accuracy::AccuracyCommandLine command_line;
  CLI11_PARSE(command_line.app(), argc, argv);
  const absl::Status status = geodex::accuracy::RunHarness(command_line.flags());
  if (!status.ok()) {
    std::fprintf(stderr, "geodex-accuracy: %s\n", status.ToString().c_str());
    return 1;
  }
  return 0;
}
