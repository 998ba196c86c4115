#include "core/mesh/mesh.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <span>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/common/edge_groups.h"
#include "core/common/status_macros.h"

namespace geodex::mesh {
namespace {

// Faces whose doubled area is below this fraction of their longest squared
// edge are degenerate to double precision (collinear corners).
constexpr double kDegenerateAreaRatio = 1e-14;

double CornerAngle(const Vec3& at, const Vec3& a, const Vec3& b) {
  const Vec3 u = a - at;
  const Vec3 w = b - at;
  return std::atan2(u.cross(w).norm(), u.dot(w));
}

int32_t FindRoot(std::vector<int32_t>& parent, int32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

}  // namespace

absl::StatusOr<Mesh> Mesh::Create(std::vector<Vec3> positions, std::vector<Triangle> faces,
                                  std::string name) {
  return Create(std::move(positions), std::move(faces), std::move(name), MeshOptions{});
}

absl::StatusOr<Mesh> Mesh::Create(std::vector<Vec3> positions, std::vector<Triangle> faces,
                                  std::string name, const MeshOptions& options) {
  Mesh mesh;
  mesh.name_ = std::move(name);
  if (faces.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(mesh.name_, ": mesh has no faces"));
  }
  if (positions.size() >= static_cast<size_t>(INT32_MAX) || faces.size() >= INT32_MAX / 3) {
    return absl::InvalidArgumentError(absl::StrCat(mesh.name_, ": mesh too large"));
  }
  for (size_t v = 0; v < positions.size(); ++v) {
    if (!positions[v].allFinite()) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: vertex %d has a non-finite coordinate (%g, %g, %g)", mesh.name_, v,
                          positions[v].x(), positions[v].y(), positions[v].z()));
    }
  }
  const int64_t n = static_cast<int64_t>(positions.size());
  for (size_t f = 0; f < faces.size(); ++f) {
    const Triangle& t = faces[f];
    for (int i = 0; i < 3; ++i) {
      if (t[i] < 0 || t[i] >= n) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "%s: face %d references vertex %d, out of range [0, %d)", mesh.name_, f, t[i], n));
      }
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      return absl::InvalidArgumentError(absl::StrFormat("%s: face %d repeats a vertex (%d %d %d)",
                                                        mesh.name_, f, t[0], t[1], t[2]));
    }
    if (!options.allow_zero_area_faces &&
        IsZeroAreaTriangle(positions[t[0]], positions[t[1]], positions[t[2]])) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: face %d (%d %d %d) has zero area (its corners are collinear or coincide)",
          mesh.name_, f, t[0], t[1], t[2]));
    }
  }
  // Duplicate faces: the same vertex set, in any order.
  {
    std::vector<std::pair<Triangle, int32_t>> sorted(faces.size());
    for (size_t f = 0; f < faces.size(); ++f) {
      Triangle t = faces[f];
      std::sort(t.begin(), t.end());
      sorted[f] = {t, static_cast<int32_t>(f)};
    }
    std::sort(sorted.begin(), sorted.end());
    for (size_t i = 1; i < sorted.size(); ++i) {
      if (sorted[i].first == sorted[i - 1].first) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s: faces %d and %d are duplicates (vertices %d %d %d)", mesh.name_,
                            sorted[i - 1].second, sorted[i].second, sorted[i].first[0],
                            sorted[i].first[1], sorted[i].first[2]));
      }
    }
  }
  mesh.positions_ = std::move(positions);
  mesh.faces_ = std::move(faces);
  GEODEX_RETURN_IF_ERROR(mesh.BuildAdjacency());
  return mesh;
}

