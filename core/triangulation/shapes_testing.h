#pragma once

// Test-only: the generated shapes every triangulation test runs on, each with
// the sample count its tests use. One group of each kind the builder meets:
// closed surfaces of genus 0, 1 and 2 (sphere, cube, torus, double torus),
// surfaces with boundary (flat grid, square with a hole, folded sheet), and
// several connected components.

#include <cstdint>
#include <vector>

#include "core/mesh/mesh.h"

namespace geodex::triangulation {

struct TestShape {
  const char* name;
  mesh::Mesh mesh;
  int32_t samples;  // farthest-point samples to draw on it
};

// Made afresh on each call, in a fixed order.
std::vector<TestShape> TestShapes();

}  // namespace geodex::triangulation
