#include "core/triangulation/geodesic_edges.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <iterator>
#include <thread>
#include <tuple>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/common/threads.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/geometry/face_frame.h"
#include "core/geometry/vec2.h"

namespace geodex::triangulation {
namespace {

using mesh::kNone;
using mesh::Mesh;
using mesh::SurfacePoint;
using mesh::Vec3;

// Barycentric weights below this are zero: a path point that close to a mesh
// edge or vertex is on it.
constexpr double kSnap = 1e-9;

// A path point in a form that does not depend on the face it was expressed
// in: at a vertex, on an edge (the half-edge with the smaller id of the twin
// pair, t measured from its origin) or inside a face.
struct Location {
  enum class Kind : int8_t { kVertex, kEdge, kFace };
  Kind kind = Kind::kFace;
  int32_t id = kNone;  // vertex, half-edge or face
  double t = 0;
  std::array<double, 3> w = {0, 0, 0};
};

Location Locate(const Mesh& mesh, const SurfacePoint& p) {
  std::array<double, 3> w = p.w;
  const double sum = w[0] + w[1] + w[2];
  int nonzero = 0, zero = 0, last = 0;
  for (int i = 0; i < 3; ++i) {
    w[i] = std::max(w[i] / sum, 0.0);
    if (w[i] <= kSnap) {
      zero = i;
    } else {
      ++nonzero;
      last = i;
    }
  }
  Location at;
  if (nonzero <= 1) {
    at.kind = Location::Kind::kVertex;
    at.id = mesh.face(p.face)[last];
  } else if (nonzero == 2) {
    int32_t h = 3 * p.face + (zero + 1) % 3;  // the side opposite the zero weight
    double t = w[(zero + 2) % 3] / (w[(zero + 1) % 3] + w[(zero + 2) % 3]);
    const int32_t twin = mesh.Twin(h);
    if (twin != kNone && twin < h) {
      h = twin;
      t = 1 - t;
    }
    at.kind = Location::Kind::kEdge;
    at.id = h;
    at.t = t;
  } else {
    at.kind = Location::Kind::kFace;
    at.id = p.face;
    at.w = w;
  }
  return at;
}

bool SameLocation(const Location& x, const Location& y) {
  if (x.kind != y.kind || x.id != y.id) return false;
  switch (x.kind) {
    case Location::Kind::kVertex:
      return true;
    case Location::Kind::kEdge:
      return std::abs(x.t - y.t) <= kSnap;
    case Location::Kind::kFace:
      return std::max({std::abs(x.w[0] - y.w[0]), std::abs(x.w[1] - y.w[1]),
                       std::abs(x.w[2] - y.w[2])}) <= kSnap;
  }
  return false;
}

// The faces that contain a location, appended to `out`.
void FacesOf(const Mesh& mesh, const Location& at, std::vector<int32_t>* out) {
  switch (at.kind) {
    case Location::Kind::kVertex:
      for (const int32_t h : mesh.Outgoing(at.id)) out->push_back(Mesh::FaceOf(h));
      break;
    case Location::Kind::kEdge:
      out->push_back(Mesh::FaceOf(at.id));
      if (mesh.Twin(at.id) != kNone) out->push_back(Mesh::FaceOf(mesh.Twin(at.id)));
      break;
    case Location::Kind::kFace:
      out->push_back(at.id);
      break;
  }
}

// Barycentric weights of a location in face `f`, which must contain it.
std::array<double, 3> WeightsIn(const Mesh& mesh, const Location& at, int32_t f) {
  std::array<double, 3> w = {0, 0, 0};
  switch (at.kind) {
    case Location::Kind::kVertex:
      for (int i = 0; i < 3; ++i) {
        if (mesh.face(f)[i] == at.id) w[i] = 1;
      }
      break;
    case Location::Kind::kEdge: {
      const int32_t h = at.id;
      if (Mesh::FaceOf(h) == f) {
        w[h % 3] = 1 - at.t;
        w[(h + 1) % 3] = at.t;
      } else {
        const int32_t g = mesh.Twin(h);  // Origin(g) = Dest(h)
        w[g % 3] = at.t;
        w[(g + 1) % 3] = 1 - at.t;
      }
      break;
    }
    case Location::Kind::kFace:
      w = at.w;
      break;
  }
  return w;
}

using geometry::Vec2;

// A face whose doubled area is below this fraction of its longest side
// squared is degenerate for FindCrossings: the bound by which mesh repair
// counts sliver faces.
constexpr double kDegenerateArea = 1e-6;

// A face in its own planar frame: corner 0 at the origin, corner 1 at (l, 0),
// corner 2 at (cx, cy) with cy > 0.
struct FaceFrame {
  double l, cx, cy;
  double size;  // longest side