namespace {

// Pairs `mesh`'s half-edges by their undirected edge into `twin` (kNone on
// the boundary); returns the number of boundary edges.
absl::StatusOr<int32_t> PairTwins(const Mesh& mesh, const std::string& name,
                                  std::vector<int32_t>& twin) {
  const int32_t nh = 3 * mesh.num_faces();
  twin.assign(nh, kNone);
  int32_t num_boundary_edges = 0;
  auto ends = [&](int32_t h) { return std::pair<int32_t, int32_t>(mesh.Origin(h), mesh.Dest(h)); };
  GEODEX_RETURN_IF_ERROR(
      ForEachEdge(nh, ends, [&](std::span<const int32_t> group, int64_t a, int64_t b) {
        if (group.size() > 2) {
          std::string list;
          for (size_t k = 0; k < group.size(); ++k)
            absl::StrAppend(&list, k > 0 ? ", " : "", Mesh::FaceOf(group[k]));
          return absl::InvalidArgumentError(
              absl::StrFormat("%s: non-manifold edge (%d, %d) is shared by %d faces (%s)", name, a,
                              b, group.size(), list));
        }
        if (group.size() == 2) {
          const int32_t h0 = group[0], h1 = group[1];
          if (mesh.Origin(h0) == mesh.Origin(h1)) {
            return absl::InvalidArgumentError(absl::StrFormat(
                "%s: faces %d and %d traverse edge (%d, %d) in the same direction (inconsistent "
                "orientation or a non-orientable surface)",
                name, Mesh::FaceOf(h0), Mesh::FaceOf(h1), a, b));
          }
          twin[h0] = h1;
          twin[h1] = h0;
        } else {
          ++num_boundary_edges;
        }
        return absl::OkStatus();
      }));
  return num_boundary_edges;
}

// The outgoing half-edges of each vertex v, outgoing[offset[v], offset[v +
// 1]), in counter-clockwise order round v; whether v is on the boundary;
// the sum of its corners' angles.
struct Fans {
  std::vector<int32_t> offset;
  std::vector<int32_t> outgoing;
  std::vector<uint8_t> is_boundary;
  std::vector<double> angle_sum;
};

// Orders the fan of vertex v, whose outgoing half-edges are `unordered`
// [begin, end), into `fans` (its twins paired).
absl::Status OrderFan(const Mesh& mesh, const std::string& name,
                      const std::vector<int32_t>& unordered, int32_t v, Fans& fans) {
  const int32_t begin = fans.offset[v], end = fans.offset[v + 1];
  if (begin == end) return absl::OkStatus();
  // Start at a half-edge with no clockwise neighbour (a boundary), if any.
  int32_t start = unordered[begin];
  for (int32_t k = begin; k < end; ++k) {
    if (mesh.Twin(unordered[k]) == kNone) {
      start = unordered[k];
      fans.is_boundary[v] = 1;
      break;
    }
  }
  int32_t count = 0;
  int32_t h = start;
  do {
    fans.outgoing[begin + count++] = h;
    const int32_t back = mesh.Twin(Mesh::Prev(h));  // counter-clockwise neighbour
    if (back == kNone) {
      fans.is_boundary[v] = 1;
      break;
    }
    h = back;
  } while (h != start && count < end - begin);
  if (count != end - begin) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: non-manifold vertex %d: its %d faces form more than one fan", name, v, end - begin));
  }
  for (int32_t k = begin; k < end; ++k) {
    const int32_t o = fans.outgoing[k];
    fans.angle_sum[v] +=
        CornerAngle(mesh.position(v), mesh.position(mesh.Dest(o)), mesh.position(mesh.Opposite(o)));
  }
  return absl::OkStatus();
}

// Outgoing half-edges per vertex, then each fan ordered counter-clockwise.
absl::StatusOr<Fans> OrderFans(const Mesh& mesh, const std::string& name) {
  const int32_t nv = mesh.num_vertices();
  const int32_t nh = 3 * mesh.num_faces();
  Fans fans;
  fans.offset.assign(nv + 1, 0);
  for (int32_t h = 0; h < nh; ++h) ++fans.offset[mesh.Origin(h) + 1];
  for (int32_t v = 0; v < nv; ++v) fans.offset[v + 1] += fans.offset[v];
  std::vector<int32_t> unordered(nh);
  {
    std::vector<int32_t> fill(fans.offset.begin(), fans.offset.end() - 1);
    for (int32_t h = 0; h < nh; ++h) unordered[fill[mesh.Origin(h)]++] = h;
  }
  fans.outgoing.assign(nh, kNone);
  fans.is_boundary.assign(nv, 0);
  fans.angle_sum.assign(nv, 0.0);
  for (int32_t v = 0; v < nv; ++v) {
    GEODEX_RETURN_IF_ERROR(OrderFan(mesh, name, unordered, v, fans));
  }
  return fans;
}

// Labels the connected components over faces, in order of their first
// face, in `face_component` and `vertex_component`; returns their number.
int32_t LabelComponents(const Mesh& mesh, std::vector<int32_t>& face_component,
                        std::vector<int32_t>& vertex_component) {
  const int32_t nf = mesh.num_faces();
  const int32_t nh = 3 * nf;
  std::vector<int32_t> parent(nf);
  std::iota(parent.begin(), parent.end(), 0);
  for (int32_t h = 0; h < nh; ++h) {
    if (mesh.Twin(h) == kNone) continue;
    const int32_t a = FindRoot(parent, Mesh::FaceOf(h));
    const int32_t b = FindRoot(parent, Mesh::FaceOf(mesh.Twin(h)));
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
  face_component.assign(nf, kNone);
  std::vector<int32_t> root_id(nf, kNone);
  int32_t num_components = 0;
  for (int32_t f = 0; f < nf; ++f) {
    const int32_t r = FindRoot(parent, f);
    if (root_id[r] == kNone) root_id[r] = num_components++;
    face_component[f] = root_id[r];
  }
  vertex_component.assign(mesh.num_vertices(), kNone);
  for (int32_t f = 0; f < nf; ++f) {
    for (int32_t v : mesh.face(f)) vertex_component[v] = face_component[f];
  }
  return num_components;
}

}  // namespace

