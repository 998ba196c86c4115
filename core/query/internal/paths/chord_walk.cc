#include "core/query/internal/paths/chord_walk.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "absl/container/inlined_vector.h"
#include "core/geometry/planar_unfolding.h"
#include "core/geometry/vec2.h"
#include "core/query/internal/paths/path_straightening.h"
#include "core/query/internal/paths/strip_funnel.h"

namespace geodex::query {
namespace {

using geometry::Cross;
using geometry::Vec2;
using mesh::Vec3;

// The barycentric velocity (sum 0) of moving along `dir` in face f.
std::array<double, 3> Velocity(const MeshView& view, int32_t f, const Vec3& dir) {
  const Vec3 v[3] = {view.Position(view.Vertex(f, 0)), view.Position(view.Vertex(f, 1)),
                     view.Position(view.Vertex(f, 2))};
  const Vec3 n = (v[1] - v[0]).cross(v[2] - v[0]);
  // One division, not three: a walk's step waits on each (the velocity
  // only chooses the edge the walk leaves by; the path's length is measured
  // in the corridor's layout).
  const double inverse_area2 = 1 / n.squaredNorm();
  std::array<double, 3> beta;
  for (int i = 0; i < 3; ++i) {
    beta[i] = n.cross(v[(i + 2) % 3] - v[(i + 1) % 3]).dot(dir) * inverse_area2;
  }
  return beta;
}

// Direction `d`, in the plane of the face across edge (a, b) from face f,
// turned about that edge into f's plane: a straight line across the edge
// in the unfolding of the two faces.
Vec3 UnfoldHeading(const MeshView& view, int32_t f, const std::array<int32_t, 2>& edge,
                   const Vec3& d) {
  const Vec3 a = view.Position(edge[0]);
  const Vec3 e = (view.Position(edge[1]) - a).normalized();
  Vec3 into = Vec3::Zero();  // in f's plane, perpendicular to the edge, into f
  for (int i = 0; i < 3; ++i) {
    const int32_t c = view.Vertex(f, i);
    if (c != edge[0] && c != edge[1]) {
      into = view.Position(c) - a;
      into -= into.dot(e) * e;
    }
  }
  const double along = d.dot(e);
  return along * e + (d - along * e).norm() * into.normalized();
}

// A corridor of faces (consecutive ones share an edge) unfolded into one
// plane (strip_funnel.h), with the points it runs between, in a walk
// scratch's arrays. The shortest path through it is found by the funnel
// algorithm on the unfolded edges it crosses (portals), in a few flops a
// face; where that path bends round a vertex short of a straight angle on
// the vertex's other side, the corridor is moved to that side (Release),
// and only the faces after the bend are laid out again.
class Corridor {
 public:
  // Where the funnel's path bends: the vertex, the run of portals
  // [first, last] that end at it on the side it is on, and the angle the
  // path turns by.
  struct Bend {
    int32_t vertex;
    size_t first, last;
    double turn;
  };
  using Bends = absl::InlinedVector<Bend, 8>;

  explicit Corridor(QueryScratch::Walks& scratch)
      : faces_(scratch.faces), flat_(scratch.flat), portals_(scratch.portals) {}

  std::vector<int32_t>& faces() { return faces_; }

  // Lays out faces() from `from` (a point faces()[0] holds) to `to` (one the
  // last face holds), keeping the layouts of the faces before `first` (laid
  // out by the last call, and unchanged since). The layouts are those of
  // UnfoldStrip, to the bit: each face is placed across the edge it shares
  // with the one before, as laid out. False when consecutive faces share no
  // edge.
  bool Unfold(const MeshView& view, const SurfacePoint& from, const SurfacePoint& to,
              size_t first = 0) {
    const size_t n = faces_.size();
    flat_.resize(n);
    portals_.resize(n - 1);
    if (first == 0) {
      flat_[0] = LayOutFace(view, faces_[0]);
      start_ = LocateInFlat(view, flat_[0], from, 0);
      first = 1;
    }
    for (size_t t = first; t < n; ++t) {
      const int32_t f = faces_[t - 1];
      int edge = -1;
      for (int i = 0; i < 3; ++i) {
        const int32_t h = view.twins[3 * f + i];
        if (h >= 0 && h / 3 == faces_[t]) edge = i;
      }
      if (edge < 0) return false;
      // The half-edge runs from corner `edge` to the next, with f on its
      // left: going out of f, its end is on the left.
      const int left = (edge + 1) % 3;
      const int32_t a = view.Vertex(f, left), b = view.Vertex(f, edge);
      const FlatFace& prev = flat_[t - 1];
      portals_[t - 1] = {{prev.corners[left], prev.corners[edge]}, {a, b}};
      flat_[t] = UnfoldAcross(view, prev, faces_[t], a, b);
    }
    end_ = LocateInFlat(view, flat_[n - 1], to, 0);
    return true;
  }

