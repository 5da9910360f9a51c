// SPDX-License-Identifier: Apache-2.0
// Tests for the lock-free SPSC ring used between libcamera's thread and the capture thread,
// and in place between a pad's thread and the DSP thread.
#include <gtest/gtest.h>

#include <cstdint>
#include <thread>
#include <vector>

#include "tacse3/hal/camera/spsc_ring.hpp"

namespace tacse3::hal {
namespace {

TEST(SpscRing, FillsToCapacityThenRefuses) {
  SpscRing<std::uint32_t, 4> r;
  EXPECT_TRUE(r.empty());
  for (std::uint32_t i = 0; i < 4; ++i) EXPECT_TRUE(r.push(i));
  EXPECT_FALSE(r.push(99));
  EXPECT_EQ(r.size(), 4u);
  std::uint32_t v = 0;
  for (std::uint32_t i = 0; i < 4; ++i) {
    ASSERT_TRUE(r.pop(v));
    EXPECT_EQ(v, i);
  }
  EXPECT_FALSE(r.pop(v));
}

TEST(SpscRing, HandsSlotsOverInPlaceInOrderUpToItsCapacity) {
  SpscRing<int, 4> ring;
  EXPECT_EQ(ring.front(), nullptr);
  std::vector<int*> slots;
  for (int i = 0; i < 4; ++i) {
    int* slot = ring.back();
    ASSERT_NE(slot, nullptr);
    *slot = 10 + i;
    slots.push_back(slot);
    ring.commit();
  }
  EXPECT_EQ(ring.back(), nullptr) << "full";
  // The consumer reads the producer's slots themselves, oldest first.
  for (int i = 0; i < 4; ++i) {
    const int* slot = ring.front();
    ASSERT_NE(slot, nullptr);
    ASSERT_EQ(slot, slots[static_cast<std::size_t>(i)]);
    const int value = *slot;
    EXPECT_EQ(value, 10 + i);
    ring.pop();
    if (i == 0) {
      EXPECT_EQ(ring.back(), slots[0]) << "the first slot is free again";
    }
  }
  EXPECT_EQ(ring.front(), nullptr);
}

TEST(SpscRing, WrapsManyTimes) {
  SpscRing<std::uint32_t, 8> r;
  std::uint32_t next_in = 0;
  std::uint32_t next_out = 0;
  for (int round = 0; round < 1000; ++round) {
    for (int k = 0; k < 5; ++k) ASSERT_TRUE(r.push(next_in++));
    std::uint32_t v = 0;
    for (int k = 0; k < 5; ++k) {
      ASSERT_TRUE(r.pop(v));
      ASSERT_EQ(v, next_out++);
    }
  }
}

TEST(SpscRing, TwoThreadsKeepOrderAndLoseNothing) {
  SpscRing<std::uint32_t, 16> r;
  constexpr std::uint32_t kCount = 200'000;
  std::thread producer([&] {
    for (std::uint32_t i = 0; i < kCount;) {
      if (r.push(i)) {
        ++i;
      } else {
        std::this_thread::yield();  // full: let the consumer run (2-core CI)
      }
    }
  });
  std::uint32_t expected = 0;
  std::uint64_t mismatches = 0;
  while (expected < kCount) {
    std::uint32_t v = 0;
    if (r.pop(v)) {
      if (v != expected) ++mismatches;
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_EQ(mismatches, 0u);
  EXPECT_TRUE(r.empty());
}

}  // namespace
}  // namespace tacse3::hal
