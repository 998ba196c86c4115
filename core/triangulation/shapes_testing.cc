#include "core/triangulation/shapes_testing.h"

#include "core/mesh/generators.h"

namespace geodex::triangulation {

std::vector<TestShape> TestShapes() {
  namespace gen = mesh::gen;
  std::vector<TestShape> shapes;
  shapes.push_back({"grid", gen::Grid(24, 24, 3.0, 3.0, 0.3, 7), 40});
  shapes.push_back({"sphere", gen::Sphere(4, 1.0), 60});
  shapes.push_back({"torus", gen::Torus(64, 32, 2.0, 0.7), 60});
  shapes.push_back({"cube", gen::Cube(12, 2.0), 50});
  shapes.push_back({"double_torus", gen::DoubleTorus(12, 4.0), 80});
  shapes.push_back({"square_with_hole", gen::SquareWithHole(24, 3.0), 40});
  shapes.push_back({"two_components", gen::TwoComponents(16), 30});
  shapes.push_back({"folded_sheet", gen::FoldedSheet(20, 12, 2.0, 1.0, 1.0), 20});
  return shapes;
}

}  // namespace geodex::triangulation
