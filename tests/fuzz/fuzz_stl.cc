// libFuzzer target: mesh::ParseStlTriangles (core/mesh/mesh_io.h), ASCII or
// binary by content, welded exactly and with a tolerance, then the repair
// of what it read (tests/fuzz/mesh_fuzz_util.h).

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/mesh/mesh_io.h"
#include "tests/fuzz/mesh_fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view contents(reinterpret_cast<const char*>(data), size);
  for (double tolerance : {0.0, 1e-3}) {
    geodex::mesh::ReadOptions options;
    options.weld_tolerance = tolerance;
    const absl::StatusOr<geodex::mesh::RawMesh> raw =
        geodex::mesh::ParseStlTriangles(contents, "fuzz.stl", options);
    if (raw.ok()) geodex::fuzz::CheckRawAndRepair(*raw);
  }
  return 0;
}
