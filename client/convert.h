#pragma once

// Conversions between the client's types (geodex/client/types.h) and the
// geodex.v1 messages, shared by the Client methods. The FromProto functions
// check what the server sent: DATA_LOSS for arrays of inconsistent length.

#include <cstddef>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/types/span.h"
#include "geodex/client/types.h"
#include "geodex/v1/geodex.pb.h"

namespace geodex::client {

v1::ModelRef ToProto(const ModelRef& model);
v1::NearPairs ToProto(NearPairs mode);
v1::SurfacePoints ToProto(absl::Span<const SurfacePoint> points);
// Pairs [begin, end) as the packed arrays a and b.
void PairsToProto(absl::Span<const PointPair> pairs, size_t begin, size_t end, v1::SurfacePoints* a,
                  v1::SurfacePoints* b);

absl::StatusOr<std::vector<SurfacePoint>> FromProto(const v1::SurfacePoints& points);
ModelInfo FromProto(const v1::ModelInfo& m);

// INVALID_ARGUMENT for a model reference no server accepts (no name, a
// negative version); checked before any call.
absl::Status CheckModel(const ModelRef& model);

}  // namespace geodex::client
