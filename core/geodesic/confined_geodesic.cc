#include "core/geodesic/confined_geodesic.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex::geodesic {
namespace {

using mesh::kNone;
using mesh::Vec3;

// A border bound may fall short of d_R(q) by this fraction of it and still
// certify: the terms and d_R(q) carry rounding of that order, and accepting
// it bounds the answer's error by it.
constexpr double kCertificateSlack = 1e-12;

// A point's coordinates relative to the line of a half-edge: `u` along it
// from its origin, `r` the distance from the line.
struct LineCoords {
  double u, r;
};

LineCoords CoordsAlong(const Mesh& mesh, int32_t h, const Vec3& x) {
  const Vec3& o = mesh.position(mesh.Origin(h));
  const double length = mesh.Length(h);
  if (!(length > 0)) return {0, (x - o).norm()};
  const Vec3 axis = (mesh.position(mesh.Dest(h)) - o) / length;
  const Vec3 rel = x - o;
  return {rel.dot(axis), rel.cross(axis).norm()};
}

// min over u in [lo, hi] of |X - (u,0)| + |(u,0) - Y|, for X and Y given by
// their coordinates relative to the line (each may be turned about it
// freely). The sum is convex in u; on the whole line its minimum is where
// the segment from X to Y unfolded across the line meets it, so clamping
// that point to [lo, hi] gives the minimum over the interval.
double MinSumOnSegment(LineCoords x, LineCoords y, double lo, double hi) {
  if (hi < lo) std::swap(lo, hi);
  const double r = x.r + y.r;
  double u = r > 0 ? x.u + (y.u - x.u) * (x.r / r) : x.u;
  u = std::clamp(u, lo, hi);
  return Hypot(u - x.u, x.r) + Hypot(u - y.u, y.r);
}

}  // namespace

ConfinedGeodesicSolver::ConfinedGeodesicSolver(const Mesh& mesh, const ConfinedOptions& options)
    : ConfinedGeodesicSolver(std::make_unique<ExactGeodesicSolver>(mesh), nullptr, options) {}

ConfinedGeodesicSolver::ConfinedGeodesicSolver(ExactGeodesicSolver& engine,
                                               const ConfinedOptions& options)
    : ConfinedGeodesicSolver(nullptr, &engine, options) {}

// mesh_ is read off the engine before own_engine_ takes it (members are made
// in their order of declaration).
ConfinedGeodesicSolver::ConfinedGeodesicSolver(std::unique_ptr<ExactGeodesicSolver> own,
                                               ExactGeodesicSolver* borrowed,
                                               const ConfinedOptions& options)
    : mesh_((borrowed != nullptr ? *borrowed : *own).mesh()),
      options_(options),
      own_engine_(std::move(own)),
      engine_(borrowed != nullptr ? *borrowed : *own_engine_),
      in_region_(mesh_.num_faces(), 0),
      slot_(mesh_.num_halfedges(), -1),
      chain_parent_(mesh_.num_faces(), -2) {
  // The points' stars must lie inside the region: the certificate has no
  // term for paths that leave it at a source.
  options_.seed_rings = std::max(options_.seed_rings, 1);
}

void ConfinedGeodesicSolver::ClearRegion() {
  for (const int32_t f : region_faces_) in_region_[f] = 0;
  region_faces_.clear();
}

void ConfinedGeodesicSolver::AddFace(int32_t f) {
  if (in_region_[f]) return;
  in_region_[f] = 1;
  region_faces_.push_back(f);
}

void ConfinedGeodesicSolver::GrowRings(std::vector<int32_t>& vertices, int32_t rings) {
  std::vector<int32_t>& next = next_vertices_;
  for (int32_t ring = 0; ring < rings && !vertices.empty(); ++ring) {
    next.clear();
    for (const int32_t v : vertices) {
      for (const int32_t o : mesh_.Outgoing(v)) {
        const int32_t f = Mesh::FaceOf(o);
        if (in_region_[f]) continue;
        AddFace(f);
        for (const int32_t w : mesh_.face(f)) next.push_back(w);
      }
    }
    std::swap(vertices, next);
  }
}

