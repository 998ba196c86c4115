#include "tests/integration/cgal_reference.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_shortest_path.h>

#include <limits>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace geodex::cgal_reference {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;
using Traits = CGAL::Surface_mesh_shortest_path_traits<Kernel, CgalMesh>;
using ShortestPath = CGAL::Surface_mesh_shortest_path<Traits>;
using VertexIndex = CgalMesh::Vertex_index;
using FaceIndex = CgalMesh::Face_index;

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

struct CgalShortestPaths::Impl {
  const mesh::Mesh& mesh;
  CgalMesh cgal_mesh;
  // geodex vertex id -> CGAL vertex (null for unreferenced vertices), and back.
  std::vector<VertexIndex> to_cgal;
  std::vector<int32_t> from_cgal;
  // geodex face f is CGAL face f: faces are added in order and none is refused.
  std::unique_ptr<ShortestPath> shortest_path;

  explicit Impl(const mesh::Mesh& m) : mesh(m) {}
};

CgalShortestPaths::CgalShortestPaths(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
CgalShortestPaths::~CgalShortestPaths() = default;

absl::StatusOr<std::unique_ptr<CgalShortestPaths>> CgalShortestPaths::Create(
    const mesh::Mesh& mesh) {
  auto impl = std::make_unique<Impl>(mesh);
  impl->to_cgal.assign(mesh.num_vertices(), CgalMesh::null_vertex());
  // Pitfall (3): unreferenced vertices crash CGAL, so they are left out.
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
    if (!mesh.IsReferenced(v)) continue;
    const mesh::Vec3& p = mesh.position(v);
    impl->to_cgal[v] = impl->cgal_mesh.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z()));
    impl->from_cgal.push_back(v);
  }
  for (int32_t f = 0; f < mesh.num_faces(); ++f) {
    const mesh::Triangle& t = mesh.face(f);
    const FaceIndex face =
        impl->cgal_mesh.add_face(impl->to_cgal[t[0]], impl->to_cgal[t[1]], impl->to_cgal[t[2]]);
    if (face == CgalMesh::null_face() || static_cast<int32_t>(face.idx()) != f) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: CGAL Surface_mesh refused face %d (%d, %d, %d)", mesh.name(), f, t[0], t[1], t[2]));
    }
  }
  impl->shortest_path = std::make_unique<ShortestPath>(impl->cgal_mesh);
  return std::unique_ptr<CgalShortestPaths>(new CgalShortestPaths(std::move(impl)));
}

std::array<int32_t, 3> CgalShortestPaths::BarycentricOrder(int32_t f) const {
  // CGAL's coordinate i belongs to the source of the i-th half-edge after
  // halfedge(f) (see Surface_mesh_shortest_paths_3::internal::edge_index and
  // Surface_mesh_shortest_path::face_location(vertex)).
  const CgalMesh& m = impl_->cgal_mesh;
  std::array<int32_t, 3> order;
  auto h = m.halfedge(FaceIndex(static_cast<CgalMesh::size_type>(f)));
  for (int i = 0; i < 3; ++i, h = m.next(h)) {
    order[i] = impl_->from_cgal[m.source(h).idx()];
  }
  return order;
}

int32_t CgalShortestPaths::num_cgal_vertices() const {
  return static_cast<int32_t>(impl_->from_cgal.size());
}

void CgalShortestPaths::Release() { impl_->shortest_path->clear(); }

absl::StatusOr<std::vector<double>> CgalShortestPaths::Distances(const mesh::SurfacePoint& source) {
  const mesh::Mesh& mesh = impl_->mesh;
  if (absl::Status status = mesh::ValidateSurfacePoint(mesh, source, 0.0); !status.ok()) {
    return status;
  }
  const mesh::Triangle& t = mesh.face(source.face);
  int zeros = 0, vertex_corner = -1;
  for (int i = 0; i < 3; ++i) {
    if (source.w[i] == 0) ++zeros;
    if (source.w[i] == 1) vertex_corner = i;
  }
  ShortestPath& sp = *impl_->shortest_path;
  sp.clear();
  if (vertex_corner >= 0) {
    sp.add_source_point(impl_->to_cgal[t[vertex_corner]]);
  } else {
    if (zeros == 1) {
      // Pitfall (1): CGAL mirrors a point on an edge along that edge; only the
      // midpoint is its own mirror image.
      for (int i = 0; i < 3; ++i) {
        if (source.w[i] != 0 && source.w[i] != 0.5) {
          return absl::InvalidArgumentError(absl::StrFormat(
              "source on an edge of face %d at weights (%g, %g, %g): CGAL 5.5.1 misplaces edge "
              "points other than the midpoint",
              source.face, source.w[0], source.w[1], source.w[2]));
        }
      }
    }
    // Pitfall (2): permute our weights (face order) into CGAL's order.
    const std::array<int32_t, 3> order = BarycentricOrder(source.face);
    Traits::Barycentric_coordinates b;
    for (int i = 0; i < 3; ++i) {
      const int corner = order[i] == t[0] ? 0 : order[i] == t[1] ? 1 : 2;
      b[i] = source.w[corner];
    }
    sp.add_source_point(FaceIndex(static_cast<CgalMesh::size_type>(source.face)), b);
  }
  sp.build_sequence_tree();
  std::vector<double> distance(mesh.num_vertices(), kInf);
  for (size_t i = 0; i < impl_->from_cgal.size(); ++i) {
    const double d = sp.shortest_distance_to_source_points(VertexIndex(i)).first;
    // CGAL reports unreachable vertices with a negative distance.
    distance[impl_->from_cgal[i]] = d < 0 ? kInf : d;
  }
  return distance;
}

}  // namespace geodex::cgal_reference
