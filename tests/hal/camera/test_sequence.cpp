// SPDX-License-Identifier: Apache-2.0
// Tests for sequence-gap drop counting, including 32-bit wraparound and driver restarts.
#include <gtest/gtest.h>

#include <cstdint>

#include "tacse3/hal/camera/sequence.hpp"

namespace tacse3::hal {
namespace {

TEST(SequenceTracker, ConsecutiveNumbersDropNothing) {
  SequenceTracker t;
  for (std::uint32_t s = 10; s < 1000; ++s) EXPECT_EQ(t.update(s), 0u);
  EXPECT_EQ(t.dropped(), 0u);
}

TEST(SequenceTracker, GapsAreCounted) {
  SequenceTracker t;
  EXPECT_EQ(t.update(0), 0u);
  EXPECT_EQ(t.update(1), 0u);
  EXPECT_EQ(t.update(4), 2u);  // 2 and 3 missing
  EXPECT_EQ(t.update(5), 0u);
  EXPECT_EQ(t.update(15), 9u);
  EXPECT_EQ(t.dropped(), 11u);
}

TEST(SequenceTracker, FirstFrameIsNeverADrop) {
  SequenceTracker t;
  EXPECT_EQ(t.update(123456), 0u);  // e.g. libcamera starting mid-count
  EXPECT_EQ(t.dropped(), 0u);
}

TEST(SequenceTracker, WrapsAround) {
  SequenceTracker t;
  t.update(0xFFFFFFFDu);
  EXPECT_EQ(t.update(0xFFFFFFFEu), 0u);
  EXPECT_EQ(t.update(0xFFFFFFFFu), 0u);
  EXPECT_EQ(t.update(0u), 0u);
  EXPECT_EQ(t.update(3u), 2u);
  t.update(0xFFFFFFFEu);  // backwards: a restart, not 4 billion drops
  EXPECT_EQ(t.restarts(), 1u);
  EXPECT_EQ(t.update(1u), 2u);  // 0xFFFFFFFF and 0 missing across the wrap
  EXPECT_EQ(t.dropped(), 4u);
}

TEST(SequenceTracker, BackwardJumpIsARestart) {
  SequenceTracker t;
  t.update(500);
  EXPECT_EQ(t.update(0), 0u);  // driver restarted its counter (STREAMOFF/ON)
  EXPECT_EQ(t.restarts(), 1u);
  EXPECT_EQ(t.update(1), 0u);
  EXPECT_EQ(t.update(3), 1u);
  EXPECT_EQ(t.dropped(), 1u);
}

TEST(SequenceTracker, RepeatIsNotADrop) {
  SequenceTracker t;
  t.update(7);
  EXPECT_EQ(t.update(7), 0u);
  EXPECT_EQ(t.repeats(), 1u);
  EXPECT_EQ(t.update(8), 0u);
}

TEST(SequenceTracker, MaxGapBoundary) {
  SequenceTracker t(100);
  t.update(0);
  EXPECT_EQ(t.update(100), 99u);  // a step of exactly max_gap is a gap
  EXPECT_EQ(t.update(201), 0u);   // a step beyond it is a restart
  EXPECT_EQ(t.restarts(), 1u);
}

TEST(SequenceTracker, ResetForgetsThePreviousRun) {
  SequenceTracker t;
  t.update(10);
  t.reset();
  EXPECT_EQ(t.update(0), 0u);  // reopened device starts at 0: no drop, no restart
  EXPECT_EQ(t.restarts(), 0u);
  EXPECT_EQ(t.update(2), 1u);
}

}  // namespace
}  // namespace tacse3::hal
