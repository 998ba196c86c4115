#pragma once

// Options of geodex::client::Connect and of the Client.

#include <cstdint>
#include <string>

#include "absl/time/time.h"
#include "geodex/client/types.h"

namespace geodex::client {

// Which failures are retried, how often and how long to wait between tries.
//
// Only UNAVAILABLE is retried by default: the server returns it while a model
// is loading, and gRPC returns it when no connection could be made or one
// broke before the call was answered. Every geodex RPC is a read without side
// effects, so retrying is always safe; DEADLINE_EXCEEDED is still not retried
// by default because a call that ran out of time usually does so again and
// retrying only multiplies the load on a slow server. Set
// `retry_deadline_exceeded` to change that. INVALID_ARGUMENT, NOT_FOUND,
// OUT_OF_RANGE, RESOURCE_EXHAUSTED, ... are never retried.
//
// Waits grow exponentially: before attempt k+1 (k >= 1) the client sleeps a
// uniformly random time in [0, min(max_backoff, initial_backoff *
// multiplier^(k-1))] ("full jitter"), so that many clients failing at once do
// not come back at once.
struct RetryPolicy {
  int max_attempts = 4;  // 1 disables retries
  absl::Duration initial_backoff = absl::Milliseconds(50);
  absl::Duration max_backoff = absl::Seconds(2);
  double multiplier = 2.0;
  bool retry_deadline_exceeded = false;
};

// TLS. Empty `ca_file` and `cert_file` with `enabled` false: plaintext.
struct TlsOptions {
  bool enabled = false;     // set automatically when any file below is given
  std::string ca_file;      // PEM roots to verify the server; empty: system roots
  std::string cert_file;    // PEM client certificate chain (mTLS), with key_file
  std::string key_file;     // PEM client private key (mTLS)
  std::string server_name;  // overrides the name checked against the server's
                            // certificate (tests with self-signed certificates)
};

// Everything Connect needs.
struct ConnectOptions {
  TlsOptions tls;
  // Sent as "authorization: Bearer <token>" with every call: as gRPC call
  // credentials over TLS, as plain metadata over a plaintext channel (only
  // sensible on loopback or behind a TLS-terminating proxy).
  std::string bearer_token;
  // Per attempt of every call, except DistanceSession streams (no deadline
  // unless SessionOptions says so).
  absl::Duration deadline = absl::Seconds(60);
  RetryPolicy retry;
  // gRPC load-balancing policy across the addresses the target resolves to.
  // "round_robin" spreads calls over all servers; "pick_first" uses one.
  std::string load_balancing_policy = "round_robin";
  // Pairs per StreamDistances batch in Client::Distance.
  int32_t batch_size = 4096;
  std::string user_agent_prefix = "geodex-client/0.1";
};

// Options of a Client that are not about the channel. Connect fills them from
// ConnectOptions; tests construct a Client over a mock with them directly.
struct ClientOptions {
  int32_t batch_size = 4096;         // pairs per Distance batch (one unary call if all fit)
  int32_t path_batch_size = 256;     // pairs per Path call (paths are large)
  int32_t locate_batch_size = 8192;  // positions per Locate call
  RetryPolicy retry;                 // also used to resume a broken Distance stream
};

// Options of one DistanceSession.
struct SessionOptions {
  NearPairs near_pairs = NearPairs::kModelDefault;
  // Every batch refines the pairs that may be closer than this many L1000
  // (DistanceQuery::refine_below; about 8 is the every-distance mode). 0:
  // the model's threshold.
  double refine_below = 0;
  // The whole stream must end by then; infinite: no deadline.
  absl::Duration deadline = absl::InfiniteDuration();
};

}  // namespace geodex::client
