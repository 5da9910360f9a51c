// SPDX-License-Identifier: Apache-2.0
// Tests for the lock-free SPSC ring used between libcamera's thread and the capture thread.
#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

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
