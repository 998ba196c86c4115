#include "core/query/engine/internal/paths/strip_funnel.h"

#include <algorithm>
#include <cmath>

#include "core/geometry/planar_unfolding.h"

namespace geodex::query {

using geometry::Cross;
using geometry::Vec2;
using mesh::Vec3;

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

bool UnfoldStrip(const MeshView& view, std::span<const int32_t> faces,
                 const mesh::SurfacePoint& from, const mesh::SurfacePoint& to, double min_weight,
                 UnfoldedStrip* out) {
  out->portals.clear();
  FlatFace flat = LayOutFace(view, faces[0]);
  out->start = LocateInFlat(view, flat, from, min_weight);
  for (size_t t = 0; t + 1 < faces.size(); ++t) {
    Portal portal;
    if (!StepAcross(view, flat, faces[t + 1], &portal, &flat)) return false;
    out->portals.push_back(portal);
  }
  out->end = LocateInFlat(view, flat, to, min_weight);
  return true;
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
