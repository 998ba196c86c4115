#include "core/geodesic/radix_heap.h"

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <random>
#include <utility>
#include <vector>

#include "gtest/gtest.h"

namespace geodex::geodesic {
namespace {

using Heap = RadixHeap<int32_t>;
using Reference = std::priority_queue<std::pair<double, int32_t>,
                                      std::vector<std::pair<double, int32_t>>, std::greater<>>;

// Drives a RadixHeap and a std::priority_queue with the same Dijkstra-like
// (monotone) sequence: each pop pushes a few keys at or above the popped one.
// Checks that keys pop in the same order; values of equal keys may differ.
void CompareMonotone(Heap& heap, std::mt19937_64& rng, int steps, bool coarse_keys) {
  Reference reference;
  std::uniform_real_distribution<double> step(0.0, 2.0);
  std::uniform_int_distribution<int> fanout(0, 3);
  int32_t next_value = 0;
  auto key_after = [&](double base) {
    // Coarse keys are small integers: many ties.
    return coarse_keys ? base + std::floor(step(rng)) : base + step(rng) * step(rng);
  };
  for (int i = 0; i < 8; ++i) {
    const double key = key_after(0.0);
    heap.Push(key, next_value);
    reference.push({key, next_value++});
  }
  for (int i = 0; i < steps && !reference.empty(); ++i) {
    ASSERT_EQ(heap.size(), reference.size());
    const auto [key, value] = heap.Pop();
    ASSERT_EQ(key, reference.top().first) << "pop " << i;
    reference.pop();
    const int n = fanout(rng);
    for (int k = 0; k < n; ++k) {
      const double child = key_after(key);
      heap.Push(child, next_value);
      reference.push({child, next_value++});
    }
  }
  while (!reference.empty()) {
    ASSERT_FALSE(heap.empty());
    ASSERT_EQ(heap.Pop().key, reference.top().first);
    reference.pop();
  }
  EXPECT_TRUE(heap.empty());
  EXPECT_EQ(heap.size(), 0u);
}

TEST(RadixHeap, MatchesPriorityQueueOnMonotoneSequences) {
  std::mt19937_64 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    Heap heap;
    CompareMonotone(heap, rng, 20000, /*coarse_keys=*/false);
  }
}

TEST(RadixHeap, MatchesPriorityQueueWithTies) {
  std::mt19937_64 rng(2);
  for (int trial = 0; trial < 20; ++trial) {
    Heap heap;
    CompareMonotone(heap, rng, 20000, /*coarse_keys=*/true);
  }
}

TEST(RadixHeap, SortsArbitraryKeysPushedBeforeAnyPop) {
  std::mt19937_64 rng(3);
  // Spread over many binades, plus zero, denormals and infinity.
  std::vector<double> keys = {0.0, 5e-324, 1e-310, std::numeric_limits<double>::infinity(), 1.0};
  std::uniform_real_distribution<double> exponent(-300, 300);
  for (int i = 0; i < 5000; ++i) keys.push_back(std::pow(10.0, exponent(rng)));
  Heap heap;
  for (size_t i = 0; i < keys.size(); ++i) heap.Push(keys[i], static_cast<int32_t>(i));
  std::vector<double> popped;
  while (!heap.empty()) popped.push_back(heap.Pop().key);
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(popped, keys);
}

TEST(RadixHeap, TiesPopAllTheirValues) {
  Heap heap;
  for (int32_t v = 0; v < 100; ++v) heap.Push(v % 2 == 0 ? 1.0 : 3.0, v);
  std::vector<int32_t> ones, threes;
  while (!heap.empty()) {
    const auto [key, value] = heap.Pop();
    (key == 1.0 ? ones : threes).push_back(value);
    if (key == 3.0) {
      EXPECT_EQ(ones.size(), 50u) << "a 3 popped before all the 1s";
    }
  }
  std::sort(ones.begin(), ones.end());
  std::sort(threes.begin(), threes.end());
  ASSERT_EQ(ones.size(), 50u);
  ASSERT_EQ(threes.size(), 50u);
  for (int32_t i = 0; i < 50; ++i) {
    EXPECT_EQ(ones[i], 2 * i);
    EXPECT_EQ(threes[i], 2 * i + 1);
  }
}

TEST(RadixHeap, KeysBelowTheLastPopArePoppedNextWithTheirOwnKey) {
  Heap heap;
  heap.Push(1.0, 0);
  heap.Push(2.0, 1);
  heap.Push(3.0, 2);
  EXPECT_EQ(heap.Pop().value, 0);
  EXPECT_EQ(heap.Pop().value, 1);  // last popped key: 2.0
  heap.Push(2.0 - 1e-15, 3);       // rounding put it below: clamped to 2.0
  heap.Push(0.5, 4);               // far below: clamped as well
  heap.Push(2.5, 5);
  std::vector<std::pair<double, int32_t>> rest;
  while (!heap.empty()) {
    const auto [key, value] = heap.Pop();
    rest.push_back({key, value});
  }
  ASSERT_EQ(rest.size(), 4u);
  // The two clamped keys come first (in either order), reported unclamped.
  std::sort(rest.begin(), rest.begin() + 2);
  EXPECT_EQ(rest[0], std::make_pair(0.5, 4));
  EXPECT_EQ(rest[1], std::make_pair(2.0 - 1e-15, 3));
  EXPECT_EQ(rest[2], std::make_pair(2.5, 5));
  EXPECT_EQ(rest[3], std::make_pair(3.0, 2));
}

TEST(RadixHeap, NegativeKeysCountAsZero) {
  Heap heap;
  heap.Push(1.0, 0);
  heap.Push(-0.0, 1);
  heap.Push(-3.0, 2);
  heap.Push(0.0, 3);
  std::vector<int32_t> first;
  for (int i = 0; i < 3; ++i) first.push_back(heap.Pop().value);
  std::sort(first.begin(), first.end());
  EXPECT_EQ(first, (std::vector<int32_t>{1, 2, 3}));
  EXPECT_EQ(heap.Pop().value, 0);
}

TEST(RadixHeap, RandomClampedKeysPopInClampedOrder) {
  // Keys are pushed anywhere, some below the last pop: the pops must follow
  // the clamped keys max(key, last popped), and report the keys as pushed.
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> uniform(0.0, 100.0);
  Heap heap;
  std::vector<std::pair<double, double>> pending;  // {clamped, pushed}
  double last = 0;
  for (int i = 0; i < 20000; ++i) {
    if (pending.empty() || uniform(rng) < 55) {
      const double key = uniform(rng);
      heap.Push(key, i);
      pending.push_back({std::max(key, last), key});
    } else {
      const auto [key, value] = heap.Pop();
      const auto least = std::min_element(pending.begin(), pending.end());
      const double clamped = std::max(key, last);
      ASSERT_EQ(clamped, least->first) << "pop " << i;
      // Remove one pending entry with this clamped key and pushed key.
      const auto it = std::find(pending.begin(), pending.end(), std::make_pair(clamped, key));
      ASSERT_NE(it, pending.end());
      pending.erase(it);
      last = clamped;
    }
  }
}

TEST(RadixHeap, ReuseAfterClear) {
  std::mt19937_64 rng(5);
  Heap heap;
  CompareMonotone(heap, rng, 5000, /*coarse_keys=*/false);
  // Leave entries behind and a large last key, then clear.
  heap.Push(1e6, 0);
  heap.Push(2e6, 1);
  EXPECT_EQ(heap.Pop().key, 1e6);
  heap.Clear();
  EXPECT_TRUE(heap.empty());
  EXPECT_EQ(heap.size(), 0u);
  // Small keys are no longer clamped to 1e6.
  heap.Push(3.0, 2);
  heap.Push(1.0, 3);
  EXPECT_EQ(heap.Pop().key, 1.0);
  EXPECT_EQ(heap.Pop().key, 3.0);
  heap.Clear();
  CompareMonotone(heap, rng, 5000, /*coarse_keys=*/false);
}

TEST(RadixHeap, NearFrontNamesQueuedEntriesOnly) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> step(0.0, 1.0);
  Heap heap;
  std::vector<bool> queued;
  int64_t named = 0;
  auto push = [&](double key) {
    heap.Push(key, static_cast<int32_t>(queued.size()));
    queued.push_back(true);
  };
  for (int i = 0; i < 100; ++i) push(step(rng));
  while (!heap.empty()) {
    const auto [key, value] = heap.Pop([&](int32_t v) {
      ++named;
      ASSERT_TRUE(queued[v]) << v;
    });
    ASSERT_TRUE(queued[value]);
    queued[value] = false;
    if (queued.size() < 20000) {
      for (int k = 0; k < 2; ++k) push(key + step(rng));
    }
  }
  EXPECT_GT(named, 20000);
}

TEST(RadixHeap, PopOrderIsDeterministic) {
  auto run = [](Heap& heap) {
    std::mt19937_64 rng(6);
    std::uniform_int_distribution<int> key(0, 20);
    std::vector<int32_t> order;
    for (int32_t i = 0; i < 3000; ++i) {
      heap.Push(key(rng) * 0.25 + (order.empty() ? 0 : 10.0), i);
      if (i % 3 == 2) order.push_back(heap.Pop().value);
    }
    while (!heap.empty()) order.push_back(heap.Pop().value);
    return order;
  };
  Heap a, b;
  const std::vector<int32_t> first = run(a);
  EXPECT_EQ(first, run(b));
  a.Clear();
  EXPECT_EQ(first, run(a));  // a reused heap too
}

}  // namespace
}  // namespace geodex::geodesic
