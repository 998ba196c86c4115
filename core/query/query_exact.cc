// QueryEngine's exact refinement: the mesh rebuilt from the index on first
// use, the per-scratch exact solver over it, and the local propagations the
// near-pair modes and the exponential map run.

#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/query/query_engine.h"

namespace geodex::query {

const mesh::Mesh* QueryEngine::ExactMesh() const {
  std::call_once(mesh_once_, [this] {
    const index::Index& ix = *index_;
    std::vector<mesh::Vec3> positions(ix.num_vertices());
    for (int32_t v = 0; v < ix.num_vertices(); ++v) positions[v] = view_.Position(v);
    std::vector<mesh::Triangle> faces(ix.num_faces());
    for (int32_t f = 0; f < ix.num_faces(); ++f) {
      faces[f] = {ix.faces()[3 * f], ix.faces()[3 * f + 1], ix.faces()[3 * f + 2]};
    }
    // The index was made from a valid mesh, repaired ones with their
    // zero-area faces; a failure here leaves exact refinement off (the
    // callers fall back to the other answers).
    mesh::MeshOptions mesh_options;
    mesh_options.allow_zero_area_faces = true;
    absl::StatusOr<mesh::Mesh> m =
        mesh::Mesh::Create(std::move(positions), std::move(faces), "index", mesh_options);
    if (m.ok()) mesh_ = std::make_unique<mesh::Mesh>(*std::move(m));
  });
  return mesh_.get();
}

geodesic::ExactGeodesicSolver* QueryEngine::ExactSolver(QueryScratch& scratch) const {
  const mesh::Mesh* m = ExactMesh();
  if (m == nullptr) return nullptr;
  if (scratch.solver_ == nullptr || scratch.mesh_ != m) {
    scratch.solver_ = std::make_unique<geodesic::ExactGeodesicSolver>(*m);
    scratch.mesh_ = m;
  }
  return scratch.solver_.get();
}

std::optional<double> QueryEngine::ExactNearDistance(const SurfacePoint& from,
                                                     const SurfacePoint& to,
                                                     QueryScratch* scratch) const {
  QueryScratch local;
  geodesic::ExactGeodesicSolver* solver = ExactSolver(scratch != nullptr ? *scratch : local);
  if (solver == nullptr) return std::nullopt;
  geodesic::GeodesicOptions options;
  options.stop_points = {to};
  if (!solver->Propagate({from}, options).ok()) return std::nullopt;
  return solver->DistanceAt(to);
}

absl::StatusOr<std::span<const double>> QueryEngine::LocalExactDistances(
    const SurfacePoint& p, double radius, QueryScratch& scratch) const {
  GEODEX_RETURN_IF_ERROR(Validate(p));
  if (!(radius >= 0)) {
    return absl::InvalidArgumentError(absl::StrFormat("the radius must be >= 0, got %g", radius));
  }
  geodesic::ExactGeodesicSolver* solver = ExactSolver(scratch);
  if (solver == nullptr) {
    return absl::InternalError("the index's mesh cannot be rebuilt for exact propagation");
  }
  geodesic::GeodesicOptions options;
  options.stop_radius = radius;
  GEODEX_RETURN_IF_ERROR(solver->Propagate({Canonical(p)}, options));
  return std::span<const double>(solver->VertexDistances());
}

}  // namespace geodex::query
