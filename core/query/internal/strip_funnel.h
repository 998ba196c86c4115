#pragma once

// A strip of faces unfolded into the plane, and the shortest path through
// it: the parts the chord walk (chord_walk.h) and the path straightener
// (path_straightening.h) are built of.
//
// A strip is a sequence of faces, each sharing an edge with the one before.
// Laid out face after face (the first with corner 0 at the origin and
// corner 1 on the x axis, each next one across the shared edge, on the other
// side of it from the face before), it is isometric to the surface it
// covers, so a straight segment in the plane is a straight path on the
// surface. The shared edges are the portals a path through the strip
// crosses; the funnel algorithm (Lee & Preparata 1984) finds the shortest
// such path in a few flops a portal. Where that path bends, it bends round
// an end of a portal: a mesh vertex.
//
// Thread safety: pure functions of immutable data.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>

#include "absl/container/inlined_vector.h"
#include "core/geometry/planar_unfolding.h"
#include "core/geometry/vec2.h"
#include "core/mesh/mesh.h"
#include "core/query/internal/mesh_view.h"

namespace geodex::query {

// A face of a strip laid out in the plane: its mesh vertices and their
// positions, both in the face's corner order.
struct FlatFace {
  int32_t face;
  std::array<int32_t, 3> vertices;
  std::array<geometry::Vec2, 3> corners;

