#pragma once

// An in-process stand-in for the geodex server, for tests of the gRPC
// connection and the CLI before (and independently of) server/. Its answers
// follow simple closed forms so that tests can check them exactly:
//
//   distance(a, b)   = |a.face - b.face| + sum_i |a.w[i] - b.w[i]|
//   path(a, b)       = [a, b] at positions (face, w1, w2), length = distance
//   field(v)         = min over sources s of |v - s.face|   (num_vertices = 60);
//                      with a radius r, the sparse form: the vertices with
//                      field(v) <= r, 7 entries a chunk
//   locate(x, y, z)  = face clamp(floor(x)), weights (1, 0, 0), distance |y|
//   mesh             = vertex v at (v, v % 2, 0), face f = (f % 60, (f + 1) % 60,
//                      (f + 2) % 60); chunk k holds vertices [7k, 7k + 7) and
//                      faces [11k, 11k + 11) (10 chunks)
//   vertex id v      = the point of weight 1 on v in face max(v - 2, 0), the
//                      lowest holding it
//   triangulation    = 10 samples, sample i at vertex 6i; 16 triangles,
//                      triangle t with samples (t, t + 1, t + 2) mod 10 and
//                      neighbour (t + 1) mod 16 across its first side;
//                      vertex v in triangle v mod 16
//
// and the other calls as their definitions say. Every call of the proto's
// list (geodex/v1/geodex_rpcs.h) is served; a test checks it. Models:
// "fake" (version 1, 100 faces, 60 vertices), "loading" (always
// UNAVAILABLE), anything else NOT_FOUND. A face >= 100 or a vertex >= 60 is
// OUT_OF_RANGE, bad weights INVALID_ARGUMENT (naming the element, e.g.
// "a[3]"), like the real server. Thread-safe.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "absl/synchronization/mutex.h"
#include "geodex/v1/geodex.grpc.pb.h"
#include "geodex/v1/geodex_rpcs.h"
#include "grpcpp/grpcpp.h"

namespace geodex::client::testing {

class FakeGeodexService final : public v1::Geodex::Service {
 public:
  static constexpr int64_t kNumFaces = 100;
  static constexpr int64_t kNumVertices = 60;
  static constexpr int32_t kNumSamples = 10;
  static constexpr int32_t kNumTriangles = 16;

  // One override per call of the proto's list, with the signature of its
  // kind; each is defined in fake_geodex_service_testing.cc.
#define GEODEX_FAKE_DECLARE(Name, Request, Response, Kind, ...) \
  GEODEX_FAKE_DECLARE_##Kind(Name, Request, Response)
#define GEODEX_FAKE_DECLARE_Unary(Name, Request, Response)                            \
  grpc::Status Name(grpc::ServerContext* context, const v1::Request* request, \
                    v1::Response* response) override;
#define GEODEX_FAKE_DECLARE_ServerStreaming(Name, Request, Response)                  \
  grpc::Status Name(grpc::ServerContext* context, const v1::Request* request, \
                    grpc::ServerWriter<v1::Response>* writer) override;
#define GEODEX_FAKE_DECLARE_BidiStreaming(Name, Request, Response) \
  grpc::Status Name(grpc::ServerContext* context,                 \
                    grpc::ServerReaderWriter<v1::Response, v1::Request>* stream) override;
  GEODEX_V1_RPCS(GEODEX_FAKE_DECLARE)
#undef GEODEX_FAKE_DECLARE
#undef GEODEX_FAKE_DECLARE_Unary
#undef GEODEX_FAKE_DECLARE_ServerStreaming
#undef GEODEX_FAKE_DECLARE_BidiStreaming

  // Fails the next `n` calls (of any method) with UNAVAILABLE.
  void FailNext(int n) { fail_next_.store(n); }
  // Every call sleeps this long first.
  void SetDelay(absl::Duration delay) {
    absl::MutexLock lock(&mu_);
    delay_ = delay;
  }
  // Calls received (including failed ones).
  int64_t calls() const { return calls_.load(); }
  // The "authorization" metadata of the last call ("" if none).
  std::string last_authorization() const {
    absl::MutexLock lock(&mu_);
    return last_authorization_;
  }

 private:
  // Common entry of every method: counts, records metadata, delays, fails.
  grpc::Status Enter(grpc::ServerContext* context);

  std::atomic<int> fail_next_{0};
  std::atomic<int64_t> calls_{0};
  mutable absl::Mutex mu_;
  absl::Duration delay_ ABSL_GUARDED_BY(mu_) = absl::ZeroDuration();
  std::string last_authorization_ ABSL_GUARDED_BY(mu_);
};

// A FakeGeodexService listening on 127.0.0.1 on a free port.
class FakeGeodexServer {
 public:
  FakeGeodexServer();
  ~FakeGeodexServer();
  const std::string& address() const { return address_; }  // "127.0.0.1:PORT"
  FakeGeodexService& service() { return service_; }

 private:
  FakeGeodexService service_;
  std::unique_ptr<grpc::Server> server_;
  std::string address_;
};

}  // namespace geodex::client::testing