void ConfinedGeodesicSolver::AddFaceChain(int32_t from, int32_t to) {
  chain_parent_[from] = -1;
  chain_reached_.push_back(from);
  for (size_t i = 0; i < chain_reached_.size() && chain_parent_[to] == -2; ++i) {
    const int32_t f = chain_reached_[i];
    for (int k = 0; k < 3; ++k) {
      const int32_t t = mesh_.Twin(3 * f + k);
      if (t == kNone) continue;
      const int32_t g = Mesh::FaceOf(t);
      if (chain_parent_[g] != -2) continue;
      chain_parent_[g] = f;
      chain_reached_.push_back(g);
    }
  }
  if (chain_parent_[to] != -2) {
    for (int32_t f = to; f != -1; f = chain_parent_[f]) AddFace(f);
  }
  for (const int32_t f : chain_reached_) chain_parent_[f] = -2;
  chain_reached_.clear();
}

void ConfinedGeodesicSolver::AddEllipsoid(int32_t start, const Vec3& p, const Vec3& q,
                                          double length) {
  // Faces some point x of which may have |x - p| + |x - q| <= length, by a
  // lower bound on that sum over the face: its value at the centroid less
  // twice the face's radius about it.
  // The centroids and radii are the same in every call: computed once
  // (they were a tenth of a near pair's exact check).
  if (face_ball_.empty()) {
    face_ball_.resize(mesh_.num_faces());
    for (int32_t f = 0; f < mesh_.num_faces(); ++f) {
      const auto& [a, b, c] = mesh_.face(f);
      const Vec3 centroid = (mesh_.position(a) + mesh_.position(b) + mesh_.position(c)) / 3;
      const double radius =
          std::max({(mesh_.position(a) - centroid).norm(), (mesh_.position(b) - centroid).norm(),
                    (mesh_.position(c) - centroid).norm()});
      face_ball_[f] = {centroid.x(), centroid.y(), centroid.z(), radius};
    }
  }
  auto inside = [&](int32_t f) {
    const std::array<double, 4>& ball = face_ball_[f];
    const Vec3 centroid(ball[0], ball[1], ball[2]);
    return (centroid - p).norm() + (centroid - q).norm() - 2 * ball[3] <= length;
  };
  // chain_parent_ marks the faces tested (-1), chain_reached_ lists them;
  // the ones inside are queued.
  std::vector<int32_t>& queue = ellipsoid_queue_;
  queue.clear();
  chain_parent_[start] = -1;
  chain_reached_.push_back(start);
  queue.push_back(start);
  for (size_t i = 0; i < queue.size(); ++i) {
    const int32_t f = queue[i];
    AddFace(f);
    for (int k = 0; k < 3; ++k) {
      const int32_t t = mesh_.Twin(3 * f + k);
      if (t == kNone) continue;
      const int32_t g = Mesh::FaceOf(t);
      if (chain_parent_[g] != -2) continue;
      chain_parent_[g] = -1;
      chain_reached_.push_back(g);
      if (inside(g)) queue.push_back(g);
    }
  }
  for (const int32_t f : chain_reached_) chain_parent_[f] = -2;
  chain_reached_.clear();
}

void ConfinedGeodesicSolver::FindViolations(const Vec3& q, double distance,
                                            std::vector<int32_t>& violating_vertices) {
  border_.clear();
  bound_.clear();
  // Corners of each border edge's face: a path to a point b of the edge
  // through corner c, straight from c, is d_R(c) + |c - b| long.
  for (const int32_t f : region_faces_) {
    for (int k = 0; k < 3; ++k) {
      const int32_t h = 3 * f + k;
      const int32_t t = mesh_.Twin(h);
      if (t == kNone || in_region_[Mesh::FaceOf(t)]) continue;
      const double length = mesh_.Length(h);
      const LineCoords qc = CoordsAlong(mesh_, h, q);
      const int32_t a = mesh_.Origin(h), b = mesh_.Dest(h), c = mesh_.Opposite(h);
      double bound = engine_.VertexDistance(a) + MinSumOnSegment({0, 0}, qc, 0, length);
      bound =
          std::min(bound, engine_.VertexDistance(b) + MinSumOnSegment({length, 0}, qc, 0, length));
      bound = std::min(
          bound, engine_.VertexDistance(c) +
                     MinSumOnSegment(CoordsAlong(mesh_, h, mesh_.position(c)), qc, 0, length));
      slot_[h] = static_cast<int32_t>(border_.size());
      border_.push_back(h);
      bound_.push_back(bound);
    }
  }
  // Windows that reached the border: the point x of [b0,b1] is
  // sigma + |S - x| away, S the pseudo-source in the edge's frame.
  for (const ExactGeodesicSolver::BorderWindow& w : engine_.BorderWindows()) {
    const int32_t s = slot_[mesh_.Twin(w.h)];
    const double term =
        w.sigma + MinSumOnSegment({w.sx, std::abs(w.sy)}, CoordsAlong(mesh_, w.h, q), w.b0, w.b1);
    bound_[s] = std::min(bound_[s], term);
  }
  // Points of the border at least SettledBelow() away (where the terms may be
  // incomplete) need no term: SettledBelow() >= distance.
  const double threshold =
      distance < kInfinity ? distance - kCertificateSlack * distance : kInfinity;
  for (size_t i = 0; i < border_.size(); ++i) {
    const int32_t h = border_[i];
    slot_[h] = -1;
    if (bound_[i] < threshold) {
      violating_vertices.push_back(mesh_.Origin(h));
      violating_vertices.push_back(mesh_.Dest(h));
    }
  }
}

