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
#include "core/geometry/face_frame.h"
#include "core/geometry/planar_unfolding.h"
#include "core/geometry/vec2.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/mesh_view.h"

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

// Face g, which shares its edge (a, b) with `prev`, laid out across that
// edge: a and b where prev has them, g's third vertex on the other side of
// the edge from prev's, placed from its distances to a and b (in that
// order: geometry::Place measures from a). The edge is measured as prev
// laid it out, so that the three corners agree with each other in the
// plane.
FlatFace UnfoldAcross(const MeshView& view, const FlatFace& prev, int32_t g, int32_t a, int32_t b);

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

// A strip laid out in the plane: where its end points fall and the portals
// between its faces.
struct UnfoldedStrip {
  geometry::Vec2 start = geometry::Vec2::Zero(), end = geometry::Vec2::Zero();
  // portals[t] is the edge faces[t] and faces[t + 1] share, its ends named
  // as seen going out of faces[t].
  absl::InlinedVector<Portal, 32> portals;
};

// One step of a strip, written once for every strip loop (UnfoldStrip, the
// chord walk's corridor): face `next`, which shares an edge with prev's
// face, laid out across that edge (UnfoldAcross) into *out, and the edge as
// the portal a path crosses going out of prev into *portal. False when the
// faces share no edge.
bool StepAcross(const MeshView& view, const FlatFace& prev, int32_t next, Portal* portal,
                FlatFace* out);

// The strip loop: lays out faces[0] (LayOutFace) and each next face across
// the edge it shares with the one before (StepAcross), and places `from` (a
// point faces[0] holds) and `to` (one the last face holds) with
// LocateInFlat(min_weight). False when two consecutive faces share no edge.
bool UnfoldStrip(const MeshView& view, std::span<const int32_t> faces,
                 const mesh::SurfacePoint& from, const mesh::SurfacePoint& to, double min_weight,
                 UnfoldedStrip* out);

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
  const geometry::FaceFrame frame =
      geometry::FrameOfTriangle(view.Position(flat.vertices[0]), view.Position(flat.vertices[1]),
                                view.Position(flat.vertices[2]));
  flat.corners = {geometry::Vec2::Zero(), geometry::Vec2(frame.length, 0),
                  geometry::Vec2(frame.cx, frame.cy)};
  return flat;
}

inline FlatFace UnfoldAcross(const MeshView& view, const FlatFace& prev, int32_t g, int32_t a,
                             int32_t b) {
  const int ia = prev.CornerOf(a), ib = prev.CornerOf(b);
  const geometry::Vec2 pa = prev.corners[ia], pb = prev.corners[ib];
  const geometry::Vec2 behind = prev.corners[FlatFace::ThirdCorner(ia, ib)];
  FlatFace flat{g, {view.Vertex(g, 0), view.Vertex(g, 1), view.Vertex(g, 2)}, {}};
  const int ja = flat.CornerOf(a), jb = flat.CornerOf(b), k = FlatFace::ThirdCorner(ja, jb);
  const mesh::Vec3 c = view.Position(flat.vertices[k]);
  const double l = (pb - pa).norm();
  const geometry::Vec2 ux = (pb - pa) / l;
  // prev's third corner is left of a -> b, so g's goes right.
  const bool right = geometry::Cross(ux, behind - pa) > 0;
  double x, y;
  geometry::Place(l, (c - view.Position(a)).norm(), (c - view.Position(b)).norm(), &x, &y);
  geometry::Vec2 uy(-ux.y(), ux.x());
  if (right) uy = -uy;
  flat.corners[ja] = pa;
  flat.corners[jb] = pb;
  flat.corners[k] = pa + x * ux + y * uy;
  return flat;
}

inline bool StepAcross(const MeshView& view, const FlatFace& prev, int32_t next, Portal* portal,
                       FlatFace* out) {
  const int32_t f = prev.face;
  int edge = -1;
  for (int i = 0; i < 3; ++i) {
    const int32_t h = view.twins[3 * f + i];
    if (h >= 0 && h / 3 == next) edge = i;
  }
  if (edge < 0) return false;
  // The half-edge runs from corner `edge` to the next, with f on its left:
  // going out of f, its end is on the left. prev's corners are in f's
  // corner order (LayOutFace, UnfoldAcross).
  const int left = (edge + 1) % 3;
  const int32_t a = view.Vertex(f, left), b = view.Vertex(f, edge);
  *portal = {{prev.corners[left], prev.corners[edge]}, {a, b}};
  *out = UnfoldAcross(view, prev, next, a, b);
  return true;
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
