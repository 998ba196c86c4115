#include "core/query/engine/internal/exact/local_exact.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <span>
#include <unordered_map>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex::query {

LocalExact::LocalExact(const index::Index& index, const MeshView& view)
    : index_(&index), view_(view) {}

LocalExact::~LocalExact() = default;

const mesh::Mesh* LocalExact::ExactMesh() const {
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

const mesh::Mesh* LocalExact::CoarseMesh() const {
  std::call_once(coarse_once_, [this] {
    const index::Index& ix = *index_;
    if (!ix.split().split()) return;
    std::vector<mesh::Vec3> positions(ix.num_vertices());
    for (int32_t v = 0; v < ix.num_vertices(); ++v) positions[v] = view_.Position(v);
    absl::StatusOr<mesh::Mesh> coarse =
        index::CoarseMeshOf(positions, ix.split(), ix.split_vertices(), "coarse");
    // Index::Open checked the split: a failure here leaves the pairs'
    // propagations on the index's mesh, where they give the same distances.
    if (coarse.ok()) coarse_ = std::make_unique<mesh::Mesh>(*std::move(coarse));
  });
  return coarse_.get();
}

namespace {

ExactSolvers* SolversOver(const mesh::Mesh& m, ExactSolvers& s) {
  if (s.exact == nullptr || s.mesh != &m) {
    s.confined.reset();  // it borrows the solver replaced here
    s.exact = std::make_unique<geodesic::ExactGeodesicSolver>(m);
    s.mesh = &m;
  }
  return &s;
}

}  // namespace

ExactSolvers* LocalExact::Solvers(QueryScratch& scratch) const {
  const mesh::Mesh* m = ExactMesh();
  return m == nullptr ? nullptr : SolversOver(*m, scratch.solvers().index_mesh);
}

ExactSolvers* LocalExact::PairSolvers(QueryScratch& scratch, bool* coarse) const {
  const mesh::Mesh* c = CoarseMesh();
  *coarse = c != nullptr;
  return c != nullptr ? SolversOver(*c, scratch.solvers().coarse) : Solvers(scratch);
}

SurfacePoint LocalExact::ToCoarse(const SurfacePoint& p) const {
  const index::SplitFaceRecord r = index_->split().Piece(p.face);
  SurfacePoint coarse{r.coarse_face, {0, 0, 0}};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) coarse.w[j] += p.w[i] * r.weight[i][j];
  }
  return coarse;
}

std::optional<double> LocalExact::NearDistance(const SurfacePoint& from, const SurfacePoint& to,
                                               QueryScratch* scratch) const {
  QueryScratch local;
  bool coarse = false;
  ExactSolvers* s = PairSolvers(scratch != nullptr ? *scratch : local, &coarse);
  if (s == nullptr) return std::nullopt;
  const SurfacePoint a = coarse ? ToCoarse(from) : from, b = coarse ? ToCoarse(to) : to;
  geodesic::GeodesicOptions options;
  options.stop_points = {b};
  if (!s->exact->Propagate({a}, options).ok()) return std::nullopt;
  return s->exact->DistanceAt(b);
}

std::optional<double> LocalExact::ConfinedDistance(const SurfacePoint& from, const SurfacePoint& to,
                                                   std::span<const int32_t> seed_faces,
                                                   QueryScratch& scratch,
                                                   double upper_bound) const {
  bool coarse = false;
  ExactSolvers* s = PairSolvers(scratch, &coarse);
  if (s == nullptr) return std::nullopt;
  if (s->confined == nullptr) {
    s->confined = std::make_unique<geodesic::ConfinedGeodesicSolver>(*s->exact);
  }
  scratch.solvers().last_confined = s->confined.get();
  if (!coarse) {
    const absl::StatusOr<double> d = s->confined->Distance(from, to, seed_faces, upper_bound);
    return d.ok() ? std::optional<double>(*d) : std::nullopt;
  }
  // The seeds' coarse faces, each once, in the order the seeds reach them.
  std::vector<int32_t>& seeds = scratch.solvers().coarse_seeds;
  seeds.clear();
  for (const int32_t f : seed_faces) {
    const int32_t c = index_->split().Piece(f).coarse_face;
    if (std::find(seeds.begin(), seeds.end(), c) == seeds.end()) seeds.push_back(c);
  }
  const absl::StatusOr<double> d =
      s->confined->Distance(ToCoarse(from), ToCoarse(to), seeds, upper_bound);
  return d.ok() ? std::optional<double>(*d) : std::nullopt;
}

absl::StatusOr<std::span<const double>> LocalExact::Distances(const SurfacePoint& p, double radius,
                                                              QueryScratch& scratch) const {
  if (!(radius >= 0)) {
    return absl::InvalidArgumentError(absl::StrFormat("the radius must be >= 0, got %g", radius));
  }
  ExactSolvers* solvers = Solvers(scratch);
  geodesic::ExactGeodesicSolver* solver = solvers != nullptr ? solvers->exact.get() : nullptr;
  if (solver == nullptr) {
    return absl::InternalError("the index's mesh cannot be rebuilt for exact propagation");
  }
  geodesic::GeodesicOptions options;
  options.stop_radius = radius;
  GEODEX_RETURN_IF_ERROR(solver->Propagate({p}, options));
  return std::span<const double>(solver->VertexDistances());
}

