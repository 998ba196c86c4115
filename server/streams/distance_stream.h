#pragma once

// StreamDistances: the bidirectional stream of distance batches.
//
// It reads at most ServiceLimits::stream_window batches ahead of the answers
// written, computes them on the worker pool (several at once with several
// workers), and writes answers in batch order, one write in flight. A slow
// reader therefore stops the reads, and HTTP/2 flow control pushes back on
// the sender. A bad batch is answered with its error and the stream goes on.
// Each batch resolves its model when it is computed, so a long stream moves
// to a new version when one is swapped in (the answer carries the version).
//
// Shutdown (StreamBase::Drain): the stream stops reading, answers the
// batches it has read, and finishes UNAVAILABLE ("server shutting down",
// with the count of answered batches) so that the client can send the rest
// elsewhere.

#include "geodex/v1/geodex.pb.h"
#include "grpcpp/server_context.h"
#include "grpcpp/support/server_callback.h"

namespace geodex::server {

struct ServiceResources;

// The reactor of one StreamDistances call, admitted or already finished
// with the error of its admission. `resources` must outlive the call.
grpc::ServerBidiReactor<v1::DistanceBatch, v1::DistanceResult>* StartDistanceStream(
    const ServiceResources* resources, grpc::CallbackServerContext* context);

}  // namespace geodex::server
