#pragma once

// Request limits of the Geodex service, and the one place they are checked.
// Beyond any of them a call fails with RESOURCE_EXHAUSTED, naming the limit.
// Server-wide values come from flags; a model's config.textproto may lower
// them (server/config/model_config.proto).
//
// Thread safety: pure functions.

#include <cstdint>

#include "absl/status/status.h"
#include "server/config/model_config.pb.h"

namespace geodex::server {

struct ServiceLimits {
  int64_t max_pairs_per_message = 1'000'000;  // Distance, each StreamDistances batch
  int64_t max_matrix_cells = 50'000'000;      // sources x targets of one Matrix call
  int64_t max_field_sources = 10'000;         // sources of one DistanceField call
  // Vertices one DistanceField call with a radius may reach: its exact
  // propagation stops past them (a cost cap; the answer lists those within
  // the radius).
  int64_t max_field_vertices = 1'000'000;
  int64_t max_path_pairs = 10'000;           // pairs of one Path call
  int64_t max_locate_positions = 1'000'000;  // positions of one Locate call
  int64_t max_message_bytes = 64 << 20;      // any received message (gRPC enforces it)
  // Streaming calls running at once: every call with a reactor in
  // server/streams/ (StreamDistances and each server stream) is admitted
  // through the one StreamSet that counts them against this limit.
  int32_t max_concurrent_streams = 64;
  // Batches of one StreamDistances call read ahead of the answers written:
  // enough to keep a worker busy while the previous answer is on the wire,
  // few enough that a slow reader stops the stream (backpressure).
  int32_t stream_window = 4;
  // Vertices, and faces, per GetMesh chunk: at most this many of each,
  // clamped to [1, 65536] (the most geodex.v1 allows; about 2.5 MiB, under
  // gRPC's 4 MiB default message size). Tests lower it to get many chunks.
  int32_t mesh_chunk_elements = 1 << 16;
};

// `server` with every non-zero limit of `model` that is smaller applied.
inline ServiceLimits WithModelLimits(ServiceLimits server, const ModelLimits& model) {
  auto lower = [](int64_t* limit, int64_t value) {
    if (value > 0 && value < *limit) *limit = value;
  };
  lower(&server.max_pairs_per_message, model.max_pairs_per_message());
  lower(&server.max_matrix_cells, model.max_matrix_cells());
  lower(&server.max_field_sources, model.max_field_sources());
  lower(&server.max_field_vertices, model.max_field_vertices());
  lower(&server.max_path_pairs, model.max_path_pairs());
  lower(&server.max_locate_positions, model.max_locate_positions());
  return server;
}

// The checks. Each returns OK within its limit, else ResourceExhausted with
// the count, the limit and its name ("12 pairs exceed the limit of 10 per
// message (max_pairs_per_message)").

// `pairs` of one Distance call or StreamDistances batch.
absl::Status CheckPairsPerMessage(const ServiceLimits& limits, int64_t pairs);
// `sources` x `targets` of one Matrix call (without overflow).
absl::Status CheckMatrixCells(const ServiceLimits& limits, int64_t sources, int64_t targets);
// `sources` of one DistanceField call.
absl::Status CheckFieldSources(const ServiceLimits& limits, int64_t sources);
// The error of a DistanceField call whose field within a radius reached
// more vertices than max_field_vertices (the query stops there and says so
// with ResourceExhausted, `status`, its only use of that code): its message
// with the limit's name
// ("the field within radius 2 reaches more than 1000 vertices, the limit
// (max_field_vertices)").
absl::Status FieldVerticesExceeded(const ServiceLimits& limits, const absl::Status& status);
// `pairs` of one Path call.
absl::Status CheckPathPairs(const ServiceLimits& limits, int64_t pairs);
// `positions` of one Locate call.
absl::Status CheckLocatePositions(const ServiceLimits& limits, int64_t positions);
// Admitting one more streaming call while `running` run.
absl::Status CheckConcurrentStreams(const ServiceLimits& limits, int64_t running);

}  // namespace geodex::server
