#pragma once

// Where geodex.v1 messages become core types and back: what the calls share
// (points, positions, distance options, the model) and most answers. A
// streamed call may instead read its own options and write its own chunks
// beside its reactor (server/streams/<call>_stream.*, as the exponential
// map's does), with the helpers here, so that adding one leaves this file.
//
// Reading validates everything a query needs, with messages that name the
// offending element the way the request spells it ("a[17]: face id 99999 out
// of range [0, 5000)"), and with the codes of STYLE.md: InvalidArgument for
// malformed input, OutOfRange for a face id past the end.
//
// Ids. Requests and answers use the ids of the mesh file a model was built
// from; when the builder repaired that mesh they differ from the index's
// (core/query/engine/input_ids.h). Points are read into the index's ids here
// (PointsFromProto), and every answer that names faces or vertices is written
// back in input ids (here: paths, located points, fields, the mesh, the
// triangulation, the model's counts; InputQueries answers other calls in
// input ids already).
//
// Thread safety: pure functions (outputs are the caller's).

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/query/input_queries.h"
#include "core/query/engine/query_types.h"
#include "geodex/v1/geodex.pb.h"
#include "server/registry/model_registry.h"

namespace geodex::server {

// Reads `points` (named `name` in messages, in input ids; faces and weights,
// vertex ids, or both mixed: geodex.proto's SurfacePoints) into `out`, in
// the index's ids, validating each point against the input mesh's face and
// vertex counts and the engine's weight tolerance. Errors: InvalidArgument
// if weights are not 3 per face ("a: 4 faces but 11 weights (want 12)") or
// the vertex ids do not pair up with them, and for a vertex no face holds;
// OutOfRange for a face or vertex id
// past the end and InvalidArgument for NaN, infinite or negative weights or
// weights not summing to 1, both naming the point ("a[17]: ...").
absl::Status PointsFromProto(const v1::SurfacePoints& points, std::string_view name,
                             const query::InputQueries& queries, query::EnginePoints* out);

// Number of points in `points`: its vertex ids when it has any, else its
// faces (the rest is checked by PointsFromProto).
inline int64_t PointCount(const v1::SurfacePoints& points) {
  return points.vertices_size() > 0 ? points.vertices_size() : points.faces_size();
}

// OK when `a` and `b` hold as many points each (pairs a[i], b[i]). Errors:
// InvalidArgument ("a has 3 points but b has 2; they must pair up").
absl::Status CheckPairedUp(const v1::SurfacePoints& a, const v1::SurfacePoints& b);

// Reads `points` that must hold exactly one point (named `name`) into `out`
// as PointsFromProto does (an exponential map's centre). Errors:
// InvalidArgument for another count ("center: give exactly one point, got
// 2"), and those of PointsFromProto.
absl::Status OnePointFromProto(const v1::SurfacePoints& points, std::string_view name,
                               const query::InputQueries& queries, query::EnginePoints* out);

// Reads packed 3D positions. Errors: InvalidArgument if xyz is not a multiple
// of 3 long or a coordinate is not finite ("positions[4]: y is nan").
absl::Status PositionsFromProto(const v1::Positions& positions, std::string_view name,
                                std::vector<mesh::Vec3>* out);

// Appends one point to `points` as it is (callers give input ids).
void AppendPoint(const mesh::SurfacePoint& point, v1::SurfacePoints* points);

// Resizes `values` to `n` and returns its storage, for the engine to fill.
std::span<double> ResizeForOutput(google::protobuf::RepeatedField<double>* values, int64_t n);

// A path from InputQueries::Path (in input ids); `length` is the sum of its
// 3D segments.
void PathToProto(std::span<const query::PathPoint> path, v1::Polyline* polyline);
// The answer for a pair on different connected components: no points,
// length +Infinity.
void UnreachablePathToProto(v1::Polyline* polyline);

// A located point (InputQueries::Locate, in input ids) appended to a
// LocateResponse.
void AppendLocated(const query::LocatedPoint& located, v1::LocateResponse* response);

// Rows [row_offset, row_offset + rows) of a matrix, `values` row-major, and
// their error bounds alike (empty when the request asked for none).
void MatrixBlockToProto(int64_t row_offset, int64_t rows, int64_t num_targets,
                        std::span<const double> values, std::span<const double> bounds,
                        int64_t version, v1::MatrixBlock* block);

// Vertices [offset, offset + count) of a distance field (per input vertex:
// InputQueries::Field).
void FieldChunkToProto(const query::DistanceField& field, int64_t offset, int64_t count,
                       bool with_nearest_source, int64_t version, v1::DistanceFieldChunk* chunk);

// Entries [offset, offset + count) of a field within a radius (in input ids:
// InputQueries::FieldWithin), in the sparse form: vertices aligned with
// distances, vertex_offset = offset, num_vertices the answer's entries.
void RadiusFieldChunkToProto(const query::RadiusField& field, int64_t offset, int64_t count,
                             bool with_nearest_source, int64_t version,
                             v1::DistanceFieldChunk* chunk);

// Vertices [vertex_offset, vertex_offset + vertex_count) and faces
// [face_offset, face_offset + face_count) of the input mesh of `queries`'
// index (the mesh file's vertices and faces, also when it was repaired), with
// the mesh's totals and `version`. The ranges must lie within the input mesh.
void MeshChunkToProto(const query::InputQueries& queries, int64_t vertex_offset,
                      int64_t vertex_count, int64_t face_offset, int64_t face_count,
                      int64_t version, v1::MeshChunk* chunk);

// The geodesic triangulation held by `queries`' index (GetTriangulation), with
// `version`, in input ids (InputQueries::SamplePoints, VertexTriangles).
void TriangulationToProto(const query::InputQueries& queries, int64_t version,
                          v1::TriangulationResponse* out);

// A model as GetModel and ListModels describe it: `version` (a served
// version of `model`) if given, otherwise what is known without an index
// (state, reason, versions on disk). Vertex and face counts are the input
// mesh's.
void ModelInfoToProto(const ModelSnapshot& model, const ServedVersion* version,
                      v1::ModelInfo* info);

// --- Options ----------------------------------------------------------------
// What a request asks of the engine, as core options: the request's choices
// where it makes them, else the defaults of the model's configuration
// (server/config/model_config.proto). Errors: InvalidArgument for an unknown
// or contradictory choice, naming the field as the request spells it.

// What a distance request chooses. DistanceRequest and DistanceBatch carry
// every field; MatrixRequest all but the deprecated exact_near_pairs.
struct DistanceChoice {
  int near_pairs = 0;  // a v1::NearPairs value, unchecked
  bool exact_near_pairs = false;
  double tolerance = 0;
  bool error_bounds = false;
  double refine_below = 0;  // in L1000 (DistanceOptions::refine_below_l1000)

