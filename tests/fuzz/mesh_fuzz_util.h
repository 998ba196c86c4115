#pragma once

// Shared body of the mesh-format fuzz targets: parse, then check what the
// parser returned against the invariants the rest of geodex relies on.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "absl/status/statusor.h"
#include "core/mesh/mesh_io.h"

namespace geodex::fuzz {

// Parses `data` with `parse`; when it parses, re-creates the mesh from its
// arrays with Mesh::Create (the parsers already did: a second Create must
// accept what the first produced) and walks every array, so that ASan sees
// out-of-bounds ids.
template <typename Parse>
void FuzzMeshParser(const uint8_t* data, size_t size, Parse parse) {
  const std::string_view contents(reinterpret_cast<const char*>(data), size);
  absl::StatusOr<mesh::LoadedMesh> loaded = parse(contents, "fuzz");
  if (!loaded.ok()) return;
  const mesh::Mesh& m = loaded->mesh;
  if (loaded->input_face.size() != static_cast<size_t>(m.num_faces())) std::abort();
  double sum = 0;
  for (const mesh::Vec3& p : m.positions()) sum += p.x() + p.y() + p.z();
  for (const mesh::Triangle& t : m.faces()) {
    for (int32_t v : t) {
      if (v < 0 || v >= m.num_vertices()) std::abort();
      sum += m.positions()[v].x();
    }
  }
  absl::StatusOr<mesh::Mesh> again =
      mesh::Mesh::Create(std::vector<mesh::Vec3>(m.positions().begin(), m.positions().end()),
                         std::vector<mesh::Triangle>(m.faces().begin(), m.faces().end()), "again");
  if (!again.ok()) std::abort();
  volatile double sink = sum;
  (void)sink;
}

}  // namespace geodex::fuzz
