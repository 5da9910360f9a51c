// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: reassembler fault injection (CRC, skipped/repeated counters, truncation, stale).
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;
using R = tp::CycleReassembler::Result;

namespace {

constexpr std::uint64_t kPeriodUs = 8333;

tp::CycleFrames make_cycle(int k, std::uint8_t node = 1,
                           tp::FrameMode mode = tp::FrameMode::kClassic) {
  tp::Cycle c;
  c.timestamp_us = 1000000 + static_cast<std::uint64_t>(k) * kPeriodUs;
  c.estimate_valid = true;
  c.angular = {0.001 * k, -0.002 * k, 0.5};
  c.linear = {0.0001 * k, 0.0, -0.01};
  c.orientation = {1.0, 0.0, 0.0, 0.0};
  c.position = {0.00002 * k, 0.0, 0.0};
  tp::TxConfig tx;
  tx.endpoint.node_id = node;
  tx.frame_mode = mode;
  tp::CycleFrames f;
  EXPECT_EQ(tp::encode_cycle(c, static_cast<std::uint8_t>(k), tx, f), tp::Status::kOk);
  return f;
}

struct Harness {
  tp::CycleReassembler r{tp::Endpoint{}};
  std::vector<tp::Cycle> samples;
  void feed(const tp::CanFrame& f) {
    tp::Cycle c;
    if (r.feed(f, c) == R::kComplete) samples.push_back(c);
  }
  void feed_cycle(const tp::CycleFrames& fr) {
    for (std::size_t i = 0; i < fr.count; ++i) feed(fr.frames[i]);
  }
};

}  // namespace

TEST(Reassembler, CleanStreamEveryCycleOnce) {
  Harness run;
  for (int k = 0; k < 40; ++k) run.feed_cycle(make_cycle(k));
  ASSERT_EQ(run.samples.size(), 40u);
  for (int k = 0; k < 40; ++k) {
    EXPECT_EQ(run.samples[static_cast<std::size_t>(k)].counter, k & 15);
    EXPECT_EQ(run.samples[static_cast<std::size_t>(k)].timestamp_us,
              1000000 + static_cast<std::uint64_t>(k) * kPeriodUs);
    EXPECT_DOUBLE_EQ(run.samples[static_cast<std::size_t>(k)].angular.x, 0.001 * k);
  }
  const auto& s = run.r.stats();
  EXPECT_EQ(s.frames, 200u);
  EXPECT_EQ(s.samples, 40u);
  EXPECT_EQ(s.crc_errors + s.counter_gaps + s.repeated + s.incomplete + s.stale, 0u);
}

TEST(Reassembler, FrameOrderWithinACycleDoesNotMatter) {
  Harness run;
  for (int k = 0; k < 10; ++k) {
    tp::CycleFrames f = make_cycle(k);
    std::rotate(f.frames.begin(), f.frames.begin() + (k % 5), f.frames.end());
    if (k % 2 == 1) std::reverse(f.frames.begin(), f.frames.end());
    run.feed_cycle(f);
  }
  EXPECT_EQ(run.samples.size(), 10u);
  EXPECT_EQ(run.r.stats().incomplete, 0u);
}

TEST(Reassembler, CorruptedCrcDropsThatCycleOnly) {
  Harness run;
  for (int k = 0; k < 8; ++k) {
    tp::CycleFrames f = make_cycle(k);
    if (k == 3) f.frames[2].data[1] ^= 0x40;  // one bit of TwistLinear
    if (k == 5) f.frames[4].data[7] ^= 0xFF;  // the CRC byte of PosePosition
    run.feed_cycle(f);
  }
  const auto& s = run.r.stats();
  EXPECT_EQ(s.crc_errors, 2u);
  EXPECT_EQ(s.incomplete, 2u);
  EXPECT_EQ(s.samples, 6u);
  EXPECT_EQ(s.counter_gaps, 0u);
  for (const tp::Cycle& c : run.samples) EXPECT_TRUE(c.counter != 3 && c.counter != 5);
}

TEST(Reassembler, SkippedCountersAreGaps) {
  Harness run;
  for (int k : {0, 1, 2, 5, 6, 10}) run.feed_cycle(make_cycle(k));
  EXPECT_EQ(run.samples.size(), 6u);
  EXPECT_EQ(run.r.stats().counter_gaps, 2u + 3u);
  EXPECT_EQ(run.r.stats().incomplete, 0u);
}

TEST(Reassembler, RepeatedCounterIsCaughtAndNotEmittedTwice) {
  Harness run;
  run.feed_cycle(make_cycle(0));
  run.feed_cycle(make_cycle(1));
  run.feed_cycle(make_cycle(1));  // the whole cycle again
  run.feed_cycle(make_cycle(2));
  EXPECT_EQ(run.samples.size(), 3u);
  EXPECT_EQ(run.r.stats().repeated, 5u);
  // A late frame of the previous cycle does not disturb the cycle in progress.
  const tp::CycleFrames c3 = make_cycle(3);
  const tp::CycleFrames c2 = make_cycle(2);
  run.feed(c3.frames[0]);
  run.feed(c3.frames[1]);
  run.feed(c2.frames[3]);
  for (std::size_t i = 2; i < 5; ++i) run.feed(c3.frames[i]);
  EXPECT_EQ(run.samples.size(), 4u);
  EXPECT_EQ(run.r.stats().repeated, 6u);
  EXPECT_EQ(run.r.stats().incomplete, 0u);
  // A duplicated frame inside a cycle is counted once and ignored.
  const tp::CycleFrames c4 = make_cycle(4);
  run.feed(c4.frames[0]);
  run.feed(c4.frames[0]);
  for (std::size_t i = 1; i < 5; ++i) run.feed(c4.frames[i]);
  EXPECT_EQ(run.samples.size(), 5u);
  EXPECT_EQ(run.r.stats().repeated, 7u);
}