  FaceFrame(const Mesh& mesh, int32_t f) {
    const Vec3& p0 = mesh.position(mesh.face(f)[0]);
    const Vec3& p1 = mesh.position(mesh.face(f)[1]);
    const Vec3& p2 = mesh.position(mesh.face(f)[2]);
    const geometry::FaceFrame frame = geometry::FrameOfTriangle(p0, p1, p2);
    l = frame.length;
    cx = frame.cx;
    cy = frame.cy;
    const Vec3 e1 = p1 - p0, e2 = p2 - p0;
    size = std::max({l, e2.norm(), (e2 - e1).norm()});
    if (!(cy * l >= kDegenerateArea * size * size)) {
      // A zero-area or needle face flattens to a segment (or a point), where
      // every two pieces would touch: a path along one side and the opposite
      // corner, or two paths that cross the face apart. Which pieces cross is
      // a matter of the face's combinatorics, the same in any affine image,
      // so compare them in an equilateral triangle of the same size instead.
      size = size > 0 ? size : 1;
      l = size;
      cx = size / 2;
      cy = size * std::sqrt(3.0) / 2;
    }
  }
  Vec2 Map(const std::array<double, 3>& w) const { return {w[1] * l + w[2] * cx, w[2] * cy}; }
  SurfacePoint Unmap(int32_t f, const Vec2& p) const {
    SurfacePoint out;
    out.face = f;
    const double w2 = std::clamp(p[1] / cy, 0.0, 1.0);
    const double w1 = std::clamp((p[0] - w2 * cx) / l, 0.0, 1.0 - w2);
    out.w = {1 - w1 - w2, w1, w2};
    return out;
  }
};

// The point of segment [a, b] nearest to p.
Vec2 Nearest(const Vec2& p, const Vec2& a, const Vec2& b) {
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double len2 = dx * dx + dy * dy;
  if (!(len2 > 0)) return a;
  const double t = std::clamp(((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2, 0.0, 1.0);
  return {a[0] + t * dx, a[1] + t * dy};
}

// Whether segments [a0, a1] and [b0, b1] come within `eps` of each other, and
// where.
bool SegmentsTouch(const Vec2& a0, const Vec2& a1, const Vec2& b0, const Vec2& b1, double eps,
                   Vec2* at) {
  // Each end's side of the other segment's line (positive to the left).
  const double o1 = geometry::Cross(a1 - a0, b0 - a0), o2 = geometry::Cross(a1 - a0, b1 - a0);
  const double o3 = geometry::Cross(b1 - b0, a0 - b0), o4 = geometry::Cross(b1 - b0, a1 - b0);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) {
    const double t = o3 / (o3 - o4);
    *at = {a0[0] + t * (a1[0] - a0[0]), a0[1] + t * (a1[1] - a0[1])};
    return true;
  }
  // No proper crossing: the closest approach involves an endpoint.
  double best = eps;
  bool touch = false;
  auto consider = [&](const Vec2& p, const Vec2& s0, const Vec2& s1) {
    const Vec2 q = Nearest(p, s0, s1);
    const double d = (p - q).norm();
    if (d < best) {
      best = d;
      touch = true;
      *at = {(p[0] + q[0]) / 2, (p[1] + q[1]) / 2};
    }
  };
  consider(a0, b0, b1);
  consider(a1, b0, b1);
  consider(b0, a0, a1);
  consider(b1, a0, a1);
  return touch;
}

// A piece of one path inside one face: a segment between two consecutive
// points, or a single point of the path that lies on the face's boundary.
struct Piece {
  int32_t face;
  int32_t edge;                // index of the path's edge
  std::array<double, 3> p, q;  // barycentric in `face`
  int32_t vp, vq;              // mesh vertex at p / q, or kNone
};

// When a mesh edge joins vertices u and v and is no longer than their
// geodesic `distance`, it is a shortest geodesic between them: sets `edge`'s
// path to it and returns true. Among shortest paths of equal length the
// propagation's backtracking picks one by rounding, and on a degenerate
// surface it may pick one that leaves the edge: through the apex of a
// zero-area face lying on the edge (a cap, which scans and their repair keep)
// or across the other layer where a fold is pressed flat and its two sides
// share vertices (decimation by clustering). Such a path meets the Delaunay
// edges of the neighbouring samples although the mesh edge meets none, and no
// added sample can change it: the samples there are adjacent vertices
// already. The mesh edge is the choice that does not depend on rounding.
bool MeshEdgePath(const Mesh& mesh, int32_t u, int32_t v, double distance, GeodesicEdge* edge) {
  for (const int32_t h : mesh.Outgoing(u)) {
    const int32_t f = Mesh::FaceOf(h);
    const int32_t prev = 3 * f + (h % 3 + 2) % 3;  // the half-edge into u in face f
    int32_t corner_v;
    if (mesh.Dest(h) == v) {
      corner_v = (h % 3 + 1) % 3;
    } else if (mesh.Origin(prev) == v) {
      corner_v = prev % 3;
    } else {
      continue;
    }
    const double length = (mesh.position(v) - mesh.position(u)).norm();
    if (length > distance * (1 + kSnap)) return false;
    SurfacePoint from{f, {0, 0, 0}}, to{f, {0, 0, 0}};
    from.w[h % 3] = 1;
    to.w[corner_v] = 1;
    edge->path = {from, to};
    edge->length = length;
    return true;
  }
  return false;
}

}  // namespace

std::vector<std::pair<int32_t, int32_t>> DelaunayEdges(
    std::span<const std::array<int32_t, 3>> triangles) {
  std::vector<std::pair<int32_t, int32_t>> out;
  out.reserve(3 * triangles.size());
  for (const auto& t : triangles) {
    for (int i = 0; i < 3; ++i) {
      const int32_t x = t[i], y = t[(i + 1) % 3];
      out.push_back({std::min(x, y), std::max(x, y)});
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

namespace {

// The samples on referenced mesh vertices, the triangles' corners samples.
absl::Status CheckTraceInput(const Mesh& mesh, std::span<const int32_t> samples,
                             std::span<const std::array<int32_t, 3>> triangles) {
  const int32_t m = static_cast<int32_t>(samples.size());
  for (int32_t a = 0; a < m; ++a) {
    if (samples[a] < 0 || samples[a] >= mesh.num_vertices() || !mesh.IsReferenced(samples[a])) {
      return absl::InvalidArgumentError(
          absl::StrFormat("sample %d at vertex %d is not a mesh vertex", a, samples[a]));
    }
  }
  for (const auto& t : triangles) {
    for (int32_t a : t) {
      if (a < 0 || a >= m) {
        return absl::InvalidArgumentError(
            absl::StrFormat("triangle corner %d out of range [0, %d)", a, m));
      }
    }
  }
  return absl::OkStatus();
}

// Sets `edge`'s path to the one `solver` propagated from its a to `target`,
// its b, and its length to that path's.
absl::Status BacktrackPath(const Mesh& mesh, const geodesic::ExactGeodesicSolver& solver,
                           const SurfacePoint& target, GeodesicEdge& edge) {
  GEODEX_ASSIGN_OR_RETURN(std::vector<SurfacePoint> back, solver.PathTo(target));
  // PathTo runs from b back to a and may give one place twice (a
  // vertex, then the same vertex as the end of a window's interval):
  // keep it once, but measure the length along every point.
  Vec3 last = Vec3::Zero();
  Location last_at;
  for (auto it = back.rbegin(); it != back.rend(); ++it) {
    const Vec3 x = mesh::PositionOf(mesh, *it);
    const Location x_at = Locate(mesh, *it);
    if (!edge.path.empty()) edge.length += (x - last).norm();
    if (edge.path.empty() || !SameLocation(x_at, last_at)) edge.path.push_back(*it);
    last = x;
    last_at = x_at;
  }
  // The last point kept must be b itself.
  edge.path.back() = target;
  return absl::OkStatus();
}

// The edges pairs[i] for i in [begin, end), which all start at one sample,
// from one propagation.
absl::Status TraceFromSource(const Mesh& mesh, std::span<const int32_t> samples,
                             const std::vector<std::pair<int32_t, int32_t>>& pairs, size_t begin,
                             size_t end, geodesic::ExactGeodesicSolver& solver,
                             geodesic::GeodesicOptions& options, std::vector<GeodesicEdge>& edges) {
  const int32_t a = pairs[begin].first;
  options.stop_vertices.clear();
  for (size_t i = begin; i < end; ++i) options.stop_vertices.push_back(samples[pairs[i].second]);
  GEODEX_ASSIGN_OR_RETURN(const SurfacePoint source, mesh::VertexPoint(mesh, samples[a]));
  GEODEX_RETURN_IF_ERROR(solver.Propagate({source}, options));
  for (size_t i = begin; i < end; ++i) {
    const int32_t b = pairs[i].second;
    GeodesicEdge& edge = edges[i];
    edge.a = a;
    edge.b = b;
    edge.distance = solver.VertexDistance(samples[b]);
    if (!(edge.distance < geodesic::kInfinity)) {
      return absl::NotFoundError(
          absl::StrFormat("adjacent samples %d and %d are not connected on the surface", a, b));
    }
    if (MeshEdgePath(mesh, samples[a], samples[b], edge.distance, &edge)) continue;
    GEODEX_ASSIGN_OR_RETURN(const SurfacePoint target, mesh::VertexPoint(mesh, samples[b]));
    GEODEX_RETURN_IF_ERROR(BacktrackPath(mesh, solver, target, edge));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::vector<GeodesicEdge>> TraceEdges(
    const Mesh& mesh, std::span<const int32_t> samples,
    std::span<const std::array<int32_t, 3>> triangles, int threads) {
  GEODEX_RETURN_IF_ERROR(CheckTraceInput(mesh, samples, triangles));
  const std::vector<std::pair<int32_t, int32_t>> pairs = DelaunayEdges(triangles);
  // Pairs are sorted by a: each sample with larger neighbours owns a range.
  std::vector<size_t> begin;
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (i == 0 || pairs[i].first != pairs[i - 1].first) begin.push_back(i);
  }
  const size_t num_sources = begin.size();
  begin.push_back(pairs.size());

  std::vector<GeodesicEdge> edges(pairs.size());
  std::vector<absl::Status> errors(num_sources);
  std::atomic<size_t> next{0};
  auto worker = [&]() {
    geodesic::ExactGeodesicSolver solver(mesh);
    geodesic::GeodesicOptions options;
    for (size_t k; (k = next.fetch_add(1)) < num_sources;) {
      errors[k] =
          TraceFromSource(mesh, samples, pairs, begin[k], begin[k + 1], solver, options, edges);
    }
  };
  const int count = std::min<int>(common::ThreadCount(threads), std::max<size_t>(1, num_sources));
  std::vector<std::thread> pool;
  for (int t = 0; t < count; ++t) pool.emplace_back(worker);
  for (std::thread& t : pool) t.join();
  for (const absl::Status& status : errors) GEODEX_RETURN_IF_ERROR(status);
  return edges;
}

namespace {

int32_t VertexOf(const Location& x) { return x.kind == Location::Kind::kVertex ? x.id : kNone; }

// The distinct places along `edge`'s path, each point checked on the mesh.
absl::StatusOr<std::vector<Location>> PathLocations(const Mesh& mesh, const GeodesicEdge& edge) {
  std::vector<Location> at;
  for (const SurfacePoint& p : edge.path) {
    GEODEX_RETURN_IF_ERROR(mesh::ValidateSurfacePoint(mesh, p));
    const Location x = Locate(mesh, p);
    if (at.empty() || !SameLocation(at.back(), x)) at.push_back(x);
  }
  return at;
}

// Appends the per-face pieces of the path of edge `e`, whose distinct places
// are `at`: a piece per segment and face it runs in, and a point piece per
// face that a point on a mesh edge or vertex touches without a segment.
absl::Status CutPath(const Mesh& mesh, int32_t e, const GeodesicEdge& edge,
                     const std::vector<Location>& at, std::vector<Piece>& pieces) {
  std::vector<int32_t> faces_x, faces_y, common;
  std::vector<std::vector<int32_t>> segment_faces(at.size());  // per point: faces of its segments
  for (size_t i = 0; i + 1 < at.size(); ++i) {
    faces_x.clear();
    faces_y.clear();
    FacesOf(mesh, at[i], &faces_x);
    FacesOf(mesh, at[i + 1], &faces_y);
    std::sort(faces_x.begin(), faces_x.end());
    std::sort(faces_y.begin(), faces_y.end());
    common.clear();
    std::set_intersection(faces_x.begin(), faces_x.end(), faces_y.begin(), faces_y.end(),
                          std::back_inserter(common));
    if (common.empty()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "path of edge (%d, %d): points %d and %d share no face", edge.a, edge.b, i, i + 1));
    }
    // Usually one face; both faces of a mesh edge the path runs along.
    for (const int32_t f : common) {
      pieces.push_back({f, e, WeightsIn(mesh, at[i], f), WeightsIn(mesh, at[i + 1], f),
                        VertexOf(at[i]), VertexOf(at[i + 1])});
      segment_faces[i].push_back(f);
      segment_faces[i + 1].push_back(f);
    }
  }
  // A point on a mesh edge or vertex also touches the faces around it that
  // its own segments do not enter.
  for (size_t i = 0; i < at.size(); ++i) {
    if (at[i].kind == Location::Kind::kFace) continue;
    faces_x.clear();
    FacesOf(mesh, at[i], &faces_x);
    for (const int32_t f : faces_x) {
      const auto& used = segment_faces[i];
      if (std::find(used.begin(), used.end(), f) != used.end()) continue;
      const auto w = WeightsIn(mesh, at[i], f);
      pieces.push_back({f, e, w, w, VertexOf(at[i]), VertexOf(at[i])});
    }
  }
  return absl::OkStatus();
}

// Every path cut into per-face pieces, by face.
absl::StatusOr<std::vector<Piece>> PiecesOf(const Mesh& mesh, int32_t num_samples,
                                            std::span<const GeodesicEdge> edges) {
  const int32_t m = num_samples;
  std::vector<Piece> pieces;
  for (int32_t e = 0; e < static_cast<int32_t>(edges.size()); ++e) {
    const GeodesicEdge& edge = edges[e];
    if (edge.a < 0 || edge.a >= m || edge.b < 0 || edge.b >= m) {
      return absl::InvalidArgumentError(
          absl::StrFormat("edge (%d, %d) has a sample out of range [0, %d)", edge.a, edge.b, m));
    }
    GEODEX_ASSIGN_OR_RETURN(const std::vector<Location> at, PathLocations(mesh, edge));
    GEODEX_RETURN_IF_ERROR(CutPath(mesh, e, edge, at, pieces));
  }
  std::stable_sort(pieces.begin(), pieces.end(),
                   [](const Piece& x, const Piece& y) { return x.face < y.face; });
  return pieces;
}

// Whether two pieces in one face, x0-x1 and y0-y1 in its frame, touch
// closer than `eps`, and where (`meet`); `vs` is the mesh vertex of the
// sample their edges share, or kNone.
bool PiecesTouch(const Piece& px, const Piece& py, const Vec2& x0, const Vec2& x1, const Vec2& y0,
                 const Vec2& y1, int32_t vs, double eps, Vec2* meet) {
  if (vs != kNone && (px.vp == vs || px.vq == vs) && (py.vp == vs || py.vq == vs)) {
    // Both pieces start at the common sample: straight pieces from one
    // point meet again only if they leave it in the same direction, and
    // then the far end of one lies on the other.
    const Vec2 s = px.vp == vs ? x0 : x1;
    const Vec2 xf = px.vp == vs ? x1 : x0;
    const Vec2 yf = py.vp == vs ? y1 : y0;
    if ((xf - s).norm() > eps && (xf - Nearest(xf, y0, y1)).norm() < eps) {
      *meet = xf;
      return true;
    }
    if ((yf - s).norm() > eps && (yf - Nearest(yf, x0, x1)).norm() < eps) {
      *meet = yf;
      return true;
    }
    return false;
  }
  return SegmentsTouch(x0, x1, y0, y1, eps, meet);
}

// Appends to `found` (crossing, order found) where the pieces [i, j) of
// one face, of different edges, touch.
void CrossingsInFace(const Mesh& mesh, std::span<const int32_t> samples,
                     std::span<const GeodesicEdge> edges, std::span<const Piece> pieces,
                     std::vector<std::pair<EdgeCrossing, int64_t>>& found) {
  const int32_t f = pieces.front().face;
  const FaceFrame frame(mesh, f);
  const double eps = kTouchTolerance * frame.size;
  for (size_t x = 0; x < pieces.size(); ++x) {
    const Piece& px = pieces[x];
    const Vec2 x0 = frame.Map(px.p), x1 = frame.Map(px.q);
    for (size_t y = x + 1; y < pieces.size(); ++y) {
      const Piece& py = pieces[y];
      if (py.edge == px.edge) continue;
      const Vec2 y0 = frame.Map(py.p), y1 = frame.Map(py.q);
      const GeodesicEdge& ex = edges[px.edge];
      const GeodesicEdge& ey = edges[py.edge];
      int32_t shared = kNone;
      if (ex.a == ey.a || ex.a == ey.b) shared = ex.a;
      if (ex.b == ey.a || ex.b == ey.b) shared = ex.b;
      const int32_t vs = shared == kNone ? kNone : samples[shared];
      Vec2 meet;
      if (PiecesTouch(px, py, x0, x1, y0, y1, vs, eps, &meet)) {
        EdgeCrossing c;
        c.first = std::min(px.edge, py.edge);
        c.second = std::max(px.edge, py.edge);
        c.point = frame.Unmap(f, meet);
        found.push_back({c, static_cast<int64_t>(found.size())});
      }
    }
  }
}

}  // namespace

absl::StatusOr<std::vector<EdgeCrossing>> FindCrossings(const Mesh& mesh,
                                                        std::span<const int32_t> samples,
                                                        std::span<const GeodesicEdge> edges) {
  // 1. Cut every path into per-face pieces.
  GEODEX_ASSIGN_OR_RETURN(const std::vector<Piece> pieces,
                          PiecesOf(mesh, static_cast<int32_t>(samples.size()), edges));

  // 2. Compare the pieces of different edges face by face.
  std::vector<std::pair<EdgeCrossing, int64_t>> found;  // (crossing, order found)
  for (size_t i = 0; i < pieces.size();) {
    size_t j = i;
    while (j < pieces.size() && pieces[j].face == pieces[i].face) ++j;
    CrossingsInFace(mesh, samples, edges, std::span<const Piece>(pieces).subspan(i, j - i), found);
    i = j;
  }
  // One crossing per pair: the first found (the lowest face).
  std::sort(found.begin(), found.end(), [](const auto& x, const auto& y) {
    return std::tie(x.first.first, x.first.second, x.second) <
           std::tie(y.first.first, y.first.second, y.second);
  });
  std::vector<EdgeCrossing> out;
  for (const auto& [c, order] : found) {
    if (out.empty() || out.back().first != c.first || out.back().second != c.second) {
      out.push_back(c);
    }
  }
  return out;
}

EdgeStats SummarizeEdges(std::span<const GeodesicEdge> edges) {
  EdgeStats stats;
  stats.count = static_cast<int32_t>(edges.size());
  for (const GeodesicEdge& edge : edges) {
    stats.total_length += edge.length;
    stats.longest = std::max(stats.longest, edge.length);
    if (edge.distance > 0) {
      stats.max_relative_error =
          std::max(stats.max_relative_error, std::abs(edge.length - edge.distance) / edge.distance);
    }
  }
  return stats;
}

std::string EdgesToObj(const Mesh& mesh, std::span<const GeodesicEdge> edges) {
  std::string out =
      absl::StrFormat("# geodex: %d geodesic Delaunay edges of %s\n", edges.size(), mesh.name());
  int64_t next = 1;
  for (const GeodesicEdge& edge : edges) {
    absl::StrAppend(&out, "# edge ", edge.a, " ", edge.b, "\n");
    std::string line = "l";
    for (const SurfacePoint& p : edge.path) {
      const Vec3 x = mesh::PositionOf(mesh, p);
      absl::StrAppendFormat(&out, "v %.9g %.9g %.9g\n", x.x(), x.y(), x.z());
      absl::StrAppend(&line, " ", next++);
    }
    absl::StrAppend(&out, line, "\n");
  }
  return out;
}

}  // namespace geodex::triangulation
