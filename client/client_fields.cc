// The Client calls whose answers are assembled from server-streamed chunks
// over the mesh's vertices and faces: distance fields, the exponential map
// and the mesh. Each checks that the chunks are one consistent answer
// (DATA_LOSS otherwise) before it hands it back.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "absl/strings/str_format.h"
#include "client/convert.h"
#include "geodex/client/client.h"

namespace geodex::client {
namespace {

// The radius of a field within a radius or of an exponential map: finite and
// > 0. Checked before any call, so that a bad one costs no round trip.
absl::Status CheckRadius(double radius) {
  if (std::isfinite(radius) && radius > 0) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrFormat("the radius must be finite and > 0, got %g", radius));
}

// Appends a chunk's vertex ids to `out`, whose ids must keep ascending
// across chunks: the answers that list vertices list each once, in order.
absl::Status AppendAscending(const google::protobuf::RepeatedField<int32_t>& ids, const char* what,
                             std::vector<int32_t>* out) {
  for (const int32_t id : ids) {
    if (!out->empty() && id <= out->back()) {
      return absl::DataLossError(absl::StrFormat(
          "the server sent %s vertices out of order (%d after %d)", what, id, out->back()));
    }
    out->push_back(id);
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<VertexDistances> Client::DistanceField(const ModelRef& model,
                                                      absl::Span<const SurfacePoint> sources,
                                                      bool with_nearest_source) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  v1::DistanceFieldRequest request;
  *request.mutable_model() = ToProto(model);
  *request.mutable_sources() = ToProto(sources);
  request.set_with_nearest_source(with_nearest_source);
  absl::StatusOr<std::vector<v1::DistanceFieldChunk>> chunks = connection_->DistanceField(request);
  if (!chunks.ok()) return chunks.status();

  VertexDistances field;
  const int64_t n = chunks->empty() ? 0 : chunks->front().num_vertices();
  field.distances.assign(n, std::numeric_limits<double>::quiet_NaN());
  if (with_nearest_source) field.nearest_source.assign(n, -1);
  std::vector<bool> seen(n, false);
  int64_t covered = 0;
  for (const v1::DistanceFieldChunk& chunk : *chunks) {
    const int64_t offset = chunk.vertex_offset();
    const int64_t size = chunk.distances_size();
    if (chunk.num_vertices() != n || offset < 0 || offset + size > n ||
        (with_nearest_source && chunk.nearest_source_size() != size)) {
      return absl::DataLossError(absl::StrFormat(
          "the server sent a distance field chunk of vertices [%d, %d) of %d (%d nearest "
          "sources) for a field of %d vertices",
          offset, offset + size, chunk.num_vertices(), chunk.nearest_source_size(), n));
    }
    for (int64_t v = offset; v < offset + size; ++v) {
      if (seen[v]) {
        return absl::DataLossError(
            absl::StrFormat("the server sent the distance of vertex %d twice", v));
      }
      seen[v] = true;
    }
    covered += size;
    std::copy(chunk.distances().begin(), chunk.distances().end(), field.distances.begin() + offset);
    if (with_nearest_source) {
      std::copy(chunk.nearest_source().begin(), chunk.nearest_source().end(),
                field.nearest_source.begin() + offset);
    }
    field.version = chunk.version();
  }
  if (covered != n) {
    return absl::DataLossError(
        absl::StrFormat("the server sent distances for %d of %d vertices", covered, n));
  }
  return field;
}

absl::StatusOr<VertexDistancesWithin> Client::DistanceFieldWithin(
    const ModelRef& model, absl::Span<const SurfacePoint> sources,
    const FieldWithinQuery& query) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  if (absl::Status s = CheckRadius(query.radius); !s.ok()) return s;
  v1::DistanceFieldRequest request;
  *request.mutable_model() = ToProto(model);
  *request.mutable_sources() = ToProto(sources);
  request.set_with_nearest_source(query.with_nearest_source);
  request.set_radius(query.radius);
  absl::StatusOr<std::vector<v1::DistanceFieldChunk>> chunks = connection_->DistanceField(request);
  if (!chunks.ok()) return chunks.status();

  VertexDistancesWithin field;
  const int64_t n = chunks->empty() ? 0 : chunks->front().num_vertices();
  for (const v1::DistanceFieldChunk& chunk : *chunks) {
    const int size = chunk.distances_size();
    if (chunk.vertices_size() != size) {
      return absl::DataLossError(absl::StrFormat(
          "the server sent a distance field chunk of %d distances for %d vertices%s", size,
          chunk.vertices_size(),
          chunk.vertices_size() == 0 ? " (a whole-mesh field: the server predates radius fields)"
                                     : ""));
    }
    if (chunk.num_vertices() != n || chunk.vertex_offset() != std::ssize(field.vertices) ||
        std::ssize(field.vertices) + size > n ||
        (query.with_nearest_source && chunk.nearest_source_size() != size)) {
      return absl::DataLossError(absl::StrFormat(
          "the server sent a chunk of entries [%d, %d) of %d (%d nearest sources), after %d, for a "
          "field of %d vertices within the radius",
          chunk.vertex_offset(), chunk.vertex_offset() + size, chunk.num_vertices(),
          chunk.nearest_source_size(), field.vertices.size(), n));
    }
    if (absl::Status s = AppendAscending(chunk.vertices(), "field", &field.vertices); !s.ok()) {
      return s;
    }
    field.distances.insert(field.distances.end(), chunk.distances().begin(),
                           chunk.distances().end());
    if (query.with_nearest_source) {
      field.nearest_source.insert(field.nearest_source.end(), chunk.nearest_source().begin(),
                                  chunk.nearest_source().end());
    }
    field.version = chunk.version();
  }
  if (std::ssize(field.vertices) != n) {
    return absl::DataLossError(
        absl::StrFormat("the server sent %d of the field's %d vertices within the radius",
                        field.vertices.size(), n));
  }
  return field;
}

absl::StatusOr<client::ExpMap> Client::ExpMap(const ModelRef& model, const SurfacePoint& center,
                                              const ExpMapQuery& query) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  if (absl::Status s = CheckRadius(query.radius); !s.ok()) return s;
  v1::ExpMapRequest request;
  *request.mutable_model() = ToProto(model);
  *request.mutable_center() = ToProto(absl::Span<const SurfacePoint>(&center, 1));
  request.set_radius(query.radius);
  if (query.reference_direction) {
    request.mutable_reference_direction()->mutable_xyz()->Assign(query.reference_direction->begin(),
                                                                 query.reference_direction->end());
  }
  request.set_near_pairs(ToProto(query.near_pairs));
  request.set_tolerance(query.tolerance);
  absl::StatusOr<std::vector<v1::ExpMapChunk>> chunks = connection_->ExpMap(request);
  if (!chunks.ok()) return chunks.status();

