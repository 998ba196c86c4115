// libFuzzer target: mesh::ParsePairs (core/mesh/pairs_io.h), then
// ValidatePairs against a small fixed mesh, as the tools run them.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "core/mesh/generators.h"
#include "core/mesh/pairs_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const geodex::mesh::Mesh* const mesh =
      new geodex::mesh::Mesh(geodex::mesh::gen::Grid(2, 2, 1.0, 1.0));
  auto pairs =
      geodex::mesh::ParsePairs(std::string_view(reinterpret_cast<const char*>(data), size));
  if (!pairs.ok()) return 0;
  (void)geodex::mesh::ValidatePairs(*mesh, *pairs);
  return 0;
}
