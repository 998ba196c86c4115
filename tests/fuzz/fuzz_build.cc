// libFuzzer target: the whole build (core/builder/builder.h) of small meshes
// with the topology scans and their decimation leave behind, as
// geodex-build runs it: repair, flat refinement, sampling, the triangulation
// and its repair, rows, merge. A build either succeeds, and then every
// vertex has a geodesic triangle and distances between vertices of one
// component are finite, or is refused with FailedPrecondition or
// InvalidArgument in one line of at most 300 characters
// (triangulation::kMaxRefusalLength). Anything else aborts.
//
// Bytes: [0] the shape (a sphere, a torus with a tiny tunnel, a pinched
// torus, two spheres and a tube, two spheres touching at a vertex, tiny
// components, crossing sheets), [1] samples (3..34), [2] flags (bit 0:
// cluster the vertices in cubes of (1 + [3] % 16) / 40 of the shape's size,
// a decimation; bit 1: duplicate and zero-area faces; bit 2: the extra
// triangles below), then three bytes a triangle over the shape's first 256
// vertices.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/builder/builder.h"
#include "core/builder/prepared_mesh.h"
#include "core/mesh/broken_meshes_testing.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_repair.h"
#include "core/triangulation/geodesic_triangulation.h"

namespace {

using geodex::mesh::RawMesh;
namespace gen = geodex::mesh::gen;
namespace mt = geodex::mesh::testing;

RawMesh Shape(uint8_t kind) {
  switch (kind % 7) {
    case 0:
      return mt::RawOf(gen::Sphere(2, 1.0), "sphere");
    case 1:
      return mt::RawOf(gen::Torus(32, 16, 1.0, 0.93), "tiny tunnel");
    case 2:
      return mt::RawOf(gen::PinchedTorus(32, 12, 1.0, 0.6, 0.05), "pinched torus");
    case 3:
      return mt::RawOf(gen::Dumbbell(12, 1.0, 0.08, 0.4), "dumbbell");
    case 4:
      return mt::TwoSpheresTouchingAtAVertex(1);
    case 5:
      return mt::ManyTinyComponents(6, 1);
    default:
      return mt::TwoSheetsCrossingAlongAnEdge(3);
  }
}

[[noreturn]] void Fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_build: %s\n", what.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace geodex;
  if (size < 4) return 0;
  RawMesh raw = Shape(data[0]);
  const int32_t samples = 3 + data[1] % 32;
  const uint8_t flags = data[2];
  if ((flags & 1) != 0) {
    raw = mt::ClusterVertices(raw, (1 + data[3] % 16) / 40.0);
    if (raw.triangles.empty()) return 0;
  }
  if ((flags & 2) != 0) raw = mt::WithDuplicateAndZeroAreaFaces(std::move(raw), 11);
  if ((flags & 4) != 0) {
    const int32_t nv = static_cast<int32_t>(std::min<size_t>(raw.positions.size(), 256));
    for (size_t at = 4; at + 3 <= size && at < 4 + 3 * 64; at += 3) {
      mt::AddTriangle(&raw, {data[at] % nv, data[at + 1] % nv, data[at + 2] % nv});
    }
  }
  const absl::StatusOr<mesh::RepairedMesh> repaired = mesh::RepairMesh(raw);
  if (!repaired.ok()) return 0;  // fuzz_repair checks the repair's refusals
  const absl::StatusOr<builder::PreparedMesh> prepared = builder::PrepareMesh(
      repaired->mesh, builder::RecordRepair(*repaired), samples, /*refine=*/true);
  if (!prepared.ok()) Fail("the long-edge split failed: " + prepared.status().ToString());
  builder::BuildOptions options;
  options.num_samples = samples;
  options.threads = 1;
  options.input_vertex_ids = builder::InputVertexIds(*prepared);
  builder::BuildSummary summary;
  const absl::StatusOr<index::IndexData> built =
      builder::BuildPreparedIndex(*prepared, options, &summary);
  if (!built.ok()) {
    const absl::Status& status = built.status();
    if (!absl::IsFailedPrecondition(status) && !absl::IsInvalidArgument(status)) {
      Fail("unexpected error " + status.ToString());
    }
    if (status.message().size() > triangulation::kMaxRefusalLength ||
        status.message().find('\n') != absl::string_view::npos) {
      Fail("refusal longer than one short line: " + status.ToString());
    }
    return 0;
  }
  if (summary.unassigned_vertices != 0) Fail("vertices without a geodesic triangle");
  // The sample distance matrix: finite within a component, symmetric.
  const mesh::Mesh& mesh = prepared->mesh;
  const int32_t m = summary.num_samples;
  if (built->sample_distances.size() != static_cast<size_t>(m) * m) Fail("matrix size");
  std::vector<int32_t> component(m);
  for (int32_t a = 0; a < m; ++a) component[a] = mesh.VertexComponent(built->samples[a]);
  for (int32_t a = 0; a < m; ++a) {
    for (int32_t b = 0; b < m; ++b) {
      const float d = built->sample_distances[static_cast<size_t>(a) * m + b];
      if (d != built->sample_distances[static_cast<size_t>(b) * m + a]) Fail("asymmetric matrix");
      if (component[a] == component[b] && !std::isfinite(d)) Fail("infinite distance");
    }
  }
  return 0;
}
