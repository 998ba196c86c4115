// libFuzzer target: mesh::ParseGltfTriangles (core/mesh/mesh_io.h) on
// arbitrary bytes, GLB or JSON by content, with no file access (buffers are
// embedded or missing), then the repair of what it read
// (tests/fuzz/mesh_fuzz_util.h).

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/mesh/mesh_io.h"
#include "tests/fuzz/mesh_fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view contents(reinterpret_cast<const char*>(data), size);
  const absl::StatusOr<geodex::mesh::RawMesh> raw =
      geodex::mesh::ParseGltfTriangles(contents, "fuzz.gltf", /*base_dir=*/"");
  if (raw.ok()) geodex::fuzz::CheckRawAndRepair(*raw);
  return 0;
}
