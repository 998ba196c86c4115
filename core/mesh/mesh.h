#pragma once

// An immutable, validated, indexed triangle mesh with the half-edge adjacency
// that exact geodesic propagation needs.
//
// Ids: vertex ids and triangle ids are those of the input. A triangle is face
// `f`; its half-edges are `3f`, `3f+1`, `3f+2`, where half-edge `3f+i` runs
// from `face(f)[i]` to `face(f)[(i+1)%3]`. `Twin(h)` is the half-edge of the
// neighbouring face on the same edge, or `kNone` on a boundary.
//
// Valid input: unreferenced vertices, boundaries, several connected components.
// Rejected (InvalidArgument, naming the element): fewer than one face, indices
// out of range or repeated within a face, NaN/Inf coordinates, faces of zero
// area (unless MeshOptions::allow_zero_area_faces), duplicate faces, edges
// with more than two faces or whose two faces disagree on orientation, and
// non-manifold vertices (faces around a vertex that do not form a single
// fan). core/mesh/mesh_repair.h repairs what can be repaired of these.
//
// Thread safety: immutable after construction; every method is const and safe
// to call from any number of threads.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "Eigen/Geometry"
#include "absl/status/statusor.h"

namespace geodex::mesh {

using Vec3 = Eigen::Vector3d;
using Triangle = std::array<int32_t, 3>;

inline constexpr int32_t kNone = -1;

struct MeshOptions {
  // Keep faces of zero area (collinear corners) instead of refusing them:
  // the repaired meshes of core/mesh/mesh_repair.h, and meshes rebuilt from
  // an index made of one. Such a face has angles 0, 0 and pi (or 0 for
  // coincident corners) and an area of 0; it joins its neighbours as any
  // face does.
  bool allow_zero_area_faces = false;
};

class Mesh {
 public:
  // Builds a mesh from vertex positions and triangles. `name` is used in error
  // messages (usually the file name). Errors: InvalidArgument as listed above.
  static absl::StatusOr<Mesh> Create(std::vector<Vec3> positions, std::vector<Triangle> faces,
                                     std::string name = "mesh");
  static absl::StatusOr<Mesh> Create(std::vector<Vec3> positions, std::vector<Triangle> faces,
                                     std::string name, const MeshOptions& options);

  Mesh(const Mesh&) = default;
  Mesh(Mesh&&) = default;
  Mesh& operator=(const Mesh&) = default;
  Mesh& operator=(Mesh&&) = default;

  int32_t num_vertices() const { return static_cast<int32_t>(positions_.size()); }
  int32_t num_faces() const { return static_cast<int32_t>(faces_.size()); }
  int32_t num_halfedges() const { return 3 * num_faces(); }
  const std::string& name() const { return name_; }

  const Vec3& position(int32_t v) const { return positions_[v]; }
  const std::vector<Vec3>& positions() const { return positions_; }
  const Triangle& face(int32_t f) const { return faces_[f]; }
  const std::vector<Triangle>& faces() const { return faces_; }

  // Half-edge navigation.
  static int32_t FaceOf(int32_t h) { return h / 3; }
  static int32_t Next(int32_t h) { return h - h % 3 + (h % 3 + 1) % 3; }
  static int32_t Prev(int32_t h) { return h - h % 3 + (h % 3 + 2) % 3; }
  int32_t Origin(int32_t h) const { return faces_[h / 3][h % 3]; }
  int32_t Dest(int32_t h) const { return faces_[h / 3][(h % 3 + 1) % 3]; }
  // The vertex of FaceOf(h) opposite to h.
  int32_t Opposite(int32_t h) const { return faces_[h / 3][(h % 3 + 2) % 3]; }
  int32_t Twin(int32_t h) const { return twin_[h]; }
  double Length(int32_t h) const { return length_[h]; }

  // Outgoing half-edges of `v` (one per incident face: the half-edge of that
  // face whose origin is `v`), in counter-clockwise fan order; for a boundary
  // vertex the fan starts at the boundary. Empty for unreferenced vertices.
  std::span<const int32_t> Outgoing(int32_t v) const {
    return {outgoing_.data() + outgoing_offset_[v], outgoing_.data() + outgoing_offset_[v + 1]};
  }

  bool IsBoundaryVertex(int32_t v) const { return is_boundary_[v] != 0; }
  bool IsReferenced(int32_t v) const { return outgoing_offset_[v + 1] > outgoing_offset_[v]; }
  // Sum of the interior angles at `v` over its incident faces, radians.
  double AngleSum(int32_t v) const { return angle_sum_[v]; }

  // Connected component of each face / vertex (unreferenced vertices: kNone).
  int32_t num_components() const { return num_components_; }
  int32_t FaceComponent(int32_t f) const { return face_component_[f]; }
  int32_t VertexComponent(int32_t v) const { return vertex_component_[v]; }

  double Area(int32_t f) const;
  double TotalArea() const;
  // Length of the bounding-box diagonal.
  double BoundingBoxDiagonal() const;
  Vec3 BoundingBoxMin() const;
  Vec3 BoundingBoxMax() const;
  int32_t num_boundary_edges() const { return num_boundary_edges_; }

 private:
  Mesh() = default;
  absl::Status BuildAdjacency();

  std::string name_;
  std::vector<Vec3> positions_;
  std::vector<Triangle> faces_;
  std::vector<int32_t> twin_;
  std::vector<double> length_;
  std::vector<int32_t> outgoing_offset_;
  std::vector<int32_t> outgoing_;
  std::vector<uint8_t> is_boundary_;
  std::vector<double> angle_sum_;
  std::vector<int32_t> face_component_;
  std::vector<int32_t> vertex_component_;
  int32_t num_components_ = 0;
  int32_t num_boundary_edges_ = 0;
};

// A point on the surface: a face id and barycentric weights of the face's three
// vertices in face order (w[0] for face(f)[0], ...). Weights are >= 0 and sum
// to 1 for a valid point.
struct SurfacePoint {
  int32_t face = kNone;
  std::array<double, 3> w = {1.0, 0.0, 0.0};
};

// True when a triangle's doubled area is below 1e-14 of its longest squared
// edge: degenerate to double precision (collinear or coincident corners).
// The test Mesh::Create refuses zero-area faces by.
bool IsZeroAreaTriangle(const Vec3& a, const Vec3& b, const Vec3& c);

// Position of a surface point in 3D.
Vec3 PositionOf(const Mesh& mesh, const SurfacePoint& p);

// Checks face range, finiteness, non-negativity (>= -tolerance) and that the
// weights sum to 1 within `tolerance`. Errors: OutOfRange for a bad face id,
// InvalidArgument otherwise; messages name the offending value.
absl::Status ValidateSurfacePoint(const Mesh& mesh, const SurfacePoint& p, double tolerance = 1e-6);
// The same checks against a face count, for holders of a mesh's arrays
// without a Mesh (a loaded index).
absl::Status ValidateSurfacePoint(int32_t num_faces, const SurfacePoint& p,
                                  double tolerance = 1e-6);

// The surface point at vertex `v` (in its first incident face). Errors:
// OutOfRange for a bad id, FailedPrecondition for an unreferenced vertex.
absl::StatusOr<SurfacePoint> VertexPoint(const Mesh& mesh, int32_t v);

// Whether `v` is an end of an edge of length 0 (two corners at one position,
// which mesh repair keeps).
bool TouchesZeroLengthEdge(const Mesh& mesh, int32_t v);

}  // namespace geodex::mesh
