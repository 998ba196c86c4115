#pragma once

// Shared body of the mesh-format fuzz targets: parse, then check what the
// parser returned against the invariants the rest of geodex relies on.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_repair.h"
#include "core/mesh/mesh_repair_testing.h"

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

// Checks what a corner-welding reader returned (ids in range, finite
// positions, one face per triangle in order) and what the repair makes of it
// (mesh_repair_testing.h); aborts, saying why, on any broken promise.
inline void CheckRawAndRepair(const mesh::RawMesh& raw) {
  const size_t nv = raw.positions.size();
  for (const mesh::Vec3& p : raw.positions) {
    if (!p.allFinite()) {
      std::fprintf(stderr, "reader returned a non-finite position\n");
      std::abort();
    }
  }
  if (raw.input_face.size() != raw.triangles.size()) std::abort();
  for (size_t t = 0; t < raw.triangles.size(); ++t) {
    if (raw.input_face[t] != static_cast<int32_t>(t)) std::abort();
    const mesh::Triangle& tri = raw.triangles[t];
    for (int32_t v : tri) {
      if (v < 0 || static_cast<size_t>(v) >= nv) std::abort();
    }
    // Welding never gives one triangle the same vertex twice.
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      std::fprintf(stderr, "triangle %zu repeats a vertex after welding\n", t);
      std::abort();
    }
  }
  const absl::StatusOr<mesh::RepairedMesh> repaired = mesh::RepairMesh(raw);
  const std::string problem = mesh::testing::CheckRepair(raw, repaired);
  if (!problem.empty()) {
    std::fprintf(stderr, "repair: %s\n", problem.c_str());
    std::abort();
  }
}

}  // namespace geodex::fuzz
