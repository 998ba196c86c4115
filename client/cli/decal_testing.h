#pragma once

// Meshes and exponential maps with closed-form answers for the decal tests
// (decal_test.cc, render_test.cc). Header-only; tests only.

#include <cmath>
#include <cstdint>

#include "geodex/client/types.h"

namespace geodex::client::cli::decal_testing {

// A square grid of cells x cells cells over [-1, 1]^2 in the plane z = 0.
// Vertex (ix, iy) is iy * (cells + 1) + ix at (-1 + 2 ix / cells, -1 + 2 iy /
// cells, 0); cell (cx, cy) is faces 2 (cy cells + cx) and that + 1, corners
// a = (cx, cy), b = (cx + 1, cy), c = (cx + 1, cy + 1), d = (cx, cy + 1) as
// (a, b, c) and (a, c, d): counter-clockwise seen from +z.
inline Mesh FlatGrid(int cells) {
  Mesh mesh;
  const uint32_t row = static_cast<uint32_t>(cells) + 1;
  for (int iy = 0; iy <= cells; ++iy) {
    for (int ix = 0; ix <= cells; ++ix) {
      mesh.positions.push_back({-1.0 + 2.0 * ix / cells, -1.0 + 2.0 * iy / cells, 0.0});
    }
  }
  for (uint32_t cy = 0; cy < static_cast<uint32_t>(cells); ++cy) {
    for (uint32_t cx = 0; cx < static_cast<uint32_t>(cells); ++cx) {
      const uint32_t a = cy * row + cx, b = a + 1, c = a + row + 1, d = a + row;
      mesh.faces.push_back({a, b, c});
      mesh.faces.push_back({a, c, d});
    }
  }
  return mesh;
}

// The exponential map of a mesh in the plane z = 0 (face normals +z) round
// (x, y): planar polar coordinates, u = x - centre x, v = y - centre y, for
// the vertices within `radius`.
inline ExpMap PlanarExpMap(const Mesh& mesh, double centre_x, double centre_y, double radius) {
  ExpMap map;
  for (size_t vertex = 0; vertex < mesh.positions.size(); ++vertex) {
    const double u = mesh.positions[vertex][0] - centre_x;
    const double v = mesh.positions[vertex][1] - centre_y;
    const double r = std::hypot(u, v);
    if (r > radius) continue;
    map.vertices.push_back(static_cast<int32_t>(vertex));
    map.r.push_back(r);
    map.theta.push_back(std::atan2(v, u));
    map.u.push_back(u);
    map.v.push_back(v);
  }
  return map;
}

}  // namespace geodex::client::cli::decal_testing
