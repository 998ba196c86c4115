#pragma once

// RGB images for the decal outputs of the `geodex` CLI: a PNG encoder and the
// checkerboard texture that a discrete exponential map carries onto a mesh.
//
// The checkerboard is the texture DecalToObj (decal.h) refers to and the
// pattern RenderDecal (render.h) paints, so a decal looks the same in MeshLab
// or Blender as in geodex's own picture:
//
//   const std::string png = EncodePng(Checkerboard(1024, 8));  // write as decal.png
//   absl::StatusOr<DecalFiles> files =
//       DecalToObj(mesh, map, radius, "decal.mtl", "decal.png");  // write beside it
//
// Texture coordinates (s, t) are those of OBJ `vt` lines: s to the right, t
// upwards, (0, 0) the image's bottom-left corner (row height - 1).
//
// Everything here is a pure function of its arguments; thread-safe.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace geodex::client::cli {

// An 8-bit RGB image: pixel (x, y), y = 0 the top row, is the three bytes at
// rgb[3 * (y * width + x)].
struct Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;  // 3 * width * height
};

// An 8-bit RGB colour.
using Rgb = std::array<uint8_t, 3>;

// `image` as a PNG file (8-bit RGB, not interlaced, zlib-compressed). Requires
// width > 0, height > 0 and rgb.size() == 3 * width * height; an image that
// breaks this is a programming error (asserted), and gives "" in release
// builds rather than reading past the pixels.
std::string EncodePng(const Image& image);

// The checkerboard decal texture: `squares` x `squares` squares over the unit
// square of texture coordinates, alternating dark and light, square (0, 0) at
// (s, t) = (0, 0) dark. Its centre, (s, t) = (0.5, 0.5), is the exponential
// map's centre (see DecalToObj). Orientation marks, so that a rotated or
// mirrored decal shows (they need squares >= 4):
//   - the squares of the +u +v quadrant (s, t > 0.5) are tinted red, except
//   - its row of squares nearest the +u axis (for even `squares`, the row
//     just above t = 0.5, right of s = 0.5), tinted green.
// A rotation moves the red quadrant; a mirror image puts the green row on the
// wrong side of it. Non-finite coordinates give the centre's colour.
Rgb CheckerboardColor(double s, double t, int squares);

// A `size` x `size` image of CheckerboardColor, sampled at pixel centres
// (pixel (x, y) at s = (x + 0.5) / size, t = 1 - (y + 0.5) / size). Requires
// size >= 1 and squares >= 1 (asserted; an empty image otherwise).
Image Checkerboard(int size, int squares);

}  // namespace geodex::client::cli
