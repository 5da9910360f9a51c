// SPDX-License-Identifier: Apache-2.0
// SpscSlotQueue: FIFO order, capacity, the lowest free slot first, elements built only in slots
// that are handed out, and two threads that lose nothing.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <set>
#include <thread>

#include "tacse3/firmware/slot_queue.hpp"

namespace tacse3::firmware {
namespace {

struct Counted {
  static inline int built = 0;
  static inline int destroyed = 0;
  Counted() noexcept { ++built; }
  ~Counted() { ++destroyed; }
  std::uint32_t value = 0;
  std::array<std::uint32_t, 15> payload{};  // the rest of a 64-byte element
};

using Queue4 = SpscSlotQueue<std::uint32_t, 4>;

// Fills the next slot with v and hands it over; the slot, or null when the queue was full.
std::uint32_t* put(Queue4& q, std::uint32_t v) {
  std::uint32_t* s = q.back();
  if (s != nullptr) {
    *s = v;
    q.commit();
  }
  return s;
}

// Pops first..last and checks each value, then that the queue is empty.
void expect_pops(Queue4& q, std::uint32_t first, std::uint32_t last) {
  for (std::uint32_t v = first; v <= last; ++v) {
    const std::uint32_t* s = q.front();
    ASSERT_NE(s, nullptr) << v;
    if (s != nullptr) {
      EXPECT_EQ(*s, v);
    }
    q.pop();
  }
  EXPECT_TRUE(q.empty());
}

TEST(SpscSlotQueue, HandsSlotsOverInOrderUpToItsCapacity) {
  Queue4 q;
  EXPECT_EQ(q.front(), nullptr);
  for (std::uint32_t v = 0; v < 4; ++v) ASSERT_NE(put(q, v), nullptr) << v;
  EXPECT_EQ(q.back(), nullptr) << "a full queue refuses";
  EXPECT_EQ(q.size(), 4u);
  expect_pops(q, 0, 3);
  q.pop();  // popping an empty queue changes nothing
  EXPECT_TRUE(q.empty());
  EXPECT_NE(q.back(), nullptr);
}

// The oldest element's value, popped (UINT32_MAX when empty).
std::uint32_t pop_value(SpscSlotQueue<Counted, 16>& q) {
  const Counted* s = q.front();
  if (s == nullptr) return UINT32_MAX;
  const std::uint32_t v = s->value;
  q.pop();
  return v;
}

// A ring would walk through all 16 slots; one or two in flight use only the lowest two.
TEST(SpscSlotQueue, ReusesTheLowestFreeSlotsAndBuildsNoOther) {
  Counted::built = Counted::destroyed = 0;
  {
    SpscSlotQueue<Counted, 16> q;
    EXPECT_EQ(Counted::built, 0) << "no slot is built before it is handed out";
    std::set<const Counted*> used;
    for (std::uint32_t i = 0; i < 100; ++i) {
      Counted* a = q.back();
      ASSERT_NE(a, nullptr);
      a->value = 2 * i;
      q.commit();
      Counted* b = q.back();
      ASSERT_NE(b, nullptr);
      b->value = 2 * i + 1;
      q.commit();
      used.insert(a);
      used.insert(b);
      ASSERT_EQ(pop_value(q), 2 * i);
      ASSERT_EQ(pop_value(q), 2 * i + 1);
    }
    EXPECT_EQ(used.size(), 2u);
    EXPECT_EQ(q.slots_built(), 2u);
    EXPECT_EQ(Counted::built, 2);
  }
  EXPECT_EQ(Counted::destroyed, 2) << "the built slots are destroyed with the queue";
}

// A slot freed in the middle is the next one filled, and the order stays the commit order.
TEST(SpscSlotQueue, FillsAFreedSlotNextAndKeepsTheCommitOrder) {
  Queue4 q;
  const std::uint32_t* first = put(q, 0);
  ASSERT_NE(first, nullptr);
  ASSERT_NE(put(q, 1), nullptr);
  ASSERT_NE(put(q, 2), nullptr);
  q.pop();  // frees the first slot
  EXPECT_EQ(put(q, 3), first) << "the lowest free slot";
  expect_pops(q, 1, 3);
}

TEST(SpscSlotQueue, TwoThreadsKeepOrderAndLoseNothing) {
  SpscSlotQueue<Counted, 8> q;
  constexpr std::uint32_t kCount = 200'000;
  std::thread producer([&] {
    for (std::uint32_t i = 0; i < kCount;) {
      Counted* s = q.back();
      if (s == nullptr) {
        std::this_thread::yield();  // full: let the consumer run (2-core CI)
        continue;
      }
      s->value = i;
      s->payload.fill(i * 7U);
      q.commit();
      ++i;
    }
  });
  std::uint32_t expected = 0;
  std::uint64_t mismatches = 0;
  while (expected < kCount) {
    const Counted* s = q.front();
    if (s == nullptr) {
      std::this_thread::yield();
      continue;
    }
    if (s->value != expected || s->payload.front() != expected * 7U ||
        s->payload.back() != expected * 7U)
      ++mismatches;
    q.pop();
    ++expected;
  }
  producer.join();
  EXPECT_EQ(mismatches, 0u);
  EXPECT_TRUE(q.empty());
}

// The capture loop asks again while it waits: a retry after the consumer freed a lower slot gets
// that slot, and commit() hands over the one the last back() returned.
TEST(SpscSlotQueue, ARetriedBackCommitsTheSlotItReturnedLast) {
  Queue4 q;
  ASSERT_NE(put(q, 0), nullptr);
  ASSERT_NE(put(q, 1), nullptr);
  const std::uint32_t* third = q.back();  // slot 2, not filled
  q.pop();                                // frees slot 0
  std::uint32_t* again = q.back();
  ASSERT_NE(again, nullptr);
  EXPECT_NE(again, third) << "the lower slot, freed in between";
  *again = 2;
  q.commit();
  expect_pops(q, 1, 2);
  EXPECT_EQ(q.slots_built(), 3u);
}

// reserve() builds the slots a producer will use up front, and back() then builds no other.
TEST(SpscSlotQueue, ReserveBuildsTheFirstSlotsOnly) {
  Counted::built = Counted::destroyed = 0;
  {
    SpscSlotQueue<Counted, 16> q;
    q.reserve(4);
    EXPECT_EQ(Counted::built, 4);
    EXPECT_EQ(q.slots_built(), 4u);
    for (int round = 0; round < 50; ++round) {
      for (int k = 0; k < 4; ++k) {
        ASSERT_NE(q.back(), nullptr);
        q.commit();
      }
      for (int k = 0; k < 4; ++k) q.pop();
    }
    EXPECT_EQ(Counted::built, 4) << "four in use at most: no fifth slot built";
    q.reserve(40);  // clamped to the capacity
    EXPECT_EQ(q.slots_built(), 16u);
  }
  EXPECT_EQ(Counted::destroyed, 16);
}

}  // namespace
}  // namespace tacse3::firmware
