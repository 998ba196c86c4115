#include "core/query/strip_funnel.h"

#include <algorithm>
#include <cmath>

#include "core/geometry/unfolding.h"

namespace geodex::query {

using geometry::Cross;
using geometry::Vec2;
using mesh::Vec3;

FlatFace LayOutFace(const MeshView& view, int32_t f) {
  FlatFace flat{f, {view.Vertex(f, 0), view.Vertex(f, 1), view.Vertex(f, 2)}, {}};
  const Vec3 a = view.Position(flat.vertices[0]);
  const Vec3 e1 = view.Position(flat.vertices[1]) - a;
  const Vec3 e2 = view.Position(flat.vertices[2]) - a;
  const double l = e1.norm(), cx = e1.dot(e2) / l;
  flat.corners = {Vec2::Zero(), Vec2(l, 0),
                  Vec2(cx, std::sqrt(std::max(e2.squaredNorm() - cx * cx, 0.0)))};
  return flat;
}

FlatFace UnfoldAcross(const MeshView& view, const FlatFace& prev, int32_t g, int32_t a, int32_t b,
                      EdgeMeasure measure) {
  FlatFace flat{g, {view.Vertex(g, 0), view.Vertex(g, 1), view.Vertex(g, 2)}, {}};
  const Vec2 pa = prev.At(a), pb = prev.At(b);
  const Vec2 behind = prev.At(prev.Opposite(a, b));
  const Vec3 c = view.Position(flat.Opposite(a, b));
  double l;
  Vec2 ux;
  bool right;  // prev's third corner is left of a -> b, so g's goes right
  if (measure == EdgeMeasure::kInPlane) {
    l = (pb - pa).norm();
    ux = (pb - pa) / l;
    right = Cross(ux, behind - pa) > 0;
  } else {
    l = (view.Position(b) - view.Position(a)).norm();
    ux = (pb - pa) * (1 / l);
    right = Cross(pb - pa, behind - pa) > 0;
  }
  double x, y;
  geometry::Place(l, (c - view.Position(a)).norm(), (c - view.Position(b)).norm(), &x, &y);
  Vec2 uy(-ux.y(), ux.x());
  if (right) uy = -uy;
  const Vec2 pc = pa + x * ux + y * uy;
  for (int i = 0; i < 3; ++i) {
    flat.corners[i] = flat.vertices[i] == a ? pa : flat.vertices[i] == b ? pb : pc;
  }
  return flat;
}

Vec2 LocateInFlat(const MeshView& view, const FlatFace& flat, const mesh::SurfacePoint& p,
                  double min_weight) {
  Vec2 out = Vec2::Zero();
  for (int i = 0; i < 3; ++i) {
    if (p.w[i] > min_weight) out += p.w[i] * flat.At(view.Vertex(p.face, i));
  }
  return out;
}

bool FaceHolds(const MeshView& view, int32_t f, const mesh::SurfacePoint& p) {
  for (int i = 0; i < 3; ++i) {
    if (p.w[i] > 1e-12 && view.Corner(f, view.Vertex(p.face, i)) < 0) return false;
  }
  return true;
}

double CornerAngle(const MeshView& view, int32_t f, int32_t v) {
  const int k = view.Corner(f, v);
  const Vec3 o = view.Position(v);
  const Vec3 a = view.Position(view.Vertex(f, (k + 1) % 3)) - o;
  const Vec3 b = view.Position(view.Vertex(f, (k + 2) % 3)) - o;
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

bool FacesBetween(const MeshView& view, int32_t v, int32_t from, int32_t to, int dir,
                  absl::InlinedVector<int32_t, 16>* between) {
  between->clear();
  int32_t g = from;
  for (int step = 0; step < MeshView::kMaxFanSteps; ++step) {
    g = view.Turn(g, v, dir);
    if (g < 0 || g == from) return false;
    if (g == to) return true;
    between->push_back(g);
  }
  return false;
}

std::optional<double> StraightLength(const Vec2& start, std::span<const Portal> portals,
                                     const Vec2& end) {
  const Vec2 d = end - start;
  const double slack = 1e-12 * d.squaredNorm();
  for (const Portal& portal : portals) {
    const double sl = Cross(d, portal.ends[Portal::kLeft] - start);
    const double sr = Cross(d, portal.ends[Portal::kRight] - start);
    if (std::min(sl, sr) > slack || std::max(sl, sr) < -slack) return std::nullopt;
  }
  return d.norm();
}

FunnelPath Funnel(const Vec2& start, std::span<const Portal> portals, const Vec2& end) {
  const size_t n = portals.size();
  // The end point closes the sequence as a portal of zero width (index n).
  auto end_of = [&](size_t i, int side) -> const Vec2& {
    return i < n ? portals[i].ends[side] : end;
  };
  FunnelPath path;
  Vec2 apex = start, side_at[2] = {end_of(0, Portal::kLeft), end_of(0, Portal::kRight)};
  size_t index[2] = {0, 0};
  for (size_t i = 1; i <= n; ++i) {
    // The right side narrows when the new end is left of the apex's ray to
    // it, the left side when it is right; crossing the other side's ray,
    // the path bends round that side's end and the funnel starts again
    // there.
    for (int side : {Portal::kRight, Portal::kLeft}) {
      const double sign = side == Portal::kRight ? 1 : -1;
      const Vec2& next = end_of(i, side);
      if (sign * Cross(side_at[side] - apex, next - apex) < 0) continue;  // widens
      const int other = 1 - side;
      if (apex == side_at[side] || sign * Cross(side_at[other] - apex, next - apex) < 0) {
        side_at[side] = next;
        index[side] = i;
        continue;
      }
      const size_t at = index[other];
      if (at == n) break;  // the other side's end is the end point
      apex = side_at[other];
      path.bends.push_back({at, other});
      side_at[0] = side_at[1] = apex;
      index[0] = index[1] = i = at;
      break;
    }
  }
  const Vec2* from = &start;
  for (const FunnelBend& bend : path.bends) {
    const Vec2& to = portals[bend.portal].ends[bend.side];
    path.length += (to - *from).norm();
    from = &to;
  }
  path.length += (end - *from).norm();
  return path;
}

}  // namespace geodex::query
