// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: worst-case bus load recomputed from the message table (docs: "Bus load").
#include <gtest/gtest.h>

#include <random>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

TEST(BusLoad, FrameLengthFormulas) {
  EXPECT_EQ(tp::classic_frame_bits_worst(8, false), 135u);
  EXPECT_EQ(tp::classic_frame_bits_worst(8, true), 160u);
  EXPECT_EQ(tp::classic_frame_bits_worst(0, false), 55u);
  const tp::FdBits fd64 = tp::fd_frame_bits_worst(64, false);
  EXPECT_EQ(fd64.nominal, 34u);
  EXPECT_EQ(fd64.data, 678u);
  const tp::FdBits fd8 = tp::fd_frame_bits_worst(8, false);
  EXPECT_EQ(fd8.nominal, 34u);
  EXPECT_EQ(fd8.data, 113u);
}

TEST(BusLoad, ClassicAt500kIsAtMost25Percent) {
  const tp::BitTiming t{500000.0, 2000000.0};
  const tp::BusLoad std_ids =
      tp::worst_case_bus_load(tp::IdMode::kStandard, tp::FrameMode::kClassic, t);
  // 5 cycle frames x 120 + Status 120 + 3 status frames x 10 + commands 10 + ACKs 10.
  EXPECT_DOUBLE_EQ(std_ids.frames_per_s, 770.0);
  // 770 frames x 135 bits = 103950 bit/s.
  EXPECT_NEAR(std_ids.load, 103950.0 / 500000.0, 1e-12);
  EXPECT_LE(std_ids.load, 0.25);

  const tp::BusLoad ext =
      tp::worst_case_bus_load(tp::IdMode::kExtended, tp::FrameMode::kClassic, t);
  EXPECT_NEAR(ext.load, 770.0 * 160.0 / 500000.0, 1e-12);  // 24.64 %
  EXPECT_LE(ext.load, 0.25);

  const tp::BusLoad at1m = tp::worst_case_bus_load(tp::IdMode::kStandard, tp::FrameMode::kClassic,
                                                   tp::BitTiming{1000000.0, 2000000.0});
  EXPECT_NEAR(at1m.load, 0.10395, 1e-12);
}

TEST(BusLoad, CanFdMode) {
  const tp::BitTiming t{500000.0, 2000000.0};
  const tp::BusLoad fd = tp::worst_case_bus_load(tp::IdMode::kStandard, tp::FrameMode::kFd, t);
  EXPECT_DOUBLE_EQ(fd.frames_per_s, 120.0 + 120.0 + 30.0 + 20.0);
  // CycleFd 120 x (34/500k + 678/2M) + gripper 8-byte FD frames 160 x (34/500k + 113/2M)
  // + commands 10 x 135/500k (classic).
  const double want = 120.0 * (34.0 / 500000.0 + 678.0 / 2000000.0) +
                      160.0 * (34.0 / 500000.0 + 113.0 / 2000000.0) + 10.0 * 135.0 / 500000.0;
  EXPECT_NEAR(fd.load, want, 1e-12);
  EXPECT_LT(fd.load, 0.10);
  const tp::BusLoad no_brs =
      tp::worst_case_bus_load(tp::IdMode::kStandard, tp::FrameMode::kFd, t, false);
  EXPECT_LE(no_brs.load, 0.25);
}

TEST(BusLoad, ExactStuffingNeverExceedsTheWorstCase) {
  std::mt19937 rng(5);
  const tp::BitTiming t;
  unsigned max_seen = 0;
  for (int i = 0; i < 20000; ++i) {
    tp::CanFrame f;
    f.extended = (i & 1) != 0;
    f.id = rng() & (f.extended ? tp::kExtendedIdMask : tp::kStandardIdMask);
    f.len = static_cast<std::uint8_t>(rng() % 9);
    // Mix random payloads with long runs of equal bits (the stuffing worst case).
    for (std::size_t k = 0; k < f.len; ++k) {
      f.data[k] = (i % 3 == 0) ? static_cast<std::uint8_t>(rng()) : ((i % 3 == 1) ? 0x00 : 0xFF);
    }
    bool exact = false;
    const unsigned bits = tp::frame_bits_on_wire(f, t, &exact);
    EXPECT_TRUE(exact);
    EXPECT_LE(bits, tp::classic_frame_bits_worst(f.len, f.extended));
    EXPECT_GE(bits, (f.extended ? 67u : 47u) + 8u * f.len);
    if (!f.extended && f.len == 8) max_seen = std::max(max_seen, bits);
  }
  EXPECT_GT(max_seen, 120u);
  // The tacse3 frames as encoded are within the bound as well.
  tp::CycleFrames fr;
  ASSERT_EQ(tp::encode_cycle(tp::Cycle{}, 0, tp::TxConfig{}, fr), tp::Status::kOk);
  for (std::size_t k = 0; k < fr.count; ++k) {
    EXPECT_LE(tp::frame_bits_on_wire(fr.frames[k], t), 135u);
  }
}
