#pragma once

// A picture of a decal without a viewer: a small software rasteriser that
// draws a whole mesh and paints the checkerboard of image.h on the faces a
// discrete exponential map covers, so that `geodex` can show a map's
// distortion and orientation on a headless machine.
//
// Meant to be used as
//
//   // map: the exponential map of `radius` round a centre; mesh: the same
//   // model version's mesh (both fetched with geodex::client::Client).
//   absl::StatusOr<Image> picture = RenderDecal(mesh, map, radius, RenderOptions{});
//   if (!picture.ok()) return picture.status();
//   // Write EncodePng(*picture) as decal_view.png.
//
// The picture: perspective, z-buffered, flat-shaded (Lambert plus ambient,
// two-sided, a directional light along the view direction). Faces with all
// three vertices in the map show CheckerboardColor at the perspective-correct
// DecalTextureCoordinates of each pixel, as in DecalToObj's OBJ, optionally
// with a ring where the map reaches the radius; other faces are light grey;
// the background is white. A face that faces the camera squarely shows its
// colour unchanged.
//
// Deterministic: the same input gives the same bytes. Pure functions of their
// arguments; thread-safe.

#include <array>
#include <optional>

#include "absl/status/statusor.h"
#include "client/cli/image.h"
#include "geodex/client/types.h"

namespace geodex::client::cli {

// A look-at camera in mesh coordinates. `up` need not be perpendicular to the
// view direction (target - eye); its component across it points up in the
// picture.
struct Camera {
  Position eye = {0, 0, 1};
  Position target = {0, 0, 0};
  Position up = {0, 1, 0};
};

struct RenderOptions {
  int width = 800;  // pixels, 1..16384
  int height = 800;
  // Checker squares across the decal's diameter (1..4096); the orientation
  // marks need >= 4.
  int checker_squares = 8;
  // Paint kRingColor where the map's (u, v) lie within 1 % of the radius.
  // Only decal faces carry (u, v), and they end where the mesh's vertices
  // leave the radius, so the ring is whole where the mesh has vertices on
  // the circle and in pieces where its edges are long against 1 % of it.
  bool draw_radius_ring = false;
  // The perspective's field of view across the smaller image side, in degrees
  // (exclusive 0..180).
  double field_of_view_degrees = 30;
  // The view; nullopt: DefaultDecalCamera.
  std::optional<Camera> camera;
};

// The picture's colours (before shading for the mesh and the ring).
inline constexpr Rgb kBackgroundColor = {255, 255, 255};
inline constexpr Rgb kMeshColor = {200, 200, 200};
inline constexpr Rgb kRingColor = {255, 128, 0};

// The camera RenderDecal uses by default: looking at the map's centre (where
// (u, v) = (0, 0), estimated from the nearest mapped vertices) from along the
// average normal of the decal's faces, on the side the face normals point
// to, from the distance at which a region three radii wide fills the smaller
// side of the picture. Up is the first of +y, +z, +x that is not within
// about 25 degrees of the view direction. Other parts of the mesh may stand
// between this eye and the decal (a decal inside a concavity): pass a camera
// to RenderDecal then. Errors: those of FindDecalPatch
// (decal.h); INVALID_ARGUMENT for a radius or field of view out of range.
absl::StatusOr<Camera> DefaultDecalCamera(const Mesh& mesh, const ExpMap& map, double radius,
                                          double field_of_view_degrees = 30);

// The decal on the whole mesh, seen from options.camera or the default one.
// `radius` is the map's radius in mesh units. Errors: those of
// FindDecalPatch; INVALID_ARGUMENT for a bad radius, an option out of range,
// a camera with non-finite coordinates, eye at target or up along the view
// direction, or a mesh vertex used by a face at a non-finite position.
absl::StatusOr<Image> RenderDecal(const Mesh& mesh, const ExpMap& map, double radius,
                                  const RenderOptions& options = {});

}  // namespace geodex::client::cli