absl::StatusOr<double> ConfinedGeodesicSolver::Distance(const SurfacePoint& p,
                                                        const SurfacePoint& q,
                                                        std::span<const int32_t> seed_faces,
                                                        double upper_bound) {
  stats_ = {};
  GEODEX_RETURN_IF_ERROR(mesh::ValidateSurfacePoint(mesh_, p));
  GEODEX_RETURN_IF_ERROR(mesh::ValidateSurfacePoint(mesh_, q));
  for (const int32_t f : seed_faces) {
    if (f < 0 || f >= mesh_.num_faces()) {
      return absl::OutOfRangeError(
          absl::StrFormat("seed face %d out of range [0, %d)", f, mesh_.num_faces()));
    }
  }
  ClearRegion();
  AddFace(p.face);
  AddFace(q.face);
  for (const int32_t f : seed_faces) AddFace(f);
  if (seed_faces.empty()) AddFaceChain(p.face, q.face);
  vertices_.clear();
  for (const int32_t f : region_faces_) {
    for (const int32_t v : mesh_.face(f)) vertices_.push_back(v);
  }
  GrowRings(vertices_, options_.seed_rings);

  GeodesicOptions options;
  options.stop_points = {q};
  const Vec3 px = mesh::PositionOf(mesh_, p), qx = mesh::PositionOf(mesh_, q);
  bool ellipsoid_added = false;
  if (upper_bound < kInfinity) {
    ellipsoid_added = true;
    AddEllipsoid(p.face, px, qx, upper_bound);
    options.prune_length = upper_bound;
    options.prune_point = qx;
  }
  for (int32_t rings = 1;; rings *= 2) {
    options.face_region = in_region_;
    ++stats_.rounds;
    GEODEX_RETURN_IF_ERROR(engine_.Propagate({p}, options));
    stats_.windows_created += engine_.stats().windows_created;
    const double d = engine_.DistanceAt(q);
    vertices_.clear();
    FindViolations(qx, d, vertices_);
    if (vertices_.empty()) {
      stats_.region_faces = static_cast<int32_t>(region_faces_.size());
      stats_.border_edges = static_cast<int32_t>(border_.size());
      return d;
    }
    // A path from p to q no longer than d_R(q) lies inside the ellipsoid
    // |x - p| + |x - q| <= d_R(q), so it crosses only faces that meet the
    // ellipsoid, and those faces are connected along it: the faces reached
    // from p's face through such faces hold every shortest path, and the
    // next round certifies (every border point b then has
    // d_R(b) + |b - q| >= |b - p| + |b - q| > d_R(q)). Growing rings round
    // the violating edges instead took 3-4 rounds round thin features,
    // where the straight line to q is far shorter than the way round.
    if (d < kInfinity && !ellipsoid_added) {
      ellipsoid_added = true;
      AddEllipsoid(p.face, px, qx, d);
      // And inside it, only what may lead to q within d_R(q).
      options.prune_length = d;
      options.prune_point = qx;
    } else {
      // Each round adds at least the faces beyond the violating edges, so
      // the region reaches a whole component at the latest.
      GrowRings(vertices_, rings);
    }
  }
}

absl::StatusOr<std::vector<SurfacePoint>> ConfinedGeodesicSolver::Path(
    const SurfacePoint& p, const SurfacePoint& q, std::span<const int32_t> seed_faces) {
  GEODEX_ASSIGN_OR_RETURN(const double d, Distance(p, q, seed_faces));
  if (!(d < kInfinity)) return absl::NotFoundError("the points lie in different components");
  GEODEX_ASSIGN_OR_RETURN(std::vector<SurfacePoint> path, engine_.PathTo(q));
  std::reverse(path.begin(), path.end());
  return path;
}

}  // namespace geodex::geodesic
