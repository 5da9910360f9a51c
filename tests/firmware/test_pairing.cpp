// SPDX-License-Identifier: Apache-2.0
// firmware tests: pairing frames by timestamp with jitter, drops and one silent sensor.
#include <gtest/gtest.h>

#include <cstdint>
#include <deque>
#include <random>
#include <vector>

#include "tacse3/firmware/pairing.hpp"

using namespace tacse3::firmware;

namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kPeriod = 8'333'333;

PendingFrame at(std::int64_t t, std::int64_t arrival) {
  return {true, t, arrival};
}

}  // namespace

TEST(Pairing, ConfigFromTheBoard) {
  const PairingConfig c = pairing_config(2000, 50);
  EXPECT_EQ(c.tolerance_ns, 2 * kMs);
  EXPECT_EQ(c.max_wait_ns, 50 * kMs);
}

TEST(Pairing, RulesOneByOne) {
  const PairingConfig c = pairing_config(2000, 50);
  const PendingFrame none{};
  // Within the tolerance, either order: a pair; exactly at the tolerance still pairs.
  EXPECT_EQ(decide_pairing(at(100 * kMs, 0), at(100 * kMs + 1500000, 0), true, true, 0, 0, c),
            PairAction::kPair);
  EXPECT_EQ(decide_pairing(at(100 * kMs + 2 * kMs, 0), at(100 * kMs, 0), true, true, 0, 0, c),
            PairAction::kPair);
  // Further apart: the older goes alone (its partner was dropped).
  EXPECT_EQ(decide_pairing(at(100 * kMs, 0), at(100 * kMs + kPeriod, 0), true, true, 0, 0, c),
            PairAction::kLeftAlone);
  EXPECT_EQ(decide_pairing(at(100 * kMs + 2 * kMs + 1, 0), at(100 * kMs, 0), true, true, 0, 0, c),
            PairAction::kRightAlone);
  // One head, the other sensor alive: wait up to max_wait after arrival, then alone.
  EXPECT_EQ(decide_pairing(at(100 * kMs, 5 * kMs), none, true, true, 0, 5 * kMs + 49 * kMs, c),
            PairAction::kWait);
  EXPECT_EQ(decide_pairing(at(100 * kMs, 5 * kMs), none, true, true, 0, 5 * kMs + 50 * kMs, c),
            PairAction::kLeftAlone);
  // ... and at once when the other sensor is stale / lost.
  EXPECT_EQ(decide_pairing(none, at(100 * kMs, 5 * kMs), false, true, 0, 5 * kMs, c),
            PairAction::kRightAlone);
  // A head not newer than the last sample is dropped.
  EXPECT_EQ(decide_pairing(at(100 * kMs, 0), at(101 * kMs, 0), true, true, 100 * kMs, 0, c),
            PairAction::kDropLeft);
  EXPECT_EQ(decide_pairing(none, at(99 * kMs, 0), true, true, 100 * kMs, 0, c),
            PairAction::kDropRight);
  EXPECT_EQ(decide_pairing(none, none, true, true, 0, 0, c), PairAction::kWait);
}

// Two 120 Hz streams with +-1.5 ms timestamp jitter and independent 5 % frame drops, delivered
// with up to 3 ms of arrival skew; the right sensor goes silent for 100 frames in the middle.
// A model of the DSP loop's queues must emit one sample per instant, pair the frames of one
// instant, never go back in time, and account for every frame.
TEST(Pairing, StreamsWithJitterDropsAndASilentSensor) {
  const PairingConfig c = pairing_config(2000, 50);
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::int64_t> jitter(-1'500'000, 1'500'000);
  std::uniform_int_distribution<std::int64_t> skew(0, 3'000'000);
  std::bernoulli_distribution drop(0.05);
  struct F {
    std::int64_t t, arrival;
    int instant;
  };
  std::deque<F> q[2];
  const int n = 600;
  int both = 0, left_only = 0, right_only = 0;
  for (int k = 0; k < n; ++k) {
    const bool silent = k >= 250 && k < 350;
    const bool l = !drop(rng);
    const bool r = !drop(rng) && !silent;
    const std::int64_t base = 1'000'000'000 + k * kPeriod;
    if (l) q[0].push_back({base + jitter(rng) / 2, base + skew(rng), k});
    if (r) q[1].push_back({base + jitter(rng) / 2, base + skew(rng), k});
    both += l && r;
    left_only += l && !r;
    right_only += r && !l;
  }
  // Run the loop at 0.5 ms steps; a sensor is alive while its last frame is < 50 ms old.
  std::int64_t last_t = INT64_MIN;
  std::int64_t last_seen[2] = {0, 0};
  PendingFrame head[2];
  int head_instant[2] = {-1, -1};
  int pairs = 0, singles = 0, drops = 0, mismatched = 0;
  std::vector<std::int64_t> emitted;
  for (std::int64_t now = 1'000'000'000; now < 1'000'000'000 + (n + 20) * kPeriod; now += 500'000) {
    for (int s = 0; s < 2; ++s) {
      if (!head[s].present && !q[s].empty() && q[s].front().arrival <= now) {
        head[s] = {true, q[s].front().t, now};
        head_instant[s] = q[s].front().instant;
        last_seen[s] = now;
        q[s].pop_front();
      }
    }
    for (;;) {
      const bool alive[2] = {now - last_seen[0] < 50 * kMs, now - last_seen[1] < 50 * kMs};
      const PairAction a = decide_pairing(head[0], head[1], alive[0], alive[1], last_t, now, c);
      if (a == PairAction::kWait) break;
      if (a == PairAction::kPair) {
        mismatched += head_instant[0] != head_instant[1];
        last_t = std::max(head[0].t_ns, head[1].t_ns);
        head[0].present = head[1].present = false;
        ++pairs;
      } else if (a == PairAction::kLeftAlone || a == PairAction::kRightAlone) {
        const int s = a == PairAction::kLeftAlone ? 0 : 1;
        last_t = head[s].t_ns;
        head[s].present = false;
        ++singles;
      } else {
        head[a == PairAction::kDropLeft ? 0 : 1].present = false;
        ++drops;
        continue;
      }
      ASSERT_TRUE(emitted.empty() || last_t > emitted.back());
      emitted.push_back(last_t);
    }
  }
  EXPECT_EQ(mismatched, 0) << "a pair must be two frames of one instant";
  // Every frame is accounted for: in a pair, alone, or dropped as late.
  EXPECT_EQ(2 * pairs + singles + drops, 2 * both + left_only + right_only);
  // A sensor that (re)appears -- the right one at the start, when it is not yet known to be
  // alive, and after its silence -- can cost the instant whose left frame arrived first and went
  // alone: at most one per appearance. Every other instant with both frames is a pair.
  EXPECT_LE(drops, 2);
  EXPECT_GE(pairs, both - 2);
  EXPECT_TRUE(q[0].empty() && q[1].empty() && !head[0].present && !head[1].present);
}
