#pragma once

// Loading triangle meshes from OBJ, PLY (ASCII, binary little- and big-endian),
// OFF, STL (ASCII and binary) and glTF 2.0 (.gltf with its buffers, .glb)
// files.
//
// Ids: for OBJ, PLY and OFF, vertex ids are the file's vertex order (0-based).
// Faces are numbered in file order; a polygon with k > 3 corners (c0, c1, ...,
// c{k-1}) is fan-triangulated into k-2 triangles (c0, c{i}, c{i+1}), i =
// 1..k-2, that take consecutive triangle ids. For a file of triangles only,
// triangle id = face id of the file. `LoadedMesh::input_face` maps triangle
// ids back to file faces.
//
// STL and glTF store corners, not shared vertices (glTF's indices share a
// vertex only within one primitive, and exporters split vertices along
// texture and normal seams), so their corners are welded (ReadOptions):
// vertex ids are the welded vertices in the order of their first corner.
// Face ids: an STL triangle's is its position in the file. A glTF triangle's
// is its position in the default scene's triangles: the scene's nodes depth
// first (each node, then its children, in the file's order), each node's mesh
// primitives in order, each primitive's triangles in index order, positions
// transformed by the node's world matrix. A file without scenes gives every
// mesh once, untransformed, in mesh order. Morph targets and skins are not
// applied. Primitives of points and lines, strips and fans, and compressed
// or quantized positions are refused.
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

// How a file is read.
struct ReadOptions {
  // STL and glTF: corners closer than weld_tolerance times the diagonal of
  // the corners' bounding box are one vertex. 0 (the default) welds exactly
  // equal positions only; otherwise in [1e-12, 1]. Corners are taken in file
  // order; a corner joins the nearest vertex within the tolerance, whose
  // position is that of its first corner (so a corner moves by at most the
  // tolerance), or starts a vertex of its own. Two corners of one triangle
  // never join one vertex: the later one keeps a vertex of its own at its
  // position (the triangle keeps its three corners, with an edge of length
  // 0). The OBJ, PLY and OFF readers, whose files name their vertices, refuse
  // a tolerance other than 0.
  double weld_tolerance = 0;
};

// Checks a weld tolerance (ReadOptions::weld_tolerance). Errors:
// InvalidArgument naming the value.
absl::Status ValidateWeldTolerance(double weld_tolerance);

// What welding did to a file's corners.
struct WeldReport {
  bool welded = false;             // the file's corners were welded (STL, glTF)
  double tolerance = 0;            // ReadOptions::weld_tolerance
  int64_t welded_corners = 0;      // corners that joined an earlier corner's vertex
  int64_t degenerate_corners = 0;  // corners kept apart from their own triangle's
};

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
  WeldReport weld;
};

// Loads the mesh file at `path` with the reader its extension names (.obj,
// .ply, .off, .stl, .gltf, .glb; case-insensitive), keeping the map from
// triangles to file faces. Errors: InvalidArgument for another extension, for
// a weld tolerance a format does not take, and those above.
absl::StatusOr<LoadedMesh> LoadMeshFile(const std::string& path, const ReadOptions& options = {});
// LoadMeshFile without the face map: what most callers need.
absl::StatusOr<Mesh> LoadMesh(const std::string& path, const ReadOptions& options = {});
// The file's triangles without Mesh::Create's checks, for repair. Errors:
// those of the readers (malformed files, non-finite coordinates, ids out of
// range) and of reading the file.
absl::StatusOr<RawMesh> LoadRawMeshFile(const std::string& path, const ReadOptions& options = {});
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

// STL, ASCII ("solid ... facet normal ... outer loop ... vertex x y z ...")
// or binary (80-byte header, little-endian uint32 triangle count, 50 bytes a
// triangle), told apart by the file's size and first word. Its triangles,
// corners welded (ReadOptions). Errors: InvalidArgument naming the file and
// the line (ASCII) or triangle (binary): a size that does not match the
// triangle count, a truncated facet, a facet of other than 3 vertices, a
// malformed or non-finite coordinate, no triangles.
absl::StatusOr<RawMesh> ParseStlTriangles(std::string_view contents, const std::string& name,
                                          const ReadOptions& options = {});

// glTF 2.0, binary (.glb, told by its magic) or JSON text, read with
// tinygltf (images are not decoded). External buffers are read from
// `base_dir` (the .gltf file's directory); with an empty `base_dir` only
// embedded buffers (data: URIs, the GLB chunk) are read. The default scene's
// triangles (see the header comment), corners welded (ReadOptions). Errors:
// InvalidArgument naming the file and the element: malformed JSON or GLB,
// a missing or short buffer, an accessor out of its buffer, an index out of
// range, a non-triangle primitive, a non-float or non-finite position,
// unsupported required extensions, no triangles.
absl::StatusOr<RawMesh> ParseGltfTriangles(std::string_view contents, const std::string& name,
                                           const std::string& base_dir,
                                           const ReadOptions& options = {});

// Writes an ASCII OBJ (v and f lines, 17 significant digits) / binary
// little-endian PLY (double coordinates, int indices): both read back to the
// same mesh. The file is replaced atomically (AtomicWriteFile, with its
// errors: NotFound, PermissionDenied, Internal, naming the path).
absl::Status WriteObj(const Mesh& mesh, const std::string& path);
absl::Status WritePly(const Mesh& mesh, const std::string& path);

// The mesh's triangles as STL, in face order, each with its unit normal:
// binary (coordinates rounded to float32) or ASCII (coordinates with 17
// significant digits: the doubles themselves). Read back (exact welding),
// they give the mesh's faces over its positions (float32-rounded for binary)
// with the vertices renumbered in the order of their first corner, when no
// two vertices of the mesh share a position (after rounding).
std::string StlBytes(const Mesh& mesh, bool binary);
// The mesh as a binary glTF 2.0 file: one node without a transform, one
// mesh of one TRIANGLES primitive, float32 positions and uint32 indices in
// one buffer. Reads back to the mesh with float32-rounded positions.
std::string GlbBytes(const Mesh& mesh);
// StlBytes / GlbBytes written atomically (AtomicWriteFile's errors).
absl::Status WriteStl(const Mesh& mesh, const std::string& path, bool binary);
absl::Status WriteGlb(const Mesh& mesh, const std::string& path);

}  // namespace geodex::mesh
