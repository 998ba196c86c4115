#include "core/query/engine/internal/paths/chord_walk.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "absl/container/inlined_vector.h"
#include "core/geometry/planar_unfolding.h"
#include "core/geometry/vec2.h"
#include "core/query/engine/internal/paths/path_straightening.h"
#include "core/query/engine/internal/paths/strip_funnel.h"

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

// The 3D vector that the plane vector u of face `flat` (as laid out) stands
// for: the layout is an isometry of the face, so u's coordinates in the
// basis of two laid-out edges carry over to the same edges in space.
Vec3 InSpace(const MeshView& view, const FlatFace& flat, const Vec2& u) {
  const Vec2 e1 = flat.corners[1] - flat.corners[0], e2 = flat.corners[2] - flat.corners[0];
  const double det = Cross(e1, e2);
  const Vec3 p0 = view.Position(flat.vertices[0]);
  return (Cross(u, e2) / det) * (view.Position(flat.vertices[1]) - p0) +
         (Cross(e1, u) / det) * (view.Position(flat.vertices[2]) - p0);
}

// The plane vector of face `flat` (as laid out) that stands for the part of
// the 3D vector v in the face's plane: InSpace's inverse on that plane.
Vec2 InPlane(const MeshView& view, const FlatFace& flat, const Vec3& v) {
  const Vec3 p0 = view.Position(flat.vertices[0]);
  const Vec3 a = view.Position(flat.vertices[1]) - p0, b = view.Position(flat.vertices[2]) - p0;
  const double aa = a.dot(a), ab = a.dot(b), bb = b.dot(b), det = aa * bb - ab * ab;
  const double alpha = (bb * v.dot(a) - ab * v.dot(b)) / det;
  const double beta = (aa * v.dot(b) - ab * v.dot(a)) / det;
  return alpha * (flat.corners[1] - flat.corners[0]) + beta * (flat.corners[2] - flat.corners[0]);
}