  static DistanceChoice Of(const v1::DistanceRequest& request);
  static DistanceChoice Of(const v1::DistanceBatch& request);
  static DistanceChoice Of(const v1::MatrixRequest& request);
};

// The near-pair mode and tolerance of `choice`. The mode is the request's
// (near_pairs, or the deprecated exact_near_pairs), else the configuration's
// (exact_near_pairs, then unfold_near_pairs), else by path length; the
// tolerance is the request's when > 0, else the configuration's; the
// refinement threshold is the request's. Errors: InvalidArgument for an
// unknown near_pairs value, exact_near_pairs beside another mode, or a
// negative or non-finite tolerance or threshold.
absl::StatusOr<query::DistanceOptions> DistanceOptionsFor(const ModelConfig& config,
                                                          const DistanceChoice& choice);

// Most faces a Path call's exact corridor may reach round the trace: the
// exact solve costs a propagation over the corridor.
inline constexpr uint32_t kMaxPathCorridor = 64;

// The exact corridor of a Path call: the request's exact_corridor when > 0,
// else the configuration's exact_path_corridor clamped to [0,
// kMaxPathCorridor]. Errors: InvalidArgument for a request's corridor above
// kMaxPathCorridor.
absl::StatusOr<int32_t> PathCorridorFor(const ModelConfig& config, const v1::PathRequest& request);

}  // namespace geodex::server