  // |end - start| when that segment passes through every portal.
  std::optional<double> StraightLength() const {
    return query::StraightLength(start_, portals_, end_);
  }

  // The length of the shortest path through the corridor (the funnel
  // algorithm, Lee & Preparata 1984) and where it bends.
  double Shortest(Bends* bends) const {
    const FunnelPath path = query::Funnel(start_, portals_, end_);
    const size_t n = portals_.size(), count = path.bends.size();
    // The path's k-th vertex: the start, the bends, the end.
    auto point = [&](size_t k) -> const Vec2& {
      if (k == 0) return start_;
      if (k > count) return end_;
      const FunnelBend& bend = path.bends[k - 1];
      return portals_[bend.portal].ends[bend.side];
    };
    bends->clear();
    for (size_t k = 0; k < count; ++k) {
      const auto [at, side] = path.bends[k];
      const int32_t v = portals_[at].vertices[side];
      size_t first = at, last = at;
      while (first > 0 && portals_[first - 1].vertices[side] == v) --first;
      while (last + 1 < n && portals_[last + 1].vertices[side] == v) ++last;
      const Vec2 d = point(k + 1) - point(k), e = point(k + 2) - point(k + 1);
      bends->push_back({v, first, last, std::atan2(std::abs(Cross(d, e)), d.dot(e))});
    }
    return path.length;
  }

  // Moves the corridor to the other side of the bend's vertex: the faces
  // holding it between the bend's portals are replaced by those round the
  // vertex the other way. False at the boundary. The faces from
  // bend.first + 1 on must be laid out again (Unfold(..., bend.first + 1)).
  bool Release(const MeshView& view, const Bend& bend) {
    const int32_t v = bend.vertex;
    const int32_t from = faces_[bend.first], to = faces_[bend.last + 1];
    const int32_t skip = faces_[bend.first + 1];
    const int dir = view.Turn(from, v, 0) == skip ? 1 : 0;
    absl::InlinedVector<int32_t, 16> round;
    if (!FacesBetween(view, v, from, to, dir, &round)) return false;
    faces_.erase(faces_.begin() + bend.first + 1, faces_.begin() + bend.last + 1);
    faces_.insert(faces_.begin() + bend.first + 1, round.begin(), round.end());
    return true;
  }

