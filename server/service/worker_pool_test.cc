#include "server/service/worker_pool.h"

#include <atomic>
#include <chrono>
#include <latch>
#include <set>
#include <thread>

#include "gtest/gtest.h"

namespace geodex::server {
namespace {

TEST(WorkerPoolTest, RunsEveryJobOnItsThreads) {
  std::atomic<int> done{0};
  std::mutex mutex;
  std::set<int> workers;
  {
    WorkerPool pool(3, 1000);
    for (int i = 0; i < 300; ++i) {
      ASSERT_TRUE(pool.Submit([&](WorkerContext& w) {
        std::lock_guard<std::mutex> lock(mutex);
        workers.insert(w.worker_id);
        ++done;
      }));
    }
  }  // the destructor runs what is queued
  EXPECT_EQ(done.load(), 300);
  for (int id : workers) EXPECT_TRUE(id >= 0 && id < 3);
}

TEST(WorkerPoolTest, RefusesJobsBeyondTheQueueCapacity) {
  WorkerPool pool(1, 2);
  std::latch started(1), release(1);
  ASSERT_TRUE(pool.Submit([&](WorkerContext&) {
    started.count_down();
    release.wait();
  }));
  started.wait();  // the worker is busy; the queue is empty
  EXPECT_TRUE(pool.Submit([](WorkerContext&) {}));
  EXPECT_TRUE(pool.Submit([](WorkerContext&) {}));
  EXPECT_FALSE(pool.Submit([](WorkerContext&) {}));
  EXPECT_EQ(pool.queue_depth(), 2);
  release.count_down();
  pool.Stop();
  EXPECT_FALSE(pool.Submit([](WorkerContext&) {}));
}

}  // namespace
}  // namespace geodex::server
