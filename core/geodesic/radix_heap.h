#pragma once

// A monotone priority queue keyed on non-negative doubles: a radix heap
// (Ahuja, Mehlhorn, Orlin & Tarjan, "Faster algorithms for the shortest path
// problem", JACM 37(2), 1990) over the keys' IEEE-754 bit patterns, which for
// non-negative doubles (+inf included) order like the values.
//
// It serves Dijkstra-like propagations, where no key pushed is below the last
// key popped. Entries sit in 64 buckets by the highest bit in which their key
// differs from the last popped key (bucket 0: equal to it); a pop that finds
// bucket 0 empty refills it from the lowest non-empty bucket, each entry of
// which moves to a strictly lower bucket. An entry thus moves at most 63
// times, in practice under 10, and all the work is appending to and scanning
// short vectors, where a binary heap sifts through log(n) levels with a
// data-dependent branch at each.
//
// Contract:
//   - A key below the last popped key is treated as equal to it (clamped): it
//     pops before every larger key. Negative keys and -0.0 count as 0.
//   - Pop returns the key as it was pushed, not clamped.
//   - Entries of equal (clamped) key pop in an unspecified order, but the
//     same sequence of calls always gives the same pops: it is deterministic.
//   - Clear empties the queue, forgets the last popped key and keeps the
//     memory, so a reused queue does not reallocate.
//
// Example:
//   RadixHeap<int32_t> queue;
//   queue.Push(2.5, 7);
//   queue.Push(1.0, 3);
//   const auto [key, value] = queue.Pop();  // 1.0, 3

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace geodex::geodesic {

template <typename Value>
class RadixHeap {
 public:
  struct Entry {
    double key;  // as pushed
    Value value;
  };

  bool empty() const { return size_ == 0; }
  size_t size() const { return size_; }

  void Push(double key, Value value) {
    Put(BucketOf(HeapKey(key)), {key, value});
    ++size_;
  }

  // Removes and returns an entry of least (clamped) key. Requires !empty().
  Entry Pop() {
    return Pop([](const Value&) {});
  }

  // Same, and calls `near_front(value)` for each entry that a refill moves
  // nearer the front of the queue (the one returned among them, unless it was
  // pushed at the front): such entries pop soon, so a caller whose values
  // refer to data elsewhere can prefetch that data there.
  template <typename NearFront>
  Entry Pop(NearFront&& near_front) {
    if (buckets_[0].empty()) Refill(near_front);
    const Entry top = buckets_[0].back();
    buckets_[0].pop_back();
    --size_;
    return top;
  }

  void Clear() {
    for (std::vector<Entry>& bucket : buckets_) bucket.clear();
    size_ = 0;
    last_ = 0;
    occupied_ = 0;
  }

 private:
  // The key as the heap orders it: its bit pattern, clamped to the last
  // popped key. The sign bit set (negative, -0.0) means 0, so bit 63 of a
  // heap key is always clear.
  uint64_t HeapKey(double key) const {
    const uint64_t bits = std::bit_cast<uint64_t>(key);
    return std::max(bits >> 63 ? uint64_t{0} : bits, last_);
  }

  // 0 for a key equal to last_, else 1 + the highest bit where they differ:
  // at most 63.
  int BucketOf(uint64_t key) const { return std::bit_width(key ^ last_); }

  void Put(int bucket, const Entry& e) {
    buckets_[bucket].push_back(e);
    occupied_ |= (uint64_t{1} << bucket) >> 1;  // no bit for bucket 0
  }

  // Bucket 0 is empty: makes the least key of the lowest non-empty bucket the
  // new last_ and redistributes that bucket. Its entries all share last_'s
  // bits above the bucket's bit, and the new last_ has that bit too, so each
  // entry lands in a strictly lower bucket (bucket 0 for the minimum).
  template <typename NearFront>
  void Refill(NearFront& near_front) {
    const int i = std::countr_zero(occupied_) + 1;
    occupied_ &= occupied_ - 1;
    std::vector<Entry>& from = buckets_[i];
    uint64_t least = std::numeric_limits<uint64_t>::max();
    for (const Entry& e : from) least = std::min(least, HeapKey(e.key));
    last_ = least;
    for (const Entry& e : from) {
      near_front(e.value);
      Put(BucketOf(HeapKey(e.key)), e);
    }
    from.clear();
  }

  uint64_t last_ = 0;      // bits of the last popped (clamped) key
  uint64_t occupied_ = 0;  // bit i - 1 set iff bucket i >= 1 is non-empty
  size_t size_ = 0;
  std::array<std::vector<Entry>, 64> buckets_;
};

}  // namespace geodex::geodesic
