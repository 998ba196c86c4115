#include "core/query/engine/internal/paths/cut_bound.h"

#include <algorithm>
#include <cmath>

#include "absl/container/inlined_vector.h"
#include "core/query/engine/internal/paths/strip_funnel.h"

namespace geodex::query {

using mesh::Vec3;

double TwoChordLength(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b) {
  const Vec3 e = b - a;
  const double length = e.norm();
  if (!(length > 0)) return (p - a).norm() + (q - a).norm();
  const Vec3 u = e / length;
  // Each point's place along the edge's line and its distance from it: p
  // and q turned about the line into one plane, on either side of it.
  const Vec3 pa = p - a, qa = q - a;
  const double up = pa.dot(u), uq = qa.dot(u);
  const double rp = (pa - up * u).norm(), rq = (qa - uq * u).norm();
  // The sum is convex along the line: least where the segment between the
  // turned points crosses it, else at the nearer end.
  double t = rp + rq > 0 ? up + (uq - up) * (rp / (rp + rq)) : up;
  t = std::clamp(t, 0.0, length);
  return std::sqrt((t - up) * (t - up) + rp * rp) + std::sqrt((t - uq) * (t - uq) + rq * rq);
}

namespace {

// The faces that hold p (one for an interior point; those round its edge or
// vertex otherwise).
absl::InlinedVector<int32_t, 16> FacesHolding(const MeshView& view, const SurfacePoint& p) {
  absl::InlinedVector<int32_t, 16> holding = {p.face};
  if (p.w[0] > 1e-12 && p.w[1] > 1e-12 && p.w[2] > 1e-12) return holding;
  absl::InlinedVector<int32_t, 16> around;
  for (int i = 0; i < 3; ++i) {
    if (!(p.w[i] > 1e-12)) continue;
    view.FacesAround(view.Vertex(p.face, i), p.face, &around);
    for (const int32_t g : around) {
      if (FaceHolds(view, g, p) &&
          std::find(holding.begin(), holding.end(), g) == holding.end()) {
        holding.push_back(g);
      }
    }
  }
  return holding;
}

}  // namespace

double CutLowerBound(const MeshView& view, const SurfacePoint& p, const SurfacePoint& q,
                     double reach, int max_faces, WalkScratch* scratch) {
  const Vec3 xp = view.PositionOf(p), xq = view.PositionOf(q);
  const double chord = (xp - xq).norm();
  std::vector<uint32_t>& marks = scratch->region_marks;
  marks.resize(view.faces.size() / 3, 0);
  if (++scratch->region_mark == 0) {  // the marks wrapped round: start again
    std::fill(marks.begin(), marks.end(), 0);
    scratch->region_mark = 1;
  }
  const uint32_t mark = scratch->region_mark;
  std::vector<int32_t>& region = scratch->region;
  region.clear();
  for (const int32_t f : FacesHolding(view, p)) {
    if (FaceHolds(view, f, q)) return chord;  // one face holds both: the chord is the geodesic
    marks[f] = mark;
    region.push_back(f);
  }
  auto joins = [&](int32_t g) {
    const Vec3 c = (view.Position(view.Vertex(g, 0)) + view.Position(view.Vertex(g, 1)) +
                    view.Position(view.Vertex(g, 2))) /
                   3;
    const double to_p = (c - xp).norm(), to_q = (c - xq).norm();
    return to_p < to_q && to_p + to_q <= reach && !FaceHolds(view, g, q);
  };
  double bound = std::numeric_limits<double>::infinity();
  for (size_t next = 0; next < region.size(); ++next) {
    const int32_t f = region[next];
    for (int k = 0; k < 3; ++k) {
      const int32_t twin = view.twins[3 * f + k];
      if (twin < 0) continue;  // the surface's boundary: no path crosses it
      const int32_t g = twin / 3;
      if (marks[g] == mark) continue;
      if (joins(g)) {
        if (static_cast<int>(region.size()) >= max_faces) return chord;
        marks[g] = mark;
        region.push_back(g);
        continue;
      }
      bound = std::min(bound, TwoChordLength(xp, xq, view.Position(view.Vertex(f, k)),
                                             view.Position(view.Vertex(f, (k + 1) % 3))));
    }
  }
  // A region without a border to cross (q unreachable from p) bounds
  // nothing beyond the chord the caller already had.
  return std::isfinite(bound) ? std::max(bound, chord) : chord;
}

}  // namespace geodex::query
