#pragma once

// A read-only view of a mesh as the index stores it, with the few walks the
// query code needs: vertex positions, face corners, twins, and the fan of
// faces round a vertex, and the canonical form of a surface point. Internal
// to core/query (the engine, the lifting, the path tracer and straightener).
//
// Thread safety: a view of immutable arrays; every method is const and
// thread-safe.

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>

#include "core/mesh/mesh.h"

namespace geodex::query {

// xyz per vertex, 3 vertex ids per face, and the twin of each half-edge
// (3 f + i: from corner i to corner i+1) or -1 on the boundary.
struct MeshView {
  // The most steps a walk round one vertex takes: a guard against broken
  // twins, far above any valence a mesh has.
  static constexpr int kMaxFanSteps = 4096;

  std::span<const double> positions;
  std::span<const int32_t> faces;
  std::span<const int32_t> twins;

  // The 3D position of a surface point.
  mesh::Vec3 PositionOf(const mesh::SurfacePoint& p) const;
  // A valid point with its weights clamped to >= 0 and summing to 1, and,
  // on an edge, expressed in the face of lower id, so that both
  // descriptions of a point give the same answers.
  mesh::SurfacePoint Canonical(const mesh::SurfacePoint& p) const;
  // A canonical vertex point re-expressed in the vertex's face of lowest id,
  // other points unchanged. The traces start from a point's face, so they
  // need it; the O(1) lift of a vertex is its record, whatever the face.
  mesh::SurfacePoint InLowestFaceIfVertex(const mesh::SurfacePoint& c) const;
  // The total area of the faces.
  double Area() const;

  mesh::Vec3 Position(int32_t v) const {
    return {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]};
  }
  // The vertex at corner i of face f.
  int32_t Vertex(int32_t f, int i) const { return faces[3 * f + i]; }
  // The corner of face f at vertex v, or -1 when f does not hold v.
  int Corner(int32_t f, int32_t v) const {
    for (int i = 0; i < 3; ++i) {
      if (faces[3 * f + i] == v) return i;
    }
    return -1;
  }
  // One step round vertex v: the face across the edge of f that leaves v
  // (dir 0) or enters it (dir 1); -1 at the boundary or when f does not
  // hold v.
  int32_t Turn(int32_t f, int32_t v, int dir) const {
    const int k = Corner(f, v);
    if (k < 0) return -1;
    const int32_t t = twins[dir == 0 ? 3 * f + k : 3 * f + (k + 2) % 3];
    return t < 0 ? -1 : t / 3;
  }
  // Appends the faces round vertex v to *out: f first, then the faces one
  // step after another in direction 0 until the fan closes back on f, or,
  // at a boundary, those of direction 1 too. At most kMaxFanSteps steps a
  // direction.
  template <typename Faces>
  void FacesAround(int32_t v, int32_t f, Faces* out) const {
    out->push_back(f);
    for (int dir = 0; dir < 2; ++dir) {
      int32_t g = f;
      for (int step = 0; step < kMaxFanSteps; ++step) {
        g = Turn(g, v, dir);
        if (g < 0) break;
        if (g == f) return;
        out->push_back(g);
      }
    }
  }
};

// Inline: on the path of every query.

inline mesh::SurfacePoint MeshView::Canonical(const mesh::SurfacePoint& p) const {
  mesh::SurfacePoint c = p;
  double sum = 0;
  for (double& w : c.w) {
    w = std::max(w, 0.0);
    sum += w;
  }
  for (double& w : c.w) w /= sum;
  // A point on an edge is expressed in the face of lower id, so that both
  // descriptions of it give the same answers.
  int zeros = 0, zero = 0;
  for (int i = 0; i < 3; ++i) {
    if (c.w[i] == 0) {
      ++zeros;
      zero = i;
    }
  }
  if (zeros == 1) {
    const int32_t h = 3 * c.face + (zero + 1) % 3;  // the edge opposite the zero weight
    const int32_t g = twins[h];
    if (g >= 0 && g / 3 < c.face) {
      mesh::SurfacePoint t{g / 3, {0, 0, 0}};
      t.w[g % 3] = c.w[(zero + 2) % 3];            // Origin(g) = Dest(h)
      t.w[(g % 3 + 1) % 3] = c.w[(zero + 1) % 3];  // Dest(g) = Origin(h)
      return t;
    }
  }
  return c;
}

// Walking across the faces of a MeshView in barycentric coordinates.

// Where the descent `beta` (barycentric velocities, sum 0) from barycentric
// position `b` leaves the face: the corner whose weight reaches 0 first (-1
// if none decreases) and the step *t to it.
int DescentExit(const std::array<double, 3>& beta, const std::array<double, 3>& b, double* t);

// Barycentric weights `w` of a point on the edge of a face opposite its
// corner `exit`, re-expressed in the face across that edge, whose half-edge
// g (3 * face + corner) is the twin of the edge's.
std::array<double, 3> AcrossEdge(int32_t g, int exit, const std::array<double, 3>& w);

}  // namespace geodex::query