absl::StatusOr<RadiusField> LocalExact::DistancesWithin(std::span<const SurfacePoint> sources,
                                                        double radius, int64_t max_vertices,
                                                        QueryScratch& scratch) const {
  if (!(std::isfinite(radius) && radius > 0)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("the radius must be finite and > 0, got %g", radius));
  }
  if (sources.empty()) return absl::InvalidArgumentError("no sources given");
  ExactSolvers* solvers = Solvers(scratch);
  geodesic::ExactGeodesicSolver* solver = solvers != nullptr ? solvers->exact.get() : nullptr;
  if (solver == nullptr) {
    return absl::InternalError("the index's mesh cannot be rebuilt for exact propagation");
  }
  geodesic::GeodesicOptions options;
  options.stop_radius = radius;
  options.max_vertices = max_vertices;
  if (absl::Status status = solver->Propagate(sources, options); !status.ok()) {
    if (max_vertices > 0 && absl::IsResourceExhausted(status) &&
        static_cast<int64_t>(solver->ReachedVertices().size()) > max_vertices) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "the field within radius %g reaches more than %d vertices", radius, max_vertices));
    }
    // The solver's window budget: a safety net against pathological meshes,
    // not a limit of the request (ResourceExhausted stays the vertex cap's).
    if (absl::IsResourceExhausted(status)) return absl::InternalError(status.message());
    return status;
  }
  // Vertices past the radius were reached too, with upper bounds: within it,
  // every distance is final (all the work closer than the radius was done).
  std::vector<int32_t> within;
  for (const int32_t v : solver->ReachedVertices()) {
    if (solver->VertexDistance(v) <= radius) within.push_back(v);
  }
  std::sort(within.begin(), within.end());
  RadiusField field;
  field.vertices = std::move(within);
  field.distance.reserve(field.vertices.size());
  field.nearest.reserve(field.vertices.size());
  for (const int32_t v : field.vertices) {
    field.distance.push_back(solver->VertexDistance(v));
    field.nearest.push_back(solver->NearestSource(v));
  }
  return field;
}

absl::StatusOr<std::vector<PathPoint>> LocalExact::CorridorPath(const std::vector<PathPoint>& path,
                                                                int32_t steps) const {
  // The corridor: the faces the path touches, grown across edges.
  std::vector<int32_t> faces;
  std::unordered_map<int32_t, int32_t> local_face;
  for (const PathPoint& p : path) {
    if (local_face.try_emplace(p.point.face, faces.size()).second) faces.push_back(p.point.face);
  }
  for (size_t begin = 0, step = 0; step < static_cast<size_t>(steps); ++step) {
    const size_t end = faces.size();
    for (size_t i = begin; i < end; ++i) {
      for (int k = 0; k < 3; ++k) {
        const int32_t twin = view_.twins[3 * faces[i] + k];
        if (twin < 0) continue;
        const int32_t g = twin / 3;
        if (local_face.try_emplace(g, faces.size()).second) faces.push_back(g);
      }
    }
    begin = end;
  }
  // A vertex whose corridor faces form more than one fan would make the
  // corridor non-manifold: such vertices get their whole star, until there
  // are none.
  for (bool pinched = true; pinched;) {
    pinched = false;
    std::unordered_map<int32_t, int32_t> a_face_of;  // corridor vertex -> a corridor face
    for (int32_t f : faces) {
      for (int k = 0; k < 3; ++k) a_face_of.try_emplace(view_.faces[3 * f + k], f);
    }
    for (const auto& [v, f] : a_face_of) {
      std::vector<int32_t> star;
      view_.FacesAround(v, f, &star);
      int fan_ends = 0;
      for (int32_t g : star) {
        if (!local_face.contains(g)) continue;
        const int32_t h = 3 * g + view_.Corner(g, v);  // the edge leaving v in g
        fan_ends += view_.twins[h] < 0 || !local_face.contains(view_.twins[h] / 3);
      }
      if (fan_ends <= 1) continue;
      pinched = true;
      for (int32_t g : star) {
        if (local_face.try_emplace(g, faces.size()).second) faces.push_back(g);
      }
    }
  }
  // As a mesh of its own, vertex order kept in every face.
  std::unordered_map<int32_t, int32_t> local_vertex;
  std::vector<mesh::Vec3> positions;
  std::vector<mesh::Triangle> triangles;
  for (int32_t f : faces) {
    mesh::Triangle t;
    for (int k = 0; k < 3; ++k) {
      const int32_t v = view_.faces[3 * f + k];
      auto [it, added] = local_vertex.try_emplace(v, positions.size());
      if (added) positions.push_back(view_.Position(v));
      t[k] = it->second;
    }
    triangles.push_back(t);
  }
  mesh::MeshOptions mesh_options;
  mesh_options.allow_zero_area_faces = true;  // as in the index's mesh
  GEODEX_ASSIGN_OR_RETURN(const mesh::Mesh corridor,
                          mesh::Mesh::Create(std::move(positions), std::move(triangles),
                                             "path corridor", mesh_options));
  auto local = [&](const SurfacePoint& p) { return SurfacePoint{local_face.at(p.face), p.w}; };
  const SurfacePoint from = local(path.front().point), to = local(path.back().point);
  geodesic::ExactGeodesicSolver solver(corridor);
  geodesic::GeodesicOptions options;
  options.stop_points = {to};
  GEODEX_RETURN_IF_ERROR(solver.Propagate({from}, options));
  GEODEX_ASSIGN_OR_RETURN(const std::vector<SurfacePoint> back, solver.PathTo(to));
  std::vector<PathPoint> out;
  for (auto it = back.rbegin(); it != back.rend(); ++it) {
    const SurfacePoint p{faces[it->face], it->w};
    out.push_back({p, view_.PositionOf(p)});
  }
  return out;
}

}  // namespace geodex::query
