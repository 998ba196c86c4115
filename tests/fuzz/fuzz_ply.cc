// libFuzzer target: mesh::ParsePly (core/mesh/mesh_io.h) on arbitrary bytes;
// the header picks ASCII, binary little- or big-endian, so one target (and
// seeds of each) covers all three readers.

#include <cstddef>
#include <cstdint>

#include "core/mesh/mesh_io.h"
#include "tests/fuzz/mesh_fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  geodex::fuzz::FuzzMeshParser(data, size, geodex::mesh::ParsePly);
  return 0;
}
