#include "geodex/client/connection.h"

namespace geodex::client {
namespace {

absl::Status NotImplemented(const char* method) {
  return absl::UnimplementedError(std::string("GeodexConnection::") + method +
                                  " is not implemented by this connection");
}

// What the default StreamDistances returns: fails every operation.
class FailedStream : public DistanceStream {
 public:
  explicit FailedStream(absl::Status status) : status_(std::move(status)) {}
  bool Write(const v1::DistanceBatch&) override { return false; }
  bool WritesDone() override { return false; }
  bool Read(v1::DistanceResult*) override { return false; }
  void Cancel() override {}
  absl::Status Finish() override { return status_; }

 private:
  absl::Status status_;
};

}  // namespace

#define GEODEX_CLIENT_NOT_IMPLEMENTED(Name, Request, Result) \
  absl::StatusOr<Result> GeodexConnection::Name(const Request&) { return NotImplemented(#Name); }
GEODEX_CLIENT_RPCS(GEODEX_CLIENT_NOT_IMPLEMENTED)
#undef GEODEX_CLIENT_NOT_IMPLEMENTED

std::unique_ptr<DistanceStream> GeodexConnection::StreamDistances(const StreamOptions&) {
  return std::make_unique<FailedStream>(NotImplemented("StreamDistances"));
}

}  // namespace geodex::client
