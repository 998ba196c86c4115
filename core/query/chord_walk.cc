#include "core/query/chord_walk.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "absl/container/inlined_vector.h"
#include "core/query/path_straightening.h"

namespace geodex::query {
namespace {

using mesh::Vec3;

// The barycentric velocity (sum 0) of moving along `dir` in face f.
std::array<double, 3> Velocity(const MeshView& view, int32_t f, const Vec3& dir) {
  const Vec3 v[3] = {view.Position(view.Vertex(f, 0)), view.Position(view.Vertex(f, 1)),
                     view.Position(view.Vertex(f, 2))};
  const Vec3 n = (v[1] - v[0]).cross(v[2] - v[0]);
  const double area2 = n.squaredNorm();
  std::array<double, 3> beta;
  for (int i = 0; i < 3; ++i) beta[i] = n.cross(v[(i + 2) % 3] - v[(i + 1) % 3]).dot(dir) / area2;
  return beta;
}

// True when every vertex `p` has weight on (weight > 1e-12) is a vertex of f.
bool FaceHolds(const MeshView& view, int32_t f, const SurfacePoint& p) {
  for (int i = 0; i < 3; ++i) {
    if (p.w[i] > 1e-12 && view.Corner(f, view.Vertex(p.face, i)) < 0) return false;
  }
  return true;
}

// A corridor from `from` to `to` found without the distance field: from
// face to face, each step heading for `to` along the chord projected into
// the face, until a face holds `to`. The crossings, with the ends, go to
// *path (consecutive points share a face, as StraightenPath needs). False
// when the walk reaches a vertex, the boundary or a dead end (the projected
// chord points back, past a ridge), crosses more than `max_steps` faces or
// walks more than twice the chord; then the caller traces instead.
bool WalkCorridor(const MeshView& view, const PathPoint& from, const PathPoint& to, int max_steps,
                  std::vector<PathPoint>* path) {
  path->assign({from});
  // The face to start in: from's face, or, for a vertex or edge point, the
  // face round it that the chord enters.
  absl::InlinedVector<int32_t, 16> starts;
  int positive = 0, heaviest = 0;
  for (int i = 0; i < 3; ++i) {
    positive += from.point.w[i] > 1e-12;
    if (from.point.w[i] > from.point.w[heaviest]) heaviest = i;
  }
  if (positive == 3) {
    starts.push_back(from.point.face);
  } else {
    view.FacesAround(view.Vertex(from.point.face, heaviest), from.point.face, &starts);
  }
  int32_t f = -1;
  std::array<double, 3> w;
  for (int32_t g : starts) {
    if (!FaceHolds(view, g, from.point)) continue;
    std::array<double, 3> b = {0, 0, 0};
    for (int i = 0; i < 3; ++i) {
      const int c = view.Corner(g, view.Vertex(from.point.face, i));
      if (c >= 0) b[c] = from.point.w[i];  // FaceHolds: the others weigh ~0
    }
    if (FaceHolds(view, g, to.point)) {
      path->push_back(to);
      return true;
    }
    const std::array<double, 3> beta = Velocity(view, g, to.position - from.position);
    const double eps = 1e-12 * (std::abs(beta[0]) + std::abs(beta[1]) + std::abs(beta[2]));
    bool enters = eps > 0;
    for (int i = 0; i < 3; ++i) enters = enters && (b[i] > 1e-12 || beta[i] > eps);
    if (enters) {
      f = g;
      w = b;
      break;
    }
  }
  if (f < 0) return false;
  Vec3 x = from.position;
  // A walk that wanders (round a feature, or circling `to`) gives up early.
  const double max_length = 2 * (to.position - from.position).norm();
  double length = 0;
  for (int step = 0; step < max_steps && length <= max_length; ++step) {
    if (FaceHolds(view, f, to.point)) {
      path->push_back(to);
      return true;
    }
    const std::array<double, 3> beta = Velocity(view, f, to.position - x);
    double t;
    const int exit = DescentExit(beta, w, &t);
    if (exit < 0 || !(t > 1e-14)) return false;
    for (int i = 0; i < 3; ++i) w[i] = std::max(w[i] + t * beta[i], 0.0);
    w[exit] = 0;
    const double sum = w[0] + w[1] + w[2];
    for (double& c : w) c /= sum;
    if (w[0] > 1 - 1e-9 || w[1] > 1 - 1e-9 || w[2] > 1 - 1e-9) return false;
    const Vec3 last = x;
    x = w[0] * view.Position(view.Vertex(f, 0)) + w[1] * view.Position(view.Vertex(f, 1)) +
        w[2] * view.Position(view.Vertex(f, 2));
    length += (x - last).norm();
    path->push_back({SurfacePoint{f, w}, x});
    const int32_t g = view.twins[3 * f + (exit + 1) % 3];  // the edge opposite `exit`
    if (g < 0) return false;
    f = g / 3;
    w = AcrossEdge(g, exit, w);
  }
  return false;
}

}  // namespace

std::optional<NearPath> NearPathLength(const MeshView& view, const GradientPaths& paths,
                                       const SurfacePoint& from, const SurfacePoint& to,
                                       bool walk_chord, double plausible) {
  // First the corridors of the chord, from either end. A straightened walk
  // that wraps round no vertex is a straight line through the faces it
  // crosses, a local geodesic, as the straightened trace would be, found
  // without evaluating the distance field, so at a fraction of the trace's
  // cost. Walks that wrap are often in a wrong corridor, and so, rarely, is
  // a straight one longer than `plausible` (across a sharp feature); then
  // the trace decides. Every candidate is a surface path, so the shortest is
  // kept (figures: tests/bench/README.md).
  constexpr int kMaxWalkSteps = 256;
  const PathPoint ends[2] = {{from, view.PositionOf(from)}, {to, view.PositionOf(to)}};
  std::optional<double> doubted;
  std::vector<PathPoint> walk;
  for (int start = 0; start < (walk_chord ? 2 : 0); ++start) {
    if (!WalkCorridor(view, ends[start], ends[1 - start], kMaxWalkSteps, &walk)) continue;
    std::optional<double> length = StraightLength(view, walk);
    bool wraps = false;
    if (!length) {
      walk = StraightenPath(view, std::move(walk));
      length = PathLength(walk);
      wraps = WrapsRoundAVertex(walk);
    }
    if (!wraps && *length <= plausible) return NearPath{*length, false};
    doubted = std::min(*length, doubted.value_or(*length));
  }
  // Without Path's restarts, which double the cost of a near pair for a
  // small gain (tests/bench/README.md).
  const absl::StatusOr<std::vector<PathPoint>> path =
      paths.Shortest(from, to, GradientPaths::Search::kNearPair);
  if (path.ok()) {
    const double length = PathLength(*path);
    if (!doubted || length <= *doubted) return NearPath{length, WrapsRoundAVertex(*path)};
  }
  if (doubted) return NearPath{*doubted, true};
  return std::nullopt;
}

}  // namespace geodex::query
