#pragma once

// Loading triangle meshes from OBJ, PLY (ASCII, binary little- and big-endian)
// and OFF files.
//
// Ids: vertex ids are the file's vertex order (0-based). Faces are numbered in
// file order; a polygon with k > 3 corners (c0, c1, ..., c{k-1}) is
// fan-triangulated into k-2 triangles (c0, c{i}, c{i+1}), i = 1..k-2, that take
// consecutive triangle ids. For a file of triangles only, triangle id = face id
// of the file. `LoadedMesh::input_face` maps triangle ids back to file faces.
//
// Errors: InvalidArgument for a malformed, truncated or garbage file (naming
// file and line or element) and for anything Mesh::Create rejects; reading a
// file fails as ReadWholeFile does (core/common/file_util.h): NotFound when
// there is no file (or a directory), PermissionDenied, Internal.
//
// Thread safety: every function is reentrant.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/mesh/mesh.h"

namespace geodex::mesh {

struct LoadedMesh {
  Mesh mesh;
  // input_face[t] = index of the file face that triangle t came from.
  std::vector<int32_t> input_face;
};

// A file's triangles before any validation of their topology or geometry
// (coordinates are finite and corner ids in range: the readers check those):
// what core/mesh/mesh_repair.h repairs, or Mesh::Create refuses.
struct RawMesh {
  std::string name;  // for error messages (the file name)
  std::vector<Vec3> positions;
  std::vector<Triangle> triangles;  // in triangle-id order (see above)
  // input_face[t] = index of the file face that triangle t came from.
  std::vector<int32_t> input_face;
  // True when a file face had more than 3 corners: error messages then say
  // that face ids count triangles.
  bool polygons = false;
};

// Loads the mesh file at `path` with the reader its extension names (.obj,
// .ply, .off; case-insensitive), keeping the map from triangles to file faces.
// Errors: InvalidArgument for another extension, and those above.
absl::StatusOr<LoadedMesh> LoadMeshFile(const std::string& path);
// LoadMeshFile without the face map: what most callers need.
absl::StatusOr<Mesh> LoadMesh(const std::string& path);
// The file's triangles without Mesh::Create's checks, for repair. Errors:
// those of the readers (malformed files, non-finite coordinates, ids out of
// range) and of reading the file.
absl::StatusOr<RawMesh> LoadRawMeshFile(const std::string& path);
// Mesh::Create on a raw mesh, its InvalidArgument messages noting when face
// ids count triangles of fan-triangulated polygons.
absl::StatusOr<LoadedMesh> CreateLoadedMesh(RawMesh raw);

// Parse in-memory file contents; `name` is used in error messages.
absl::StatusOr<LoadedMesh> ParseObj(std::string_view contents, const std::string& name);
absl::StatusOr<LoadedMesh> ParsePly(std::string_view contents, const std::string& name);
absl::StatusOr<LoadedMesh> ParseOff(std::string_view contents, const std::string& name);
// The same without Mesh::Create's checks (see RawMesh).
absl::StatusOr<RawMesh> ParseObjTriangles(std::string_view contents, const std::string& name);
absl::StatusOr<RawMesh> ParsePlyTriangles(std::string_view contents, const std::string& name);
absl::StatusOr<RawMesh> ParseOffTriangles(std::string_view contents, const std::string& name);

// Writes an ASCII OBJ (v and f lines, 17 significant digits) / binary
// little-endian PLY (double coordinates, int indices): both read back to the
// same mesh. The file is replaced atomically (AtomicWriteFile, with its
// errors: NotFound, PermissionDenied, Internal, naming the path).
absl::Status WriteObj(const Mesh& mesh, const std::string& path);
absl::Status WritePly(const Mesh& mesh, const std::string& path);

}  // namespace geodex::mesh
