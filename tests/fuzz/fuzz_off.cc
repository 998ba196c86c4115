// libFuzzer target: mesh::ParseOff (core/mesh/mesh_io.h) on arbitrary bytes.

#include <cstddef>
#include <cstdint>

#include "core/mesh/mesh_io.h"
#include "tests/fuzz/mesh_fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  geodex::fuzz::FuzzMeshParser(data, size, geodex::mesh::ParseOff);
  return 0;
}
