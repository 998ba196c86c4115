#pragma once

// A fixed set of worker threads with a bounded queue: where the Geodex service
// runs all query work, so that gRPC's reactor threads never compute. When the
// queue is full, Submit refuses the job and the caller answers
// RESOURCE_EXHAUSTED instead of letting work pile up without bound.
//
// Each worker owns a WorkerContext (per-thread scratch space: the core engine's
// QueryScratch and reusable point arrays) handed to every job it runs.
//
// Thread safety: Submit and queue_depth are safe from any thread. The
// destructor (or Stop) runs every job already queued, then joins the workers.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/query/input_queries.h"

namespace geodex::server {

// Per-worker scratch space. Jobs may use it freely while they run.
struct WorkerContext {
  int worker_id = 0;
  query::QueryScratch scratch;
  query::EnginePoints a, b;  // reusable point arrays
};

class WorkerPool {
 public:
  using Job = std::function<void(WorkerContext&)>;

  // `threads` >= 1 workers; at most `queue_capacity` (>= 1) jobs waiting.
  WorkerPool(int threads, int64_t queue_capacity);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  // Queues `job`. Returns false (and drops it) if the queue is full or the
  // pool is stopping.
  bool Submit(Job job);

  // Runs every queued job, then joins the workers. Idempotent; call it from
  // the owner's thread (never from a job).
  void Stop();

  int64_t queue_depth() const;
  int threads() const { return static_cast<int>(threads_.size()); }

 private:
  void Run(int worker_id);

  const int64_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<Job> queue_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace geodex::server