  // The corner at mesh vertex v; 0 when the face does not hold v.
  int CornerOf(int32_t v) const {
    return vertices[0] == v ? 0 : vertices[1] == v ? 1 : vertices[2] == v ? 2 : 0;
  }
  // The position of mesh vertex v; corner 0's when the face does not hold v.
  const geometry::Vec2& At(int32_t v) const { return corners[CornerOf(v)]; }
  // The corner that is neither i nor j (i != j).
  static int ThirdCorner(int i, int j) { return i != j ? 3 - i - j : (i + 1) % 3; }
  // The vertex of the face that is neither a nor b.
  int32_t Opposite(int32_t a, int32_t b) const {
    return vertices[ThirdCorner(CornerOf(a), CornerOf(b))];
  }
};

// Face f laid out counter-clockwise, as every face of the oriented mesh is:
// corner 0 at the origin, corner 1 on the positive x axis, corner 2 above
// it.
FlatFace LayOutFace(const MeshView& view, int32_t f);

// How UnfoldAcross measures the edge it crosses. The two are equal in real
// arithmetic and round differently: the chord walk measures the edge as the
// face before laid it out, the path straightener as the mesh has it, and
// each keeps its own so that its answers stay the same to the bit (as
// geometry::AlongEdge and AlongEdgeInv2l are both kept).
enum class EdgeMeasure {
  // The edge's length in the plane; its direction is the planar edge
  // divided by that length, and the side of the face before is read off
  // that unit direction.
  kInPlane,
  // The edge's length on the mesh; its direction is the planar edge times
  // the reciprocal of that length, and the side of the face before is read
  // off the planar edge itself.
  kOnMesh,
};

// Face g, which shares its edge (a, b) with `prev`, laid out across that
// edge: a and b where prev has them, g's third vertex on the other side of
// the edge from prev's, placed from its distances to a and b (in that
// order: geometry::Place measures from a).
FlatFace UnfoldAcross(const MeshView& view, const FlatFace& prev, int32_t g, int32_t a, int32_t b,
                      EdgeMeasure measure);

// Surface point p in the plane of `flat`, whose face holds every vertex p
// weighs more than `min_weight` (FaceHolds): the weighted sum of those
// vertices' positions; lighter weights count as 0.
geometry::Vec2 LocateInFlat(const MeshView& view, const FlatFace& flat, const mesh::SurfacePoint& p,
                            double min_weight);

// True when face f holds every vertex that p weighs more than 1e-12: f's
// closure holds p.
bool FaceHolds(const MeshView& view, int32_t f, const mesh::SurfacePoint& p);

// The angle of face f at its vertex v (radians).
double CornerAngle(const MeshView& view, int32_t f, int32_t v);

// The faces round vertex v strictly between faces `from` and `to` (which
// hold v), turning from `from` in direction `dir` (MeshView::Turn), in
// order into *between. False when the turn meets the boundary or comes
// back to `from` before it reaches `to`, or takes more than
// MeshView::kMaxFanSteps steps.
bool FacesBetween(const MeshView& view, int32_t v, int32_t from, int32_t to, int dir,
                  absl::InlinedVector<int32_t, 16>* between);

// An edge of the strip that a path through it crosses, its ends named as
// seen going through it (from the start towards the end).
struct Portal {
  static constexpr int kLeft = 0, kRight = 1;
  std::array<geometry::Vec2, 2> ends;  // [kLeft], [kRight]
  std::array<int32_t, 2> vertices;     // the mesh vertices there
};

// |end - start| when the segment from start to end passes through every
// portal (to within 1e-12 of its squared length); nullopt otherwise.
std::optional<double> StraightLength(const geometry::Vec2& start, std::span<const Portal> portals,
                                     const geometry::Vec2& end);

// A vertex of the shortest path through the portals, between its start and
// end: end `side` (Portal::kLeft or kRight) of portal `portal`.
struct FunnelBend {
  size_t portal;
  int side;
};

// The shortest path from start to end through the portals in order.
struct FunnelPath {
  double length = 0;
  absl::InlinedVector<FunnelBend, 8> bends;  // from start to end
};

// The funnel algorithm: the shortest path from `start` through `portals`
// to `end`, all in one plane. A portal end the path passes straight
// through may be a bend too (turning by 0).
FunnelPath Funnel(const geometry::Vec2& start, std::span<const Portal> portals,
                  const geometry::Vec2& end);

// Inline: on the path of every near pair.

inline FlatFace LayOutFace(const MeshView& view, int32_t f) {
  FlatFace flat{f, {view.Vertex(f, 0), view.Vertex(f, 1), view.Vertex(f, 2)}, {}};
  const mesh::Vec3 a = view.Position(flat.vertices[0]);
  const mesh::Vec3 e1 = view.Position(flat.vertices[1]) - a;
  const mesh::Vec3 e2 = view.Position(flat.vertices[2]) - a;
  const double l = e1.norm(), cx = e1.dot(e2) / l;
  flat.corners = {geometry::Vec2::Zero(), geometry::Vec2(l, 0),
                  geometry::Vec2(cx, std::sqrt(std::max(e2.squaredNorm() - cx * cx, 0.0)))};
  return flat;
}

inline FlatFace UnfoldAcross(const MeshView& view, const FlatFace& prev, int32_t g, int32_t a,
                             int32_t b, EdgeMeasure measure) {
  const int ia = prev.CornerOf(a), ib = prev.CornerOf(b);
  const geometry::Vec2 pa = prev.corners[ia], pb = prev.corners[ib];
  const geometry::Vec2 behind = prev.corners[FlatFace::ThirdCorner(ia, ib)];
  FlatFace flat{g, {view.Vertex(g, 0), view.Vertex(g, 1), view.Vertex(g, 2)}, {}};
  const int ja = flat.CornerOf(a), jb = flat.CornerOf(b), k = FlatFace::ThirdCorner(ja, jb);
  const mesh::Vec3 c = view.Position(flat.vertices[k]);
  double l;
  geometry::Vec2 ux;
  bool right;  // prev's third corner is left of a -> b, so g's goes right
  if (measure == EdgeMeasure::kInPlane) {
    l = (pb - pa).norm();
    ux = (pb - pa) / l;
    right = geometry::Cross(ux, behind - pa) > 0;
  } else {
    l = (view.Position(b) - view.Position(a)).norm();
    ux = (pb - pa) * (1 / l);
    right = geometry::Cross(pb - pa, behind - pa) > 0;
  }
  double x, y;
  geometry::Place(l, (c - view.Position(a)).norm(), (c - view.Position(b)).norm(), &x, &y);
  geometry::Vec2 uy(-ux.y(), ux.x());
  if (right) uy = -uy;
  flat.corners[ja] = pa;
  flat.corners[jb] = pb;
  flat.corners[k] = pa + x * ux + y * uy;
  return flat;
}

inline geometry::Vec2 LocateInFlat(const MeshView& view, const FlatFace& flat,
                                   const mesh::SurfacePoint& p, double min_weight) {
  geometry::Vec2 out = geometry::Vec2::Zero();
  for (int i = 0; i < 3; ++i) {
    if (p.w[i] > min_weight) out += p.w[i] * flat.At(view.Vertex(p.face, i));
  }
  return out;
}

}  // namespace geodex::query
