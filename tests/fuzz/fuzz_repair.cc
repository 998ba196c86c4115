// libFuzzer target: mesh::RepairMesh (core/mesh/mesh_repair.h) on soups
// decoded from arbitrary bytes. Every repaired mesh must be valid and hold
// the input's faces, every refusal must be for a documented reason (checked
// by mesh_repair_testing.h), and two repairs of one soup must agree.
//
// Bytes: [0] vertex count (3..18), [1] flags (bit 0: coordinates on the grid
// {0, 1, 2}^3, where positions coincide and angles tie; bit 1: one
// coordinate NaN; bit 2: polygons, consecutive triangles of one file face),
// then three bytes a vertex (coordinates) and three a triangle (corners).

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_repair.h"
#include "core/mesh/mesh_repair_testing.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using geodex::mesh::RawMesh;
  if (size < 2) return 0;
  const int nv = 3 + data[0] % 16;
  const uint8_t flags = data[1];
  size_t at = 2;
  RawMesh raw;
  raw.name = "fuzz";
  for (int v = 0; v < nv; ++v) {
    geodex::mesh::Vec3 p;
    for (int i = 0; i < 3; ++i) {
      const uint8_t b = at < size ? data[at] : static_cast<uint8_t>(v * 7 + i);
      ++at;
      p[i] = (flags & 1) != 0 ? b % 3 : static_cast<int8_t>(b) / 16.0;
    }
    raw.positions.push_back(p);
  }
  if ((flags & 2) != 0) raw.positions[data[0] % nv].y() = std::nan("");
  int32_t file_face = -1;
  for (; at + 3 <= size; at += 3) {
    const geodex::mesh::Triangle t = {data[at] % nv, data[at + 1] % nv, data[at + 2] % nv};
    // With polygons, a triangle that shares its first corner with the one
    // before continues its fan: one file face.
    const bool continues = (flags & 4) != 0 && !raw.triangles.empty() &&
                           raw.triangles.back()[0] == t[0] && raw.triangles.back()[2] == t[1];
    if (!continues) ++file_face;
    raw.triangles.push_back(t);
    raw.input_face.push_back(file_face);
  }
  raw.polygons = file_face + 1 != static_cast<int32_t>(raw.triangles.size());
  const absl::StatusOr<geodex::mesh::RepairedMesh> a = geodex::mesh::RepairMesh(raw);
  const std::string problem = geodex::mesh::testing::CheckRepair(raw, a);
  if (!problem.empty()) {
    std::fprintf(stderr, "repair: %s\n", problem.c_str());
    std::abort();
  }
  const absl::StatusOr<geodex::mesh::RepairedMesh> b = geodex::mesh::RepairMesh(raw);
  if (a.ok() != b.ok() || (a.ok() && !geodex::mesh::testing::SameRepair(*a, *b)) ||
      (!a.ok() && a.status() != b.status())) {
    std::fprintf(stderr, "two repairs of one soup differ\n");
    std::abort();
  }
  return 0;
}