 private:
  std::vector<int32_t>& faces_;
  std::vector<FlatFace>& flat_;
  std::vector<Portal>& portals_;
  Vec2 start_ = Vec2::Zero(), end_ = Vec2::Zero();
};

// A corridor from `from` to `to` found without the distance field: from
// face to face, each step heading for `to` along the chord projected into
// the face (past a ridge, where that points back, straight on across the
// edge), until a face holds `to`. The faces go to *faces. False when the
// walk reaches a vertex, the boundary or a dead end, crosses more than
// `max_steps` faces or walks more than twice the chord; then the caller
// traces instead.
bool WalkCorridor(const MeshView& view, const PathPoint& from, const PathPoint& to, int max_steps,
                  std::vector<int32_t>* faces) {
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
      faces->assign({g});
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
  faces->assign({f});
  Vec3 x = from.position;
  // A walk that wanders (round a feature, or circling `to`) gives up early.
  const double max_length = 2 * (to.position - from.position).norm();
  double length = 0;
  Vec3 heading = Vec3::Zero();  // the last step, and the edge it crossed
  std::array<int32_t, 2> heading_edge = {-1, -1};
  for (int step = 0; step < max_steps && length <= max_length; ++step) {
    if (FaceHolds(view, f, to.point)) return true;
    std::array<double, 3> beta = Velocity(view, f, to.position - x);
    double t;
    int exit = DescentExit(beta, w, &t);
    if ((exit < 0 || !(t > 1e-14)) && heading.squaredNorm() > 0) {
      // Past a ridge the chord points back: go on straight, the heading of
      // the face before unfolded into this one.
      beta = Velocity(view, f, UnfoldHeading(view, f, heading_edge, heading));
      exit = DescentExit(beta, w, &t);
    }
    if (exit < 0 || !(t > 1e-14)) return false;
    for (int i = 0; i < 3; ++i) w[i] = std::max(w[i] + t * beta[i], 0.0);
    w[exit] = 0;
    const double inverse_sum = 1 / (w[0] + w[1] + w[2]);
    for (double& c : w) c *= inverse_sum;
    if (w[0] > 1 - 1e-9 || w[1] > 1 - 1e-9 || w[2] > 1 - 1e-9) return false;
    const Vec3 last = x;
    x = w[0] * view.Position(view.Vertex(f, 0)) + w[1] * view.Position(view.Vertex(f, 1)) +
        w[2] * view.Position(view.Vertex(f, 2));
    length += (x - last).norm();
    const int32_t g = view.twins[3 * f + (exit + 1) % 3];  // the edge opposite `exit`
    if (g < 0) return false;
    heading = x - last;
    heading_edge = {view.Vertex(f, (exit + 1) % 3), view.Vertex(f, (exit + 2) % 3)};
    f = g / 3;
    faces->push_back(f);
    // The next step reads a neighbour's corners and twins: a random pair's
    // corridor is seldom in cache, so both lines of each neighbour are
    // fetched while this step's arithmetic runs.
    for (int k = 0; k < 3; ++k) {
      const int32_t next = view.twins[3 * f + k];
      if (next < 0) continue;
      __builtin_prefetch(&view.faces[next - next % 3]);
      __builtin_prefetch(&view.twins[next - next % 3]);
    }
    w = AcrossEdge(g, exit, w);
  }
  return false;
}

// A path through a vertex is locally shortest when the surface angle on
// either side of it is at least pi (Mitchell, Mount & Papadimitriou 1987),
// so when it turns by at most the vertex's angle excess (sum - 2 pi), to
// rounding.
constexpr double kBendSlack = 1e-9;

// The sum of the angles at vertex v of the faces round it (`face` is one);
// nullopt at the boundary.
std::optional<double> AngleSum(const MeshView& view, int32_t face, int32_t v) {
  double total = 0;
  int32_t g = face;
  for (int step = 0; step < MeshView::kMaxFanSteps; ++step) {
    total += CornerAngle(view, g, v);
    g = view.Turn(g, v, 0);
    if (g < 0) return std::nullopt;
    if (g == face) return total;
  }
  return std::nullopt;
}

}  // namespace

NearWalk WalkNearPair(const MeshView& view, const SurfacePoint& from, const SurfacePoint& to,
                      double plausible, QueryScratch* scratch) {
  QueryScratch own;
  QueryScratch& s = scratch != nullptr ? *scratch : own;
  QueryScratch::Walks& walks = s.walks();
  NearPairStats& count = s.near_pair_stats();
  // First the corridors of the chord, from either end, unfolded into the
  // plane. A straight segment through the corridor is a local geodesic, as
  // the straightened trace would be, found without evaluating the distance
  // field, so at a fraction of the trace's cost. Else the funnel's path
  // through it, released from the vertices it bends round short of a
  // straight angle on their other side: one that then bends at no vertex,
  // or at one saddle by no more than its angle excess, is a local geodesic
  // too. Paths bending at several saddles were often in a wrong corridor,
  // and so, rarely, is a straight one longer than `plausible` (across a
  // sharp feature); then the caller decides (NearPathLength: the trace; the
  // refinement: an exact propagation round the pair). Every candidate is a surface
  // path, so the shortest is kept (figures: tests/bench/throughput.md).
  constexpr int kMaxWalkSteps = 256;
  // A release shortens the path; a near path passes few vertices.
  constexpr int kMaxReleases = 8;
  const PathPoint ends[2] = {{from, view.PositionOf(from)}, {to, view.PositionOf(to)}};
  std::optional<double> doubted;
  Corridor corridor(walks);
  // The corridor returned lives in the scratch: none when the scratch is
  // this call's own.
  const auto in_scratch = [&](std::span<const int32_t> faces) {
    return scratch != nullptr ? faces : std::span<const int32_t>();
  };
  // The corridors of `doubted` and `found`, in walks.doubted_faces and
  // walks.found_faces.
  auto doubt = [&](double length) {
    if (doubted && *doubted <= length) return;
    doubted = length;
    walks.doubted_faces.assign(corridor.faces().begin(), corridor.faces().end());
  };
  std::optional<NearPath> found;
  Corridor::Bends bends;
  for (int start = 0; start < 2; ++start) {
    const SurfacePoint& a = ends[start].point;
    const SurfacePoint& b = ends[1 - start].point;
    if (!WalkCorridor(view, ends[start], ends[1 - start], kMaxWalkSteps, &corridor.faces()) ||
        !corridor.Unfold(view, a, b)) {
      continue;
    }
    ++count.walks;
    count.faces_crossed += static_cast<int64_t>(corridor.faces().size());
    count.faces_unfolded += static_cast<int64_t>(corridor.faces().size());
    if (const std::optional<double> length = corridor.StraightLength()) {
      if (*length <= plausible) return {NearPath{*length, false}, std::nullopt, in_scratch(corridor.faces())};
      doubt(*length);
      continue;
    }
    for (int release = 0; release <= kMaxReleases; ++release) {
      const double length = corridor.Shortest(&bends);
      const Corridor::Bend* shortcut = nullptr;
      bool judged = true;
      for (const Corridor::Bend& bend : bends) {
        const std::optional<double> angle =
            AngleSum(view, corridor.faces()[bend.first], bend.vertex);
        if (!angle) {
          judged = false;  // a boundary vertex
          break;
        }
        if (bend.turn > *angle - 2 * M_PI + kBendSlack) {
          shortcut = &bend;
          break;
        }
      }
      if (!judged) break;
      if (shortcut == nullptr) {
        if (length <= plausible && bends.size() <= 1) {
          // Straight in the walk's own corridor: as sure as a straight walk.
          if (release == 0 && bends.empty()) {
            return {NearPath{length, false}, std::nullopt, in_scratch(corridor.faces())};
          }
          // Else a local geodesic in a corridor the walk did not find by
          // itself: kept, but the other walk may find a shorter one.
          if (!found || length < found->length) {
            found = NearPath{length, !bends.empty()};
            walks.found_faces.assign(corridor.faces().begin(), corridor.faces().end());
          }
        } else {
          doubt(length);
        }
        break;
      }
      ++count.releases;
      if (!corridor.Release(view, *shortcut)) break;
      const size_t changed = shortcut->first + 1;
      if (!corridor.Unfold(view, a, b, changed)) break;
      count.faces_unfolded += static_cast<int64_t>(corridor.faces().size() - changed);
    }
  }
  // Every candidate is a surface path: the shortest is the closest.
  if (found) {
    if (doubted && *doubted < found->length) {
      return {NearPath{*doubted, true}, std::nullopt, in_scratch(walks.doubted_faces)};
    }
    return {found, std::nullopt, in_scratch(walks.found_faces)};
  }
  if (doubted) return {std::nullopt, doubted, in_scratch(walks.doubted_faces)};
  return {};
}

std::optional<NearPath> NearPathLength(const MeshView& view, const GradientPaths& paths,
                                       const SurfacePoint& from, const SurfacePoint& to,
                                       bool walk_chord, double plausible) {
  std::optional<double> doubted;
  if (walk_chord) {
    const NearWalk walk = WalkNearPair(view, from, to, plausible);
    if (walk.path) return walk.path;
    doubted = walk.doubted;
  }
  // Without Path's restarts, which double the cost of a near pair for a
  // small gain (tests/bench/throughput.md).
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
