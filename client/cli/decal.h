#pragma once

// Decal output of the `geodex` CLI: the patch of a mesh that a discrete
// exponential map (geodesic polar coordinates round a centre, ExpMap in
// geodex/client/types.h) covers, as a textured Wavefront OBJ + MTL pair, so
// that the checkerboard of image.h lies on the surface as the map places it.
//
// Meant to be used as
//
//   // map: the exponential map of `radius` round a centre; mesh: the same
//   // model version's mesh (both fetched with geodex::client::Client).
//   absl::StatusOr<DecalFiles> files =
//       DecalToObj(mesh, map, radius, "decal.mtl", "decal.png");
//   if (!files.ok()) return files.status();
//   // Write files->obj as decal.obj, files->mtl as decal.mtl and
//   // EncodePng(Checkerboard(1024, 8)) as decal.png, all in one directory;
//   // MeshLab and Blender then open decal.obj textured.
//
// RenderDecal (render.h) draws the same decal without a viewer.
//
// Pure functions of their arguments; thread-safe.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "geodex/client/types.h"

namespace geodex::client::cli {

// The faces of a mesh that an exponential map covers completely.
struct DecalPatch {
  // map_entry[v]: the index into the map's arrays of mesh vertex v, or -1
  // when v is not in the map (beyond the radius). #V entries.
  std::vector<int32_t> map_entry;
  // The ids of the faces whose three vertices are all in the map, ascending.
  std::vector<int32_t> faces;
};

// Checks `map` against `mesh` and finds the faces it covers. Errors:
//   INVALID_ARGUMENT  the map's arrays differ in length, its vertex ids do not
//                     strictly ascend or one is negative, one of its r, theta,
//                     u, v or the position of one of its vertices is not
//                     finite, the map is empty, or no face has all three
//                     vertices in it (a radius below the mesh's edge length);
//   OUT_OF_RANGE      a map vertex id or a face's vertex id is not below the
//                     mesh's number of vertices;
//   FAILED_PRECONDITION  map and mesh carry different non-zero model versions.
absl::StatusOr<DecalPatch> FindDecalPatch(const Mesh& mesh, const ExpMap& map);

// The texture coordinates (s, t) of the map point (u, v) for a decal of
// `radius`: (u / (2 radius) + 0.5, v / (2 radius) + 0.5), so the disc of the
// radius fills the unit square and the map's centre is its centre.
std::array<double, 2> DecalTextureCoordinates(double u, double v, double radius);

// An OBJ and the MTL it refers to.
struct DecalFiles {
  std::string obj;
  std::string mtl;
};

// The decal as OBJ + MTL. The OBJ holds the faces of FindDecalPatch with
// their orientation, and only the vertices they use, renumbered 1.. in
// ascending mesh vertex order; each vertex has one `vt`, its
// DecalTextureCoordinates; faces are `f a/a b/b c/c`. Comment lines
// "# mesh vertices: ..." and "# mesh faces: ..." list the mesh id of each OBJ
// vertex and face in order, runs of consecutive ids written "first-last". The
// OBJ names the MTL by `mtllib mtl_file_name`; the MTL (one matte material)
// names the texture by `map_Kd texture_file_name`. Viewers look both up
// relative to the file that names them, so plain file names put the three
// files side by side.
//
// `radius` is the map's radius in mesh units (> 0, finite). Errors: those of
// FindDecalPatch; INVALID_ARGUMENT for a bad radius, or a file name that is
// empty or has white space, a control character or '#' (OBJ and MTL readers
// split lines at white space and cut them at '#').
absl::StatusOr<DecalFiles> DecalToObj(const Mesh& mesh, const ExpMap& map, double radius,
                                      const std::string& mtl_file_name,
                                      const std::string& texture_file_name);

// OK for a finite radius > 0, INVALID_ARGUMENT otherwise.
absl::Status CheckDecalRadius(double radius);

}  // namespace geodex::client::cli
