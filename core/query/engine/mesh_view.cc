#include "core/query/engine/mesh_view.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace geodex::query {

using mesh::SurfacePoint;

SurfacePoint MeshView::InLowestFaceIfVertex(const SurfacePoint& c) const {
  int corner = -1;
  for (int i = 0; i < 3; ++i) {
    if (c.w[i] == 1) corner = i;
  }
  if (corner < 0) return c;
  const int32_t v = Vertex(c.face, corner);
  struct LowestFace {  // FacesAround's output, keeping only the lowest id
    int32_t id;
    void push_back(int32_t f) { id = std::min(id, f); }
  } lowest{c.face};
  FacesAround(v, c.face, &lowest);
  SurfacePoint t{lowest.id, {0, 0, 0}};
  t.w[Corner(lowest.id, v)] = 1;
  return t;
}

mesh::Vec3 MeshView::PositionOf(const SurfacePoint& p) const {
  const int32_t* f = &faces[3 * p.face];
  return p.w[0] * Position(f[0]) + p.w[1] * Position(f[1]) + p.w[2] * Position(f[2]);
}

double MeshView::Area() const {
  double area = 0;
  for (size_t f = 0; f < faces.size() / 3; ++f) {
    const int32_t* v = &faces[3 * f];
    area += 0.5 * (Position(v[1]) - Position(v[0])).cross(Position(v[2]) - Position(v[0])).norm();
  }
  return area;
}

int DescentExit(const std::array<double, 3>& beta, const std::array<double, 3>& b, double* t) {
  *t = std::numeric_limits<double>::infinity();
  int exit = -1;
  const double eps = 1e-12 * (std::abs(beta[0]) + std::abs(beta[1]) + std::abs(beta[2]));
  for (int i = 0; i < 3; ++i) {
    if (beta[i] < -eps) {
      const double ti = -b[i] / beta[i];
      if (ti < *t) {
        *t = ti;
        exit = i;
      }
    }
  }
  return exit;
}

std::array<double, 3> AcrossEdge(int32_t g, int exit, const std::array<double, 3>& w) {
  std::array<double, 3> next = {0, 0, 0};
  next[g % 3] = w[(exit + 2) % 3];            // Origin(g) = Dest(h)
  next[(g % 3 + 1) % 3] = w[(exit + 1) % 3];  // Dest(g) = Origin(h)
  return next;
}

}  // namespace geodex::query