TEST(Reassembler, TruncatedCyclesAreIncomplete) {
  Harness run;
  for (int k = 0; k < 6; ++k) {
    tp::CycleFrames f = make_cycle(k);
    if (k == 2) f.count = 4;  // PosePosition never sent
    if (k == 4) f.count = 1;  // only the Timestamp
    run.feed_cycle(f);
  }
  EXPECT_EQ(run.samples.size(), 4u);
  EXPECT_EQ(run.r.stats().incomplete, 2u);
  EXPECT_EQ(run.r.stats().counter_gaps, 0u);
  // A truncated cycle followed by a gap: one incomplete, and the skipped values are gaps.
  Harness run2;
  tp::CycleFrames a = make_cycle(0);
  a.count = 3;
  run2.feed_cycle(a);
  run2.feed_cycle(make_cycle(3));
  EXPECT_EQ(run2.r.stats().incomplete, 1u);
  EXPECT_EQ(run2.r.stats().counter_gaps, 2u);
  EXPECT_EQ(run2.samples.size(), 1u);
}

TEST(Reassembler, StaleTimestampIsDropped) {
  Harness run;
  run.feed_cycle(make_cycle(0));
  run.feed_cycle(make_cycle(1));
  // Cycle with the next counter but the timestamp of cycle 1: stale.
  tp::Cycle c;
  c.timestamp_us = 1000000 + kPeriodUs;
  tp::CycleFrames f;
  ASSERT_EQ(tp::encode_cycle(c, 2, tp::TxConfig{}, f), tp::Status::kOk);
  run.feed_cycle(f);
  run.feed_cycle(make_cycle(3));
  EXPECT_EQ(run.samples.size(), 3u);
  EXPECT_EQ(run.r.stats().stale, 1u);
  EXPECT_EQ(run.samples.back().counter, 3);
}

TEST(Reassembler, OtherNodesAndOtherMessagesAreIgnored) {
  Harness run;
  std::array<tp::CanFrame, 4> status{};
  ASSERT_EQ(tp::encode_status_group(tp::StatusGroup{}, 0, tp::TxConfig{}, status), tp::Status::kOk);
  for (int k = 0; k < 5; ++k) {
    const tp::CycleFrames mine = make_cycle(k, 1);
    const tp::CycleFrames other = make_cycle(k + 7, 2);
    for (std::size_t i = 0; i < 5; ++i) {
      run.feed(other.frames[i]);
      run.feed(mine.frames[i]);
      run.feed(status[i % 4]);
    }
  }
  EXPECT_EQ(run.samples.size(), 5u);
  EXPECT_EQ(run.r.stats().frames, 25u);
  EXPECT_EQ(run.r.stats().counter_gaps + run.r.stats().repeated, 0u);
}

TEST(Reassembler, CanFdFramesAndFaults) {
  Harness run;
  for (int k = 0; k < 20; ++k) {
    tp::CycleFrames f = make_cycle(k, 1, tp::FrameMode::kFd);
    ASSERT_EQ(f.count, 1u);
    if (k == 4) f.frames[0].data[20] ^= 1;  // CRC error
    if (k == 7) continue;                   // lost frame: a gap
    if (k == 9) f.frames[0].len = 48;       // wrong length
    if (k == 11) {                          // counters disagree (CRC recomputed)
      f.frames[0].data[13] = static_cast<std::uint8_t>(f.frames[0].data[13] ^ 0x10);
      tp::finish_frame(f.frames[0]);
    }
    run.feed_cycle(f);
    if (k == 15) run.feed_cycle(f);  // repeated
  }
  const auto& s = run.r.stats();
  EXPECT_EQ(s.crc_errors, 1u);
  EXPECT_EQ(s.length_errors, 1u);
  EXPECT_EQ(s.counter_errors, 1u);
  EXPECT_EQ(s.repeated, 1u);
  EXPECT_EQ(s.counter_gaps, 4u);  // 4, 7, 9, 11 never accepted
  EXPECT_EQ(s.samples, 16u);
  EXPECT_EQ(run.samples.size(), 16u);
}

TEST(CounterChecker, GapsAndRepeats) {
  tp::CounterChecker c;
  EXPECT_EQ(c.check(14), tp::CounterChecker::Result::kFirst);
  EXPECT_EQ(c.check(15), tp::CounterChecker::Result::kInSequence);
  EXPECT_EQ(c.check(0), tp::CounterChecker::Result::kInSequence);
  EXPECT_EQ(c.check(0), tp::CounterChecker::Result::kRepeated);
  EXPECT_EQ(c.check(3), tp::CounterChecker::Result::kGap);
  EXPECT_EQ(c.gaps(), 2u);
  EXPECT_EQ(c.repeated(), 1u);
}