absl::Status Mesh::BuildAdjacency() {
  const int32_t nh = 3 * num_faces();
  length_.resize(nh);
  for (int32_t h = 0; h < nh; ++h) length_[h] = (position(Dest(h)) - position(Origin(h))).norm();

  // Pair half-edges by their undirected edge.
  GEODEX_ASSIGN_OR_RETURN(num_boundary_edges_, PairTwins(*this, name_, twin_));
  GEODEX_ASSIGN_OR_RETURN(Fans fans, OrderFans(*this, name_));
  outgoing_offset_ = std::move(fans.offset);
  outgoing_ = std::move(fans.outgoing);
  is_boundary_ = std::move(fans.is_boundary);
  angle_sum_ = std::move(fans.angle_sum);
  // Connected components over faces.
  num_components_ = LabelComponents(*this, face_component_, vertex_component_);
  return absl::OkStatus();
}

double Mesh::Area(int32_t f) const {
  const Triangle& t = faces_[f];
  return 0.5 *
         (positions_[t[1]] - positions_[t[0]]).cross(positions_[t[2]] - positions_[t[0]]).norm();
}

double Mesh::TotalArea() const {
  double total = 0;
  for (int32_t f = 0; f < num_faces(); ++f) total += Area(f);
  return total;
}

Vec3 Mesh::BoundingBoxMin() const {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  for (int32_t v = 0; v < num_vertices(); ++v) {
    if (IsReferenced(v)) lo = lo.cwiseMin(positions_[v]);
  }
  return lo;
}

Vec3 Mesh::BoundingBoxMax() const {
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());
  for (int32_t v = 0; v < num_vertices(); ++v) {
    if (IsReferenced(v)) hi = hi.cwiseMax(positions_[v]);
  }
  return hi;
}

double Mesh::BoundingBoxDiagonal() const { return (BoundingBoxMax() - BoundingBoxMin()).norm(); }

bool IsZeroAreaTriangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double twice_area = (b - a).cross(c - a).norm();
  const double longest2 =
      std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  return !(twice_area > kDegenerateAreaRatio * longest2);
}

Vec3 PositionOf(const Mesh& mesh, const SurfacePoint& p) {
  const Triangle& t = mesh.face(p.face);
  return p.w[0] * mesh.position(t[0]) + p.w[1] * mesh.position(t[1]) + p.w[2] * mesh.position(t[2]);
}

absl::Status ValidateSurfacePoint(const Mesh& mesh, const SurfacePoint& p, double tolerance) {
  return ValidateSurfacePoint(mesh.num_faces(), p, tolerance);
}

absl::Status ValidateSurfacePoint(int32_t num_faces, const SurfacePoint& p, double tolerance) {
  if (p.face < 0 || p.face >= num_faces) {
    return absl::OutOfRangeError(
        absl::StrFormat("face id %d out of range [0, %d)", p.face, num_faces));
  }
  double sum = 0;
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(p.w[i])) {
      return absl::InvalidArgumentError(
          absl::StrFormat("barycentric weight %d of face %d is not finite", i, p.face));
    }
    if (p.w[i] < -tolerance) {
      return absl::InvalidArgumentError(
          absl::StrFormat("barycentric weight %d of face %d is negative (%g)", i, p.face, p.w[i]));
    }
    sum += p.w[i];
  }
  if (std::abs(sum - 1.0) > tolerance) {
    return absl::InvalidArgumentError(
        absl::StrFormat("barycentric weights of face %d sum to %.17g, not 1 (tolerance %g)", p.face,
                        sum, tolerance));
  }
  return absl::OkStatus();
}

absl::StatusOr<SurfacePoint> VertexPoint(const Mesh& mesh, int32_t v) {
  if (v < 0 || v >= mesh.num_vertices()) {
    return absl::OutOfRangeError(
        absl::StrFormat("vertex id %d out of range [0, %d)", v, mesh.num_vertices()));
  }
  if (!mesh.IsReferenced(v)) {
    return absl::FailedPreconditionError(
        absl::StrFormat("vertex %d is not referenced by any face", v));
  }
  const int32_t h = mesh.Outgoing(v)[0];
  SurfacePoint p;
  p.face = Mesh::FaceOf(h);
  p.w = {0, 0, 0};
  p.w[h % 3] = 1.0;
  return p;
}

bool TouchesZeroLengthEdge(const Mesh& mesh, int32_t v) {
  for (const int32_t o : mesh.Outgoing(v)) {
    if (!(mesh.Length(o) > 0) || !(mesh.Length(Mesh::Prev(o)) > 0)) return true;
  }
  return false;
}

}  // namespace geodex::mesh
