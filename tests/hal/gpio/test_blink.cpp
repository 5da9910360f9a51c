// SPDX-License-Identifier: Apache-2.0
// Tests for the status LED blink pattern table.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "tacse3/hal/gpio/controller.hpp"

namespace tacse3::hal {
namespace {

constexpr std::int64_t kMs = 1'000'000;

// The LED level sampled every 10 ms over `ms`, as a string of '#' (on) and '.' (off).
std::string trace(LedState s, int ms) {
  std::string out;
  for (int t = 0; t < ms; t += 10) out += led_level(blink_pattern(s), t * kMs) ? '#' : '.';
  return out;
}

TEST(BlinkPattern, Table) {
  EXPECT_EQ(trace(LedState::kOff, 200), std::string(20, '.'));
  EXPECT_EQ(trace(LedState::kTracking, 200), std::string(20, '#'));
  const auto on = [](int ms) { return std::string(static_cast<std::size_t>(ms / 10), '#'); };
  const auto off = [](int ms) { return std::string(static_cast<std::size_t>(ms / 10), '.'); };
  EXPECT_EQ(trace(LedState::kBooting, 1000), on(250) + off(250) + on(250) + off(250));
  EXPECT_EQ(trace(LedState::kFault, 200), on(50) + off(50) + on(50) + off(50));
  EXPECT_EQ(trace(LedState::kDegraded, 1000), on(100) + off(150) + on(100) + off(650));
  const std::string nc = trace(LedState::kNoContact, 4000);
  EXPECT_EQ(nc.substr(0, 10), std::string(10, '#'));
  EXPECT_EQ(nc.substr(10, 190), std::string(190, '.'));
  EXPECT_EQ(nc.substr(200, 10), std::string(10, '#'));
}

TEST(BlinkPattern, Periods) {
  EXPECT_EQ(blink_pattern(LedState::kBooting).period_ns(), 500 * kMs);
  EXPECT_EQ(blink_pattern(LedState::kNoContact).period_ns(), 2000 * kMs);
  EXPECT_EQ(blink_pattern(LedState::kDegraded).period_ns(), 1000 * kMs);
  EXPECT_EQ(blink_pattern(LedState::kFault).period_ns(), 100 * kMs);
}

TEST(BlinkPattern, EveryStateIsDistinct) {
  const LedState all[] = {LedState::kOff,      LedState::kBooting,  LedState::kNoContact,
                          LedState::kTracking, LedState::kDegraded, LedState::kFault};
  for (LedState a : all) {
    for (LedState b : all) {
      if (a != b) {
        EXPECT_NE(trace(a, 4000), trace(b, 4000)) << to_string(a) << " " << to_string(b);
      }
    }
  }
}

TEST(BlinkPattern, NextChange) {
  const BlinkPattern& p = blink_pattern(LedState::kDegraded);  // 100 on 150 off 100 on 650 off
  EXPECT_EQ(led_next_change_ns(p, 0), 100 * kMs);
  EXPECT_EQ(led_next_change_ns(p, 99 * kMs), 1 * kMs);
  EXPECT_EQ(led_next_change_ns(p, 100 * kMs), 150 * kMs);
  EXPECT_EQ(led_next_change_ns(p, 400 * kMs), 600 * kMs);
  EXPECT_EQ(led_next_change_ns(p, 1000 * kMs), 100 * kMs);  // wrapped
  EXPECT_EQ(led_next_change_ns(blink_pattern(LedState::kTracking), 5), INT64_MAX);
  EXPECT_EQ(led_next_change_ns(blink_pattern(LedState::kOff), 5), INT64_MAX);
}

}  // namespace
}  // namespace tacse3::hal