  client::ExpMap map;
  const int64_t n = chunks->empty() ? 0 : chunks->front().num_vertices();
  for (const v1::ExpMapChunk& chunk : *chunks) {
    const int size = chunk.vertices_size();
    if (chunk.num_vertices() != n || chunk.r_size() != size || chunk.theta_size() != size ||
        chunk.u_size() != size || chunk.v_size() != size ||
        static_cast<int64_t>(map.vertices.size()) + size > n) {
      return absl::DataLossError(absl::StrFormat(
          "the server sent an exponential map chunk of %d vertices (%d r, %d theta, %d u, %d v) "
          "of %d, after %d, for a map of %d",
          size, chunk.r_size(), chunk.theta_size(), chunk.u_size(), chunk.v_size(),
          chunk.num_vertices(), map.vertices.size(), n));
    }
    if (absl::Status s = AppendAscending(chunk.vertices(), "exponential map", &map.vertices);
        !s.ok()) {
      return s;
    }
    map.r.insert(map.r.end(), chunk.r().begin(), chunk.r().end());
    map.theta.insert(map.theta.end(), chunk.theta().begin(), chunk.theta().end());
    map.u.insert(map.u.end(), chunk.u().begin(), chunk.u().end());
    map.v.insert(map.v.end(), chunk.v().begin(), chunk.v().end());
    map.version = chunk.version();
  }
  if (static_cast<int64_t>(map.vertices.size()) != n) {
    return absl::DataLossError(absl::StrFormat(
        "the server sent %d of the exponential map's %d vertices", map.vertices.size(), n));
  }
  return map;
}

