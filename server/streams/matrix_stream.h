#pragma once

// Matrix: the distances from every source to every target, streamed as
// blocks of whole rows (at most 1 MiB of values each, fewer rows when the
// request's block_rows asks). It computes one block on the worker pool,
// writes it, and computes the next only when the write has completed; a
// cancelled call stops between rows.

#include "geodex/v1/geodex.pb.h"
#include "grpcpp/server_context.h"
#include "grpcpp/support/server_callback.h"

namespace geodex::server {

struct ServiceResources;

// The reactor of one Matrix call, admitted or already finished with the
// error of its admission. `resources` and `request` must outlive the call.
grpc::ServerWriteReactor<v1::MatrixBlock>* StartMatrixStream(const ServiceResources* resources,
                                                             grpc::CallbackServerContext* context,
                                                             const v1::MatrixRequest* request);

}  // namespace geodex::server
