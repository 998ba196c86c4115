#include "core/query/input_queries.h"

#include <algorithm>
#include <array>
#include <unordered_map>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/query/engine/input_ids.h"
#include "core/query/engine/query_engine.h"

namespace geodex::query {

PointName Named(std::string_view name) {
  return [name = std::string(name)](size_t i) { return absl::StrFormat("%s[%d]", name, i); };
}

absl::StatusOr<std::shared_ptr<const InputQueries>> InputQueries::Open(const std::string& path,
                                                                       QueryOptions options) {
  GEODEX_ASSIGN_OR_RETURN(std::shared_ptr<const index::Index> index, index::Index::Open(path));
  return Create(std::move(index), options);
}

absl::StatusOr<std::shared_ptr<const InputQueries>> InputQueries::Create(
    std::shared_ptr<const index::Index> index, QueryOptions options) {
  GEODEX_ASSIGN_OR_RETURN(std::shared_ptr<const QueryEngine> engine,
                          QueryEngine::Create(std::move(index), options));
  return Create(std::move(engine));
}

absl::StatusOr<std::shared_ptr<const InputQueries>> InputQueries::Create(
    std::shared_ptr<const QueryEngine> engine) {
  if (engine == nullptr) return absl::InvalidArgumentError("no engine");
  return std::shared_ptr<const InputQueries>(new InputQueries(std::move(engine)));
}

InputQueries::InputQueries(std::shared_ptr<const QueryEngine> engine)
    : engine_(std::move(engine)), ids_(std::make_unique<const InputIds>(engine_->index())) {}

InputQueries::~InputQueries() = default;

int32_t InputQueries::num_vertices() const { return ids_->num_input_vertices(); }
int32_t InputQueries::num_faces() const { return ids_->num_input_faces(); }
bool InputQueries::identity() const { return ids_->identity(); }
mesh::Triangle InputQueries::InputFace(int32_t f) const { return ids_->InputFace(f); }
int32_t InputQueries::InputVertex(int32_t internal_vertex) const {
  return ids_->InputVertex(internal_vertex);
}

const index::Index& InputQueries::index() const { return engine_->index(); }
const QueryEngine& InputQueries::engine() const { return *engine_; }
const InputIds& InputQueries::ids() const { return *ids_; }
const QueryOptions& InputQueries::options() const { return engine_->options(); }
bool InputQueries::has_error_bounds() const { return engine_->has_error_bounds(); }
double InputQueries::scale_length() const { return engine_->scale_length(); }

namespace {

// `status` with the point's name in front, when it has one.
absl::Status Prefixed(const absl::Status& status, const PointName& name, size_t i) {
  const std::string prefix = name ? name(i) : std::string();
  if (prefix.empty()) return status;
  return absl::Status(status.code(), absl::StrFormat("%s: %s", prefix, status.message()));
}

}  // namespace

absl::Status InputQueries::Read(std::span<const SurfacePoint> input, const PointName& name,
                                EnginePoints* out) const {
  out->points_.resize(input.size());
  out->input_faces_.resize(input.size());
  const double tolerance = engine_->options().weight_tolerance;
  for (size_t i = 0; i < input.size(); ++i) {
    absl::StatusOr<SurfacePoint> internal = ids_->ToInternal(input[i], tolerance);
    if (!internal.ok()) return Prefixed(internal.status(), name, i);
    out->points_[i] = *internal;
    out->input_faces_[i] = input[i].face;
  }
  return absl::OkStatus();
}

absl::Status InputQueries::Read(std::span<const int32_t> faces, std::span<const double> weights,
                                const PointName& name, EnginePoints* out) const {
  if (weights.size() != 3 * faces.size()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%d points but %d weights (want %d)", faces.size(), weights.size(), 3 * faces.size()));
  }
  out->points_.resize(faces.size());
  out->input_faces_.assign(faces.begin(), faces.end());
  const double tolerance = engine_->options().weight_tolerance;
  for (size_t i = 0; i < faces.size(); ++i) {
    absl::StatusOr<SurfacePoint> internal = ids_->ToInternal(
        {faces[i], {weights[3 * i], weights[3 * i + 1], weights[3 * i + 2]}}, tolerance);
    if (!internal.ok()) return Prefixed(internal.status(), name, i);
    out->points_[i] = *internal;
  }
  return absl::OkStatus();
}

absl::Status InputQueries::Read(std::span<const int32_t> faces, std::span<const double> weights,
                                std::span<const int32_t> vertices, const PointName& name,
                                EnginePoints* out) const {
  if (vertices.empty()) return Read(faces, weights, name, out);
  const bool mixed = !faces.empty() || !weights.empty();
  if (mixed && (faces.size() != vertices.size() || weights.size() != 3 * vertices.size())) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%d vertex ids, %d faces and %d weights: give vertices alone, or one vertex id (-1: "
        "none), one face and three weights a point",
        vertices.size(), faces.size(), weights.size()));
  }
  std::vector<SurfacePoint> points(vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) {
    if (vertices[i] < 0 && mixed) {
      points[i] = {faces[i], {weights[3 * i], weights[3 * i + 1], weights[3 * i + 2]}};
      continue;
    }
    absl::StatusOr<SurfacePoint> vertex = VertexPoint(vertices[i]);
    if (!vertex.ok()) return Prefixed(vertex.status(), name, i);
    points[i] = *vertex;
  }
  return Read(points, name, out);
}

