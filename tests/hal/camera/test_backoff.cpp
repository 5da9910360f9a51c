// SPDX-License-Identifier: Apache-2.0
// Tests for the reconnect backoff schedule: doubling, cap, attempt limit, reset.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "tacse3/hal/camera/backoff.hpp"

namespace tacse3::hal {
namespace {

std::vector<std::int64_t> delays_ms(Backoff& b, int n) {
  std::vector<std::int64_t> out;
  for (int i = 0; i < n; ++i) {
    const std::int64_t d = b.next_delay_ns();
    out.push_back(d < 0 ? -1 : d / 1'000'000);
  }
  return out;
}

TEST(Backoff, DoublesFromInitialAndCapsAtMax) {
  Backoff b(ReconnectPolicy{100, 5000, 0});
  EXPECT_EQ(delays_ms(b, 10),
            (std::vector<std::int64_t>{100, 200, 400, 800, 1600, 3200, 5000, 5000, 5000, 5000}));
  EXPECT_EQ(b.attempts(), 10);
  EXPECT_FALSE(b.exhausted());
}

TEST(Backoff, CapThatIsNotAPowerOfTwoMultiple) {
  Backoff b(ReconnectPolicy{30, 100, 0});
  EXPECT_EQ(delays_ms(b, 5), (std::vector<std::int64_t>{30, 60, 100, 100, 100}));
}

TEST(Backoff, GivesUpAfterMaxAttempts) {
  Backoff b(ReconnectPolicy{50, 1000, 3});
  EXPECT_EQ(delays_ms(b, 5), (std::vector<std::int64_t>{50, 100, 200, -1, -1}));
  EXPECT_TRUE(b.exhausted());
  b.reset();
  EXPECT_FALSE(b.exhausted());
  EXPECT_EQ(b.next_delay_ns(), 50'000'000);
}

TEST(Backoff, ResetStartsOverAtInitial) {
  Backoff b(ReconnectPolicy{100, 5000, 0});
  delays_ms(b, 4);
  b.reset();
  EXPECT_EQ(b.attempts(), 0);
  EXPECT_EQ(b.next_delay_ns(), 100'000'000);
}

TEST(Backoff, ManyAttemptsNeverOverflow) {
  Backoff b(ReconnectPolicy{1, 2'000'000'000, 0});
  std::int64_t last = 0;
  for (int i = 0; i < 200; ++i) last = b.next_delay_ns();
  EXPECT_EQ(last, std::int64_t{2'000'000'000} * 1'000'000);
}

TEST(Backoff, SanitizeClampsNonsense) {
  const ReconnectPolicy p = Backoff::sanitize(ReconnectPolicy{0, -5, -2});
  EXPECT_EQ(p.initial_ms, 1);
  EXPECT_EQ(p.max_ms, 1);
  EXPECT_EQ(p.max_attempts, 0);
}

}  // namespace
}  // namespace tacse3::hal
