// SPDX-License-Identifier: Apache-2.0
// Tests for the time-based debouncer with synthetic edge timestamps.
#include <gtest/gtest.h>

#include <cstdint>

#include "tacse3/hal/gpio/controller.hpp"

namespace tacse3::hal {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(Debouncer, BouncyPressCommitsOnceAWindowAfterTheLastBounce) {
  Debouncer d(20 * kMs, false);
  d.reset(false, 0);
  // Contact bounce over 3 ms, then held.
  d.edge(true, 1000 * kMs);
  d.edge(false, 1000 * kMs + 300'000);
  d.edge(true, 1000 * kMs + 900'000);
  d.edge(false, 1001 * kMs + 500'000);
  d.edge(true, 1003 * kMs);
  EXPECT_TRUE(d.pending());
  EXPECT_EQ(d.deadline_ns(), 1023 * kMs);
  int changes = 0;
  for (std::int64_t t = 1000 * kMs; t < 1100 * kMs; t += kMs / 2) {
    if (d.update(t)) {
      ++changes;
      EXPECT_EQ(t, 1023 * kMs);  // first update at/after the deadline
      EXPECT_TRUE(d.level());
    }
  }
  EXPECT_EQ(changes, 1);
  EXPECT_FALSE(d.pending());
  EXPECT_EQ(d.deadline_ns(), INT64_MAX);
}

TEST(Debouncer, GlitchShorterThanTheWindowNeverShows) {
  Debouncer d(20 * kMs, false);
  d.reset(false, 0);
  d.edge(true, 50 * kMs);
  d.edge(false, 55 * kMs);  // 5 ms spike (EMI)
  for (std::int64_t t = 50 * kMs; t < 200 * kMs; t += kMs) EXPECT_FALSE(d.update(t));
  EXPECT_FALSE(d.level());
}

TEST(Debouncer, ExactlyTheWindowCommits) {
  Debouncer d(20 * kMs, false);
  d.reset(false, 0);
  d.edge(true, 100 * kMs);
  EXPECT_FALSE(d.update(120 * kMs - 1));
  EXPECT_TRUE(d.update(120 * kMs));
  EXPECT_TRUE(d.level());
}

TEST(Debouncer, PressAndReleaseAreSeparateChanges) {
  Debouncer d(10 * kMs, false);
  d.reset(false, 0);
  d.edge(true, 10 * kMs);
  EXPECT_TRUE(d.update(25 * kMs));
  EXPECT_TRUE(d.level());
  d.edge(false, 200 * kMs);
  d.edge(true, 201 * kMs);  // release bounce
  d.edge(false, 202 * kMs);
  EXPECT_FALSE(d.update(211 * kMs));
  EXPECT_TRUE(d.update(212 * kMs));
  EXPECT_FALSE(d.level());
}

TEST(Debouncer, LostEdgeRestartsTheWindow) {
  // Two "rising" edges in a row (the falling one was lost): the line was not stable.
  Debouncer d(20 * kMs, false);
  d.reset(false, 0);
  d.edge(true, 10 * kMs);
  d.edge(true, 25 * kMs);
  EXPECT_FALSE(d.update(35 * kMs));
  EXPECT_TRUE(d.update(45 * kMs));
}

TEST(Debouncer, ResetSetsTheLevelWithoutAChange) {
  Debouncer d(20 * kMs, false);
  d.reset(true, 5 * kMs);  // button held at start
  EXPECT_TRUE(d.level());
  EXPECT_FALSE(d.update(1000 * kMs));
}

}  // namespace
}  // namespace tacse3::hal