const std::vector<int32_t>& InputQueries::VertexFaces() const {
  std::call_once(vertex_faces_once_, [this] {
    const int32_t nv = num_vertices();
    std::vector<int32_t> faces(nv, -1);
    const double tolerance = engine_->options().weight_tolerance;
    for (int32_t f = 0; f < num_faces(); ++f) {
      const mesh::Triangle corners = InputFace(f);
      for (int k = 0; k < 3; ++k) {
        const int32_t v = corners[k];
        if (v < 0 || v >= nv || faces[v] >= 0) continue;
        // A face the repair dropped reads as no point: the vertex is then
        // read in a later face that holds it.
        SurfacePoint p{f, {0, 0, 0}};
        p.w[k] = 1;
        if (ids_->ToInternal(p, tolerance).ok()) faces[v] = f;
      }
    }
    vertex_faces_ = std::move(faces);
  });
  return vertex_faces_;
}

absl::StatusOr<SurfacePoint> InputQueries::VertexPoint(int32_t v) const {
  if (v < 0 || v >= num_vertices()) {
    return absl::OutOfRangeError(
        absl::StrFormat("vertex id %d out of range [0, %d)", v, num_vertices()));
  }
  const int32_t f = VertexFaces()[v];
  if (f < 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("vertex %d lies on no face of the mesh", v));
  }
  const mesh::Triangle corners = InputFace(f);
  SurfacePoint p{f, {0, 0, 0}};
  for (int k = 0; k < 3; ++k) {
    if (corners[k] == v) {
      p.w[k] = 1;
      break;
    }
  }
  return p;
}

absl::Status InputQueries::DistanceBatch(const EnginePoints& a, const EnginePoints& b,
                                         std::span<double> out, const DistanceOptions& options,
                                         QueryScratch* scratch, std::span<double> bounds) const {
  return engine_->DistanceBatch(a.points_, b.points_, out, options, scratch, bounds);
}

absl::StatusOr<double> InputQueries::Distance(const EnginePoints& a, size_t i,
                                              const EnginePoints& b, size_t j,
                                              const DistanceOptions& options, QueryScratch* scratch,
                                              double* bound) const {
  return engine_->Distance(a.points_.at(i), b.points_.at(j), options, scratch, bound);
}

double InputQueries::LinearInterpolationDistance(const EnginePoints& a, size_t i,
                                                 const EnginePoints& b, size_t j) const {
  return engine_->LinearInterpolationDistance(a.points_.at(i), b.points_.at(j));
}

absl::StatusOr<double> InputQueries::TracedDistance(const EnginePoints& a, size_t i,
                                                    const EnginePoints& b, size_t j) const {
  return engine_->TracedDistance(a.points_.at(i), b.points_.at(j));
}

absl::StatusOr<std::vector<PathPoint>> InputQueries::Path(const EnginePoints& a, size_t i,
                                                          const EnginePoints& b, size_t j,
                                                          int32_t exact_corridor) const {
  GEODEX_ASSIGN_OR_RETURN(std::vector<PathPoint> path,
                          engine_->Path(a.points_.at(i), b.points_.at(j), exact_corridor));
  ids_->PathToInput(path);
  return path;
}

