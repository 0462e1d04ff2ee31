// The fixed-capacity FIFO ring view (core/ring.hpp): order, eviction of the oldest when full,
// wrap-around, capacities 0 and 1, writes kept inside the storage, and random push/pop/clear
// sequences against a plain "everything pushed" model.
#include <gtest/gtest.h>

#include <cstddef>
#include <type_traits>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/core/ring.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::ring_test {
namespace {

static_assert(!std::is_copy_constructible<RingView<int>>::value, "a view over owned storage is not copied");
static_assert(!std::is_copy_assignable<RingView<int>>::value, "a view over owned storage is not copied");

TEST(Ring, StartsEmptyAndKeepsPushOrder) {
  int storage[4] = {};
  RingView<int> ring(storage, 4);
  EXPECT_TRUE(ring.empty());
  EXPECT_FALSE(ring.full());
  EXPECT_EQ(ring.size(), 0u);
  EXPECT_EQ(ring.capacity(), 4u);
  bool evicted = true;
  EXPECT_NO_HEAP(evicted = ring.push(10));
  EXPECT_FALSE(evicted);
  EXPECT_NO_HEAP(evicted = ring.push(20));
  EXPECT_FALSE(evicted);
  EXPECT_NO_HEAP(evicted = ring.push(30));
  EXPECT_FALSE(evicted);
  EXPECT_EQ(ring.size(), 3u);
  EXPECT_FALSE(ring.empty());
  EXPECT_FALSE(ring.full());
  EXPECT_EQ(ring[0], 10);
  EXPECT_EQ(ring[1], 20);
  EXPECT_EQ(ring[2], 30);
  EXPECT_EQ(ring.front(), 10);
  EXPECT_EQ(ring.back(), 30);
}

TEST(Ring, KeepsTheNewestItemsWhenFull) {
  int storage[3] = {};
  RingView<int> ring(storage, 3);
  EXPECT_FALSE(ring.push(1));
  EXPECT_FALSE(ring.push(2));
  EXPECT_FALSE(ring.push(3));
  EXPECT_TRUE(ring.full());
  EXPECT_TRUE(ring.push(4));  // evicts 1
  EXPECT_TRUE(ring.push(5));  // evicts 2
  EXPECT_TRUE(ring.full());
  EXPECT_EQ(ring.size(), 3u);
  EXPECT_EQ(ring[0], 3);
  EXPECT_EQ(ring[1], 4);
  EXPECT_EQ(ring[2], 5);
  EXPECT_EQ(ring.front(), 3);
  EXPECT_EQ(ring.back(), 5);
  // Seven pushes into three slots: 5, 6, 7 remain, oldest first, whatever the wrap position.
  EXPECT_TRUE(ring.push(6));
  EXPECT_TRUE(ring.push(7));
  EXPECT_EQ(ring[0], 5);
  EXPECT_EQ(ring[1], 6);
  EXPECT_EQ(ring[2], 7);
}

TEST(Ring, PopFrontRemovesTheOldestAndWrapsAround) {
  int storage[3] = {};
  RingView<int> ring(storage, 3);
  ring.push(1);
  ring.push(2);
  ring.push(3);
  EXPECT_NO_HEAP(ring.pop_front());
  EXPECT_EQ(ring.size(), 2u);
  EXPECT_FALSE(ring.full());
  EXPECT_EQ(ring.front(), 2);
  EXPECT_FALSE(ring.push(4));  // room again: nothing evicted; this one wraps to slot 0
  EXPECT_TRUE(ring.full());
  EXPECT_EQ(ring[0], 2);
  EXPECT_EQ(ring[1], 3);
  EXPECT_EQ(ring[2], 4);
  ring.pop_front();
  ring.pop_front();
  ring.pop_front();
  EXPECT_TRUE(ring.empty());
  ring.pop_front();  // no effect when empty
  EXPECT_TRUE(ring.empty());
  EXPECT_EQ(ring.size(), 0u);
  EXPECT_FALSE(ring.push(9));
  EXPECT_EQ(ring.size(), 1u);
  EXPECT_EQ(ring.front(), 9);
  EXPECT_EQ(ring.back(), 9);
}

TEST(Ring, ClearEmptiesAndTheRingRefills) {
  int storage[2] = {};
  RingView<int> ring(storage, 2);
  ring.push(1);
  ring.push(2);
  ring.push(3);  // head has moved
  EXPECT_NO_HEAP(ring.clear());
  EXPECT_TRUE(ring.empty());
  EXPECT_EQ(ring.size(), 0u);
  EXPECT_EQ(ring.capacity(), 2u);
  EXPECT_FALSE(ring.push(7));
  EXPECT_FALSE(ring.push(8));
  EXPECT_TRUE(ring.push(9));
  EXPECT_EQ(ring[0], 8);
  EXPECT_EQ(ring[1], 9);
}

TEST(Ring, CapacityOneHoldsOnlyTheNewest) {
  int storage[1] = {};
  RingView<int> ring(storage, 1);
  EXPECT_FALSE(ring.push(1));
  EXPECT_TRUE(ring.full());
  EXPECT_EQ(ring.front(), 1);
  for (int v = 2; v < 6; ++v) {
    EXPECT_TRUE(ring.push(v));
    EXPECT_EQ(ring.size(), 1u);
    EXPECT_EQ(ring.front(), v);
    EXPECT_EQ(ring.back(), v);
  }
  ring.pop_front();
  EXPECT_TRUE(ring.empty());
  EXPECT_FALSE(ring.push(6));
}

TEST(Ring, CapacityZeroHoldsNothingAndTouchesNothing) {
  int guard[1] = {42};
  RingView<int> ring(guard, 0);
  EXPECT_TRUE(ring.empty());
  EXPECT_TRUE(ring.full());  // the next push evicts (it is dropped)
  bool evicted = false;
  EXPECT_NO_HEAP(evicted = ring.push(5));
  EXPECT_TRUE(evicted);
  EXPECT_EQ(ring.size(), 0u);
  EXPECT_TRUE(ring.empty());
  ring.pop_front();
  EXPECT_EQ(ring.size(), 0u);
  EXPECT_EQ(guard[0], 42);
}

TEST(Ring, MutableIndexWritesThroughAndStaysInsideTheStorage) {
  constexpr std::size_t kCapacity = 5;
  int storage[kCapacity + 2];
  for (int& s : storage) s = -1;
  RingView<int> ring(storage + 1, kCapacity);  // storage[0] and storage[kCapacity + 1] are guards
  for (int v = 0; v < 23; ++v) ring.push(v);
  EXPECT_EQ(storage[0], -1);
  EXPECT_EQ(storage[kCapacity + 1], -1);
  // 18..22 are held; every one is somewhere in the storage exactly once.
  for (int v = 18; v < 23; ++v) {
    int copies = 0;
    for (std::size_t i = 1; i <= kCapacity; ++i) copies += storage[i] == v ? 1 : 0;
    EXPECT_EQ(copies, 1) << v;
  }
  ring[2] = 1000;
  EXPECT_EQ(ring[2], 1000);
  EXPECT_EQ(ring[1], 19);
  EXPECT_EQ(ring[3], 21);
  int found = 0;
  for (std::size_t i = 1; i <= kCapacity; ++i) found += storage[i] == 1000 ? 1 : 0;
  EXPECT_EQ(found, 1);
  const RingView<int>& view = ring;
  EXPECT_EQ(view[2], 1000);
}

/// A non-trivial element: the ring copies whole values.
struct Sample {
  double x = 0.0;
  int id = 0;
};

TEST(Ring, MatchesAModelOfEverythingPushedOverRandomOperations) {
  Random random(2024);
  for (std::size_t capacity = 0; capacity <= 9; ++capacity) {
    Sample storage[9];
    RingView<Sample> ring(storage, capacity);
    // Model: all values ever pushed; the ring holds pushed[first, pushed.size()).
    std::vector<int> pushed;
    pushed.reserve(2000);
    std::size_t first = 0;
    for (int step = 0; step < 1500; ++step) {
      const std::uint64_t op = random.below(10);
      if (op < 6) {
        const int id = static_cast<int>(pushed.size());
        const bool model_evicts = pushed.size() - first == capacity;
        bool evicted = false;
        EXPECT_NO_HEAP(evicted = ring.push(Sample{0.5 * id, id}));
        pushed.push_back(id);
        if (model_evicts) ++first;
        ASSERT_EQ(evicted, model_evicts) << "capacity " << capacity << " step " << step;
      } else if (op < 9) {
        EXPECT_NO_HEAP(ring.pop_front());
        if (first < pushed.size()) ++first;
      } else {
        EXPECT_NO_HEAP(ring.clear());
        first = pushed.size();
      }
      const std::size_t held = pushed.size() - first;
      ASSERT_EQ(ring.size(), held) << "capacity " << capacity << " step " << step;
      ASSERT_EQ(ring.empty(), held == 0);
      ASSERT_EQ(ring.full(), held == capacity);
      for (std::size_t i = 0; i < held; ++i) {
        ASSERT_EQ(ring[i].id, pushed[first + i]) << "capacity " << capacity << " step " << step << " i " << i;
        ASSERT_EQ(ring[i].x, 0.5 * pushed[first + i]);
      }
      if (held > 0) {
        ASSERT_EQ(ring.front().id, pushed[first]);
        ASSERT_EQ(ring.back().id, pushed.back());
      }
    }
  }
}

}  // namespace
}  // namespace hivecal::ring_test