absl::StatusOr<Mesh> Client::GetMesh(const ModelRef& model) const {
  if (absl::Status s = CheckModel(model); !s.ok()) return s;
  v1::GetMeshRequest request;
  *request.mutable_model() = ToProto(model);
  absl::StatusOr<std::vector<v1::MeshChunk>> chunks = connection_->GetMesh(request);
  if (!chunks.ok()) return chunks.status();
  if (chunks->empty()) return absl::DataLossError("the server sent no mesh chunks");

  const v1::MeshChunk& first = chunks->front();
  const uint64_t num_vertices = first.num_vertices();
  const uint64_t num_faces = first.num_faces();
  const int64_t version = first.version();
  if (model.version != 0 && version != model.version) {
    return absl::DataLossError(
        absl::StrFormat("the server sent the mesh of version %d when version %d was asked for",
                        version, model.version));
  }
  // The ranges are checked before anything is allocated: the totals are only
  // the server's word until the chunks add up to them.
  uint64_t next_vertex = 0, next_face = 0;
  for (size_t k = 0; k < chunks->size(); ++k) {
    const v1::MeshChunk& chunk = (*chunks)[k];
    if (chunk.num_vertices() != num_vertices || chunk.num_faces() != num_faces ||
        chunk.version() != version) {
      return absl::DataLossError(absl::StrFormat(
          "mesh chunk %d is of a mesh of %d vertices and %d faces, version %d; chunk 0 of one of "
          "%d vertices and %d faces, version %d",
          k, chunk.num_vertices(), chunk.num_faces(), chunk.version(), num_vertices, num_faces,
          version));
    }
    if (chunk.positions_size() % 3 != 0 || chunk.faces_size() % 3 != 0) {
      return absl::DataLossError(absl::StrFormat(
          "mesh chunk %d has %d coordinates and %d face vertex ids; both must be multiples of 3", k,
          chunk.positions_size(), chunk.faces_size()));
    }
    if (chunk.vertex_offset() != next_vertex || chunk.face_offset() != next_face) {
      return absl::DataLossError(absl::StrFormat(
          "mesh chunk %d starts at vertex %d and face %d, not at vertex %d and face %d where the "
          "chunks before it stopped",
          k, chunk.vertex_offset(), chunk.face_offset(), next_vertex, next_face));
    }
    next_vertex += chunk.positions_size() / 3;
    next_face += chunk.faces_size() / 3;
    if (next_vertex > num_vertices || next_face > num_faces) {
      return absl::DataLossError(absl::StrFormat(
          "mesh chunk %d goes past the end of the mesh: to vertex %d of %d and face %d of %d", k,
          next_vertex, num_vertices, next_face, num_faces));
    }
  }
  if (next_vertex != num_vertices || next_face != num_faces) {
    return absl::DataLossError(
        absl::StrFormat("the server sent %d of %d mesh vertices and %d of %d faces", next_vertex,
                        num_vertices, next_face, num_faces));
  }

  Mesh mesh;
  mesh.version = version;
  mesh.positions.reserve(num_vertices);
  mesh.faces.reserve(num_faces);
  for (const v1::MeshChunk& chunk : *chunks) {
    const auto& xyz = chunk.positions();
    for (int i = 0; i < xyz.size(); i += 3) {
      mesh.positions.push_back({xyz[i], xyz[i + 1], xyz[i + 2]});
    }
    const auto& ids = chunk.faces();
    for (int i = 0; i < ids.size(); i += 3) {
      for (int c = 0; c < 3; ++c) {
        if (ids[i + c] >= num_vertices) {
          return absl::DataLossError(
              absl::StrFormat("mesh face %d names vertex %d, past the end (%d vertices)",
                              mesh.faces.size(), ids[i + c], num_vertices));
        }
      }
      mesh.faces.push_back({ids[i], ids[i + 1], ids[i + 2]});
    }
  }
  return mesh;
}

}  // namespace geodex::client