absl::StatusOr<DistanceField> InputQueries::Field(const EnginePoints& sources) const {
  GEODEX_ASSIGN_OR_RETURN(DistanceField field, engine_->Field(sources.points_));
  return ids_->FieldToInput(std::move(field));
}

absl::StatusOr<RadiusField> InputQueries::FieldWithin(const EnginePoints& sources,
                                                      const FieldWithinOptions& options,
                                                      QueryScratch* scratch) const {
  QueryScratch local;
  GEODEX_ASSIGN_OR_RETURN(
      RadiusField field,
      engine_->FieldWithin(sources.points_, options, scratch != nullptr ? *scratch : local));
  if (ids_->identity()) return field;
  // Each reached internal vertex as its input vertex (none for a midpoint),
  // then one entry per input vertex: the copy nearest its source.
  struct Entry {
    int32_t vertex;
    double distance;
    int32_t nearest;
  };
  std::vector<Entry> entries;
  entries.reserve(field.vertices.size());
  for (size_t i = 0; i < field.vertices.size(); ++i) {
    const int32_t v = ids_->InputVertex(field.vertices[i]);
    if (v != mesh::kNone) entries.push_back({v, field.distance[i], field.nearest[i]});
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return a.vertex != b.vertex ? a.vertex < b.vertex : a.distance < b.distance;
  });
  RadiusField out;
  for (const Entry& e : entries) {
    if (!out.vertices.empty() && out.vertices.back() == e.vertex) continue;
    out.vertices.push_back(e.vertex);
    out.distance.push_back(e.distance);
    out.nearest.push_back(e.nearest);
  }
  return out;
}

absl::StatusOr<LocatedPoint> InputQueries::Locate(const mesh::Vec3& x) const {
  GEODEX_ASSIGN_OR_RETURN(LocatedPoint located, engine_->Locate(x));
  located.point = ids_->ToInput(located.point);
  return located;
}

std::vector<SurfacePoint> InputQueries::SamplePoints() const {
  const index::Index& ix = index();
  const std::span<const int32_t> samples = ix.samples();
  // Sample vertex -> sample ids, to find a face for each in one pass over
  // the faces (a vertex may in principle be two samples).
  std::vector<int32_t> face_of_sample(samples.size(), -1);
  std::unordered_multimap<int32_t, int32_t> samples_at;
  samples_at.reserve(samples.size());
  for (size_t i = 0; i < samples.size(); ++i) {
    samples_at.emplace(samples[i], static_cast<int32_t>(i));
  }
  const std::span<const int32_t> faces = ix.faces();
  std::vector<std::array<double, 3>> weights(samples.size(), {0, 0, 0});
  for (int32_t f = 0; f < ix.num_faces(); ++f) {
    for (int k = 0; k < 3; ++k) {
      auto [begin, end] = samples_at.equal_range(faces[3 * f + k]);
      for (auto it = begin; it != end; ++it) {
        if (face_of_sample[it->second] >= 0) continue;
        face_of_sample[it->second] = f;
        weights[it->second][k] = 1;
      }
    }
  }
  std::vector<SurfacePoint> out(samples.size(), SurfacePoint{-1, {0, 0, 0}});
  for (size_t i = 0; i < samples.size(); ++i) {
    if (face_of_sample[i] >= 0) out[i] = ids_->ToInput({face_of_sample[i], weights[i]});
  }
  return out;
}

std::vector<int32_t> InputQueries::VertexTriangles() const {
  // The copies are one point of space; any of their triangles holds it.
  const std::span<const index::VertexRecord> records = index().vertices();
  std::vector<int32_t> out(num_vertices());
  for (int32_t v = 0; v < num_vertices(); ++v) out[v] = records[v].triangle;
  for (int32_t copy = num_vertices(); copy < num_vertices() + ids_->num_vertex_copies(); ++copy) {
    int32_t& t = out[ids_->InputVertex(copy)];
    const int32_t c = records[copy].triangle;
    if (c >= 0 && (t < 0 || c < t)) t = c;
  }
  return out;
}

}  // namespace geodex::query