bool WalkCorridor(const MeshView& view, const PathPoint& from, const PathPoint& to, int max_steps,
                  std::vector<int32_t>* faces);

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

  explicit Corridor(WalkScratch& scratch)
      : faces_(scratch.faces), flat_(scratch.flat), portals_(scratch.portals) {}

  std::vector<int32_t>& faces() { return faces_; }
  const std::vector<int32_t>& faces() const { return faces_; }

  // Lays out faces() from `from` (a point faces()[0] holds) to `to` (one the
  // last face holds), keeping the layouts of the faces before `first` (laid
  // out by the last call, and unchanged since). Each face is placed by
  // StepAcross, as UnfoldStrip places it, so the layouts agree to the bit.
  // False when consecutive faces share no edge.
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
      if (!StepAcross(view, flat_[t - 1], faces_[t], &portals_[t - 1], &flat_[t])) return false;
    }
    end_ = LocateInFlat(view, flat_[n - 1], to, 0);
    return true;
  }

  // |end - start| when that segment passes through every portal.
  std::optional<double> StraightLength() const {
    return query::StraightLength(start_, portals_, end_);
  }

  // Where the points fall in the layout of the last Unfold or Shoot.
  const Vec2& start() const { return start_; }
  const Vec2& end() const { return end_; }
  const FlatFace& first_face() const { return flat_.front(); }

  // The corridor of a straight geodesic shot from `from`, a point strictly
  // inside its face, along `aim` (a vector of that face as LayOutFace lays
  // it out), laid out as Unfold would: face to face, each step one cross
  // product deciding the edge the ray leaves by, until the ray enters
  // `to`'s face or passes `to` (abeam of it in space, in the face it
  // crosses), where the chord's walk joins it to `to`. `join` is the join's
  // working memory. False when the ray meets the boundary or a vertex
  // exactly, runs past `max_length`, or the join fails.
  bool Shoot(const MeshView& view, const PathPoint& from, const PathPoint& to, const Vec2& aim,
             double max_length, std::vector<int32_t>* join) {
    const int32_t f0 = from.point.face;
    faces_.assign(1, f0);
    flat_.assign(1, LayOutFace(view, f0));
    portals_.clear();
    start_ = LocateInFlat(view, flat_[0], from.point, 0);
    const Vec2 u = aim.normalized();
    auto side = [&](const Vec2& c) { return Cross(u, c - start_); };
    // Faces are laid out counter-clockwise: the ray leaves by the edge
    // (corner k, corner k + 1) whose corner k is on its right and k + 1 on
    // its left.
    int exit = -1;
    for (int k = 0; k < 3; ++k) {
      if (side(flat_[0].corners[k]) <= 0 && side(flat_[0].corners[(k + 1) % 3]) > 0) exit = k;
    }
    if (exit < 0) return false;
    for (int step = 0; step < kMaxShotSteps; ++step) {
      const FlatFace& flat = flat_.back();
      if (FaceHolds(view, flat.face, to.point)) {
        end_ = LocateInFlat(view, flat, to.point, 0);
        return true;
      }
      const int right = exit, left = (exit + 1) % 3;
      const double sr = side(flat.corners[right]), sl = side(flat.corners[left]);
      const double lambda = sr / (sr - sl);  // sr <= 0 < sl: where the ray crosses
      const Vec2 x = flat.corners[right] + lambda * (flat.corners[left] - flat.corners[right]);
      if (u.dot(x - start_) > max_length) return false;
      const Vec3 pr = view.Position(flat.vertices[right]);
      const Vec3 x3 = pr + lambda * (view.Position(flat.vertices[left]) - pr);
      if ((to.position - x3).dot(InSpace(view, flat, u)) <= 0) {
        return Join(view, from.point, to, lambda, exit, join);
      }
      const int32_t twin = view.twins[3 * flat.face + exit];
      if (twin < 0) return false;
      faces_.push_back(twin / 3);
      flat_.emplace_back();
      portals_.emplace_back();
      StepAcross(view, flat_[flat_.size() - 2], twin / 3, &portals_.back(), &flat_.back());
      // The ray entered across the twin half-edge, which runs from the
      // entry's left corner to its right one: the third corner's side
      // chooses the edge it leaves by.
      const FlatFace& next = flat_.back();
      const int entry_right = (twin % 3 + 1) % 3, third = (entry_right + 1) % 3;
      const double st = side(next.corners[third]);
      if (st == 0) return false;  // through a vertex
      exit = st > 0 ? entry_right : third;
    }
    return false;
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
  static constexpr int kMaxShotSteps = 256;

  // Joins the ray of Shoot, which leaves the last face across its edge
  // `exit` at `lambda` from the edge's start, to `to` by the chord's walk
  // from a point just inside that face, and lays the joined faces out. A
  // join that comes back through the ray's last faces cuts the loop.
  bool Join(const MeshView& view, const SurfacePoint& from, const PathPoint& to, double lambda,
            int exit, std::vector<int32_t>* join) {
    const FlatFace& flat = flat_.back();
    // Inside by a thousandth of the way to the centroid: the walk starts in
    // this face, not in its neighbour across the edge.
    constexpr double kInward = 1e-3;
    SurfacePoint x{flat.face, {kInward / 3, kInward / 3, kInward / 3}};
    x.w[exit] += (1 - kInward) * (1 - lambda);
    x.w[(exit + 1) % 3] += (1 - kInward) * lambda;
    const PathPoint start{x, view.PositionOf(x)};
    if (!WalkCorridor(view, start, to, kMaxShotSteps, join)) return false;
    size_t keep = faces_.size();  // the faces whose layouts stay
    for (size_t i = 1; i < join->size(); ++i) {
      const int32_t g = (*join)[i];
      // A face the corridor already holds near its end: cut back to it.
      const size_t lookback = std::min<size_t>(faces_.size(), 16);
      const auto again = std::find(faces_.end() - lookback, faces_.end(), g);
      if (again == faces_.end()) {
        faces_.push_back(g);
        continue;
      }
      const size_t at = static_cast<size_t>(again - faces_.begin());
      faces_.resize(at + 1);
      keep = std::min(keep, at + 1);
    }
    return Unfold(view, from, to.point, keep);
  }

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

// The aim of a pair's shots: the angle of the first, then the secant on the
// miss (the angle between a shot and where its target fell, which falls as
// the aim turns counter-clockwise), held by regula falsi within the last
// bracket of a sign change: the map from aim to miss jumps where rays pass
// on either side of a curved vertex, where the secant alone wanders.
class AimSearch {
 public:
  explicit AimSearch(double theta) : theta_(theta) {}

  // The angle to shoot at next, and the one of the smallest miss so far.
  double theta() const { return theta_; }
  double best() const { return best_.theta; }
  bool last_is_best() const { return last_.theta == best_.theta; }

  // Takes the miss of a shot at theta() and moves theta() on.
  void Record(double miss) {
    const Sample now{theta_, miss};
    if (std::abs(miss) < std::abs(best_.miss)) best_ = now;
    (miss < 0 ? low_ : high_) = now;
    double next = theta_ + miss;  // the fixed point, where the secant is not sound
    if (last_.seen() && miss != last_.miss) {
      const double secant = theta_ - miss * (theta_ - last_.theta) / (miss - last_.miss);
      if (std::abs(secant - theta_) < 4 * std::abs(miss) + 1e-3) next = secant;
    }
    if (low_.seen() && high_.seen() &&
        !(std::min(low_.theta, high_.theta) < next && next < std::max(low_.theta, high_.theta))) {
      next = low_.theta - low_.miss * (high_.theta - low_.theta) / (high_.miss - low_.miss);
    }
    last_ = now;
    theta_ = next;
  }

 private:
  struct Sample {
    double theta = std::numeric_limits<double>::quiet_NaN();
    double miss = std::numeric_limits<double>::infinity();
    bool seen() const { return !std::isnan(theta); }
  };
  double theta_;
  Sample last_, low_, high_, best_;
};

// The walks of one near pair (WalkNearPair): geodesics shot from `from`,
// then the chord's walks from either end, each corridor unfolded into the
// plane. A straight segment through a corridor is a local geodesic, as the
// straightened trace would be, found without evaluating the distance
// field, so at a fraction of the trace's cost. Else the funnel's path
// through it, released from the vertices it bends round short of a
// straight angle on their other side: one that then bends at no vertex, or
// at one saddle by no more than its angle excess, is a local geodesic too.
// Paths bending at several saddles were often in a wrong corridor, and so,
// rarely, is a straight one longer than `plausible` (across a sharp
// feature); then the caller decides (NearPathLength: the trace; the
// refinement: an exact propagation round the pair). Every candidate is a
// surface path, so the shortest is kept (figures: tests/bench/throughput.md).
class NearWalker {
 public:
  NearWalker(const MeshView& view, const SurfacePoint& from, const SurfacePoint& to,
             const NearWalkOptions& options, QueryScratch& scratch, bool own_scratch)
      : view_(view),
        ends_{{from, view.PositionOf(from)}, {to, view.PositionOf(to)}},
        plausible_(options.plausible),
        plausible_shot_(std::min(options.plausible, options.plausible_shot)),
        heading_(options.heading),
        shoot_(options.shoot),
        walks_(scratch.walks()),
        count_(scratch.near_pair_stats()),
        corridor_(walks_),
        own_scratch_(own_scratch) {}

  NearWalk Walk() {
    // Without a plausible length nothing tells a shot that went round the
    // wrong side of a handle or a bump (the secant may wander there): the
    // shot is doubted, and the chord's walks answer as they would without
    // it.
    const bool checked = std::isfinite(plausible_);
    if (std::optional<NearPath> shot = Shoot()) {
      if (checked) return Answer(*shot, corridor_.faces());
      Doubt(shot->length);
    }
    // Else the last shot ran within a small angle of the geodesic: its
    // corridor holds the geodesic but near the vertices the ray passed
    // close to, which the funnel bends round and the releases settle. A
    // shot that did not converge may settle round the wrong side of a
    // feature, which only a check can tell: unchecked, the chord's walks
    // answer as they would without shots.
    const bool shot_corridor = !corridor_.faces().empty();
    if (checked && shot_corridor) {
      if (std::optional<NearPath> settled =
              Settle(ends_[0].point, ends_[1].point, kMaxShotReleases, plausible_shot_)) {
        return Answer(*settled, corridor_.faces());
      }
    }
    if (checked && found_) return Answer(*found_, walks_.found_faces);
    // The chord's walks seldom settle a pair whose shots did not (they
    // pursue the chord, which the shots left for the geodesic): the caller
    // takes it from here.
    if (checked && shot_corridor) {
      if (doubted_) return {std::nullopt, doubted_, InScratch(walks_.doubted_faces)};
      return {std::nullopt, std::nullopt, InScratch(corridor_.faces())};
    }
    for (int start = 0; start < 2; ++start) {
      const SurfacePoint& a = ends_[start].point;
      const SurfacePoint& b = ends_[1 - start].point;
      if (!WalkCorridor(view_, ends_[start], ends_[1 - start], kMaxWalkSteps, &corridor_.faces()) ||
          !corridor_.Unfold(view_, a, b)) {
        continue;
      }
      ++count_.walks;
      count_.faces_crossed += static_cast<int64_t>(corridor_.faces().size());
      count_.faces_unfolded += static_cast<int64_t>(corridor_.faces().size());
      if (std::optional<NearPath> settled = Settle(a, b, kMaxReleases, plausible_)) {
        if (!found_ || settled->length <= found_->length) {
          return Answer(*settled, corridor_.faces());
        }
      }
    }
    // Every candidate is a surface path: the shortest is the closest.
    if (found_) {
      if (doubted_ && *doubted_ < found_->length) {
        return Answer(NearPath{*doubted_, true}, walks_.doubted_faces);
      }
      return Answer(*found_, walks_.found_faces);
    }
    if (doubted_) return {std::nullopt, doubted_, InScratch(walks_.doubted_faces)};
    return {};
  }

 private:
  // Keeps `path`, through the corridor as it is, if it is the shortest
  // local geodesic found so far.
  void Keep(const NearPath& path) {
    if (found_ && found_->length <= path.length) return;
    found_ = path;
    walks_.found_faces.assign(corridor_.faces().begin(), corridor_.faces().end());
  }

  static constexpr int kMaxWalkSteps = 256;
  // A release shortens the path; a near path passes few vertices.
  static constexpr int kMaxReleases = 8;
  // A shot's corridor runs close to the geodesic: its releases are worth
  // more of them than a trace costs.
  static constexpr int kMaxShotReleases = 24;
  // Shots at the other point: nine in ten of the straight ones are straight
  // by the second (tests/bench/throughput.md, "The every-distance mode").
  static constexpr int kMaxShots = 4;
  // The angle (radians) between a shot and where its target fell, below
  // which the shot's corridor is settled by the funnel instead of shot
  // again.
  static constexpr double kSettleAngle = 0.01;

  // Geodesics shot from an interior `from` (at a vertex the direction of a
  // ray is not one angle): aimed along the heading (else the chord), then
  // by the secant on the angle between the aim and where `to` fell in the
  // last shot's layout (the layout of a corridor is a chart of the surface
  // round it, so that angle goes to 0 as the aim does). A walk that pursues
  // `to` along the chord bends away from the geodesic wherever the chord
  // leaves the surface, which on curved parts costs releases or a trace.
  // The straight shot, if one is; else the corridor holds the best shot's
  // (or is empty).
  std::optional<NearPath> Shoot() {
    corridor_.faces().clear();
    const SurfacePoint& from = ends_[0].point;
    if (!shoot_ || !(from.w[0] > 0 && from.w[1] > 0 && from.w[2] > 0)) return std::nullopt;
    const Vec3 chord = ends_[1].position - ends_[0].position;
    const Vec2 aim =
        InPlane(view_, LayOutFace(view_, from.face), heading_.squaredNorm() > 0 ? heading_ : chord);
    AimSearch search(std::atan2(aim.y(), aim.x()));
    for (int shot = 0; shot < kMaxShots; ++shot) {
      const std::optional<Shot> fired = ShootAt(search.theta(), chord.norm());
      if (!fired) return std::nullopt;
      if (fired->straight) {
        if (*fired->straight > plausible_shot_) {
          Doubt(*fired->straight);
          return std::nullopt;
        }
        ++count_.straight_at_shot[shot];
        return NearPath{*fired->straight, false};
      }
      // Within a small angle another shot mostly moves the ray across a
      // vertex it passes close to, and back: the funnel does better.
      if (std::abs(fired->miss) < kSettleAngle) return std::nullopt;
      search.Record(fired->miss);
    }
    // The funnel settles the corridor of the best shot.
    if (!search.last_is_best()) (void)ShootAt(search.best(), chord.norm());
    return std::nullopt;
  }

  // One shot at angle theta (in the layout of from's face): nullopt when
  // the ray is cut short (the corridor is then cleared: none to settle);
  // else its length if it is straight, or its miss, the angle between the
  // shot and where `to` fell in its corridor's layout.
  struct Shot {
    std::optional<double> straight;
    double miss = 0;
  };
  std::optional<Shot> ShootAt(double theta, double chord) {
    const Vec2 u(std::cos(theta), std::sin(theta));
    if (!corridor_.Shoot(view_, ends_[0], ends_[1], u, 2 * chord, &walks_.join)) {
      corridor_.faces().clear();
      return std::nullopt;
    }
    ++count_.shots;
    count_.faces_crossed += static_cast<int64_t>(corridor_.faces().size());
    if (const std::optional<double> length = corridor_.StraightLength()) return Shot{length, 0};
    const Vec2 seen = corridor_.end() - corridor_.start();
    return Shot{std::nullopt, std::atan2(Cross(u, seen), u.dot(seen))};
  }

  // The funnel's path through the corridor, which runs from a to b and is
  // laid out, released round vertices it bends round short of a straight
  // angle: a local geodesic straight in the corridor as found is returned;
  // one found after releases is kept in found_ (the other walk may find a
  // shorter one), a doubted one in doubted_.
  std::optional<NearPath> Settle(const SurfacePoint& a, const SurfacePoint& b, int max_releases,
                                 double plausible) {
    if (corridor_.faces().empty()) return std::nullopt;
    if (const std::optional<double> length = corridor_.StraightLength()) {
      if (*length <= plausible) return NearPath{*length, false};
      Doubt(*length);
      return std::nullopt;
    }
    for (int release = 0; release <= max_releases; ++release) {
      const double length = corridor_.Shortest(&bends_);
      std::optional<const Corridor::Bend*> shortcut = Shortcut();
      if (!shortcut) return std::nullopt;  // a boundary vertex
      if (*shortcut == nullptr) {
        if (length <= plausible && bends_.size() <= 1) {
          if (release == 0 && bends_.empty()) return NearPath{length, false};
          Keep(NearPath{length, !bends_.empty()});
        } else {
          Doubt(length);
        }
        return std::nullopt;
      }
      ++count_.releases;
      if (!corridor_.Release(view_, **shortcut)) return std::nullopt;
      const size_t changed = (*shortcut)->first + 1;
      if (!corridor_.Unfold(view_, a, b, changed)) return std::nullopt;
      count_.faces_unfolded += static_cast<int64_t>(corridor_.faces().size() - changed);
    }
    return std::nullopt;
  }

  // The first bend of the funnel's path short of a straight angle on its
  // vertex's other side (null: none); nullopt at a boundary vertex, where
  // the angle is not known.
  std::optional<const Corridor::Bend*> Shortcut() const {
    for (const Corridor::Bend& bend : bends_) {
      const std::optional<double> angle =
          AngleSum(view_, corridor_.faces()[bend.first], bend.vertex);
      if (!angle) return std::nullopt;
      if (bend.turn > *angle - 2 * M_PI + kBendSlack) return &bend;
    }
    return nullptr;
  }

  // Keeps the shortest doubted length and its corridor.
  void Doubt(double length) {
    if (doubted_ && *doubted_ <= length) return;
    doubted_ = length;
    walks_.doubted_faces.assign(corridor_.faces().begin(), corridor_.faces().end());
  }

  // The corridor returned lives in the scratch: none when the scratch is
  // this call's own.
  std::span<const int32_t> InScratch(std::span<const int32_t> faces) const {
    return own_scratch_ ? std::span<const int32_t>() : faces;
  }
  NearWalk Answer(const NearPath& path, std::span<const int32_t> faces) const {
    return {path, std::nullopt, InScratch(faces)};
  }

  const MeshView& view_;
  const PathPoint ends_[2];
  const double plausible_;
  const double plausible_shot_;
  const Vec3 heading_;
  const bool shoot_;
  WalkScratch& walks_;
  NearPairStats& count_;
  Corridor corridor_;
  const bool own_scratch_;
  Corridor::Bends bends_;
  std::optional<NearPath> found_;
  std::optional<double> doubted_;
};

}  // namespace

NearWalk WalkNearPair(const MeshView& view, const SurfacePoint& from, const SurfacePoint& to,
                      const NearWalkOptions& options, QueryScratch* scratch) {
  QueryScratch own;
  return NearWalker(view, from, to, options, scratch != nullptr ? *scratch : own,
                    scratch == nullptr)
      .Walk();
}

std::optional<NearPath> NearPathLength(const MeshView& view, const GradientPaths& paths,
                                       const SurfacePoint& from, const SurfacePoint& to,
                                       bool walk_chord, double plausible) {
  std::optional<double> doubted;
  if (walk_chord) {
    const NearWalk walk = WalkNearPair(view, from, to, {.plausible = plausible});
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
