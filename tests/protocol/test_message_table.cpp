// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: consistency of the message table (layout rules the spec promises).
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

TEST(MessageTable, SignalsFitDoNotOverlapAndEndWithCrc) {
  std::set<unsigned> ids;
  for (const tp::MessageDef& m : tp::kMessages) {
    SCOPED_TRACE(std::string(m.name));
    EXPECT_TRUE(ids.insert(static_cast<unsigned>(m.id)).second);
    EXPECT_NE(static_cast<unsigned>(m.id), 0u);
    EXPECT_LE(static_cast<unsigned>(m.id), tp::kMessageIdMask);
    EXPECT_LE(m.signals.size(), tp::kMaxSignals);
    std::set<std::string> names;
    for (std::size_t i = 0; i < m.signals.size(); ++i) {
      const tp::SignalDef& a = m.signals[i];
      EXPECT_TRUE(names.insert(std::string(a.name)).second) << a.name;
      EXPECT_LE(a.start + a.length, m.length * 8u) << a.name;
      EXPECT_LE(a.raw_min, a.raw_max) << a.name;
      if (a.invalid != tp::Invalid::kNone) {
        const std::int64_t inv = tp::invalid_raw(a);
        EXPECT_TRUE(inv < a.raw_min || inv > a.raw_max) << a.name << ": marker inside range";
      }
      for (std::size_t j = i + 1; j < m.signals.size(); ++j) {
        const tp::SignalDef& b = m.signals[j];
        const bool same_mux_group = a.mux < 0 || b.mux < 0 || a.mux == b.mux;
        const bool overlap = a.start < b.start + b.length && b.start < a.start + a.length;
        EXPECT_FALSE(same_mux_group && overlap) << a.name << " / " << b.name;
      }
    }
    // CRC is the last byte; classic messages carry the counter in bits 52..55.
    const tp::SignalDef& last = m.signals.back();
    EXPECT_EQ(last.role, tp::Role::kCrc);
    EXPECT_EQ(last.start, (m.length - 1u) * 8u);
    const std::size_t c = tp::signal_index(
        m.signals, m.sender == tp::Sender::kController || m.id == tp::MessageId::kAck ? "Sequence"
                                                                                      : "Counter");
    ASSERT_NE(c, tp::kNoSignal);
    EXPECT_EQ(m.signals[c].start, 52u);
    EXPECT_EQ(m.signals[c].length, 4u);
  }
}

TEST(MessageTable, IdentifiersAvoidCanopenBroadcastIds) {
  for (unsigned node = tp::kMinNodeId; node <= tp::kMaxNodeId; ++node) {
    for (const tp::MessageDef& m : tp::kMessages) {
      const std::uint32_t id =
          tp::compose_id(tp::IdLayout{}, static_cast<std::uint8_t>(node), m.id);
      EXPECT_NE(id, 0x000u);  // NMT
      EXPECT_NE(id, 0x080u);  // SYNC
      EXPECT_NE(id, 0x100u);  // TIME
      tp::SplitId s;
      ASSERT_EQ(tp::split_id(tp::IdLayout{}, id, false, s), tp::Status::kOk);
      EXPECT_EQ(s.node, node);
      EXPECT_EQ(s.message, static_cast<unsigned>(m.id));
    }
  }
}

TEST(MessageTable, FdFrameIsTheClassicBlocksBackToBack) {
  const tp::MessageDef& fd = tp::message_def(tp::MessageId::kCycleFd);
  const tp::MessageId blocks[] = {tp::MessageId::kTimestamp, tp::MessageId::kTwistAngular,
                                  tp::MessageId::kTwistLinear, tp::MessageId::kPoseOrientation,
                                  tp::MessageId::kPosePosition};
  std::size_t n = 0;
  for (std::size_t b = 0; b < 5; ++b) {
    for (const tp::SignalDef& s : tp::message_def(blocks[b]).signals) {
      if (s.role == tp::Role::kCrc) continue;
      const tp::SignalDef& f = fd.signals[n++];
      EXPECT_EQ(f.start, s.start + 56u * b) << s.name;
      EXPECT_EQ(f.length, s.length);
      EXPECT_EQ(f.factor, s.factor);
      EXPECT_EQ(f.is_signed, s.is_signed);
      if (s.role != tp::Role::kCounter) {
        EXPECT_EQ(f.name, s.name);
      }
    }
  }
  EXPECT_EQ(n + 1, fd.signals.size());
  EXPECT_EQ(fd.signals.back().start, 504u);
}

TEST(MessageTable, ScalingMatchesTheSpec) {
  // The LSB table of docs/can-protocol.md.
  EXPECT_EQ(tp::table::kTwistAngular[0].factor, 0.001);
  EXPECT_EQ(tp::table::kTwistLinear[0].factor, 0.0001);
  EXPECT_EQ(tp::table::kPoseOrientation[0].factor, 0.00025);
  EXPECT_EQ(tp::table::kPosePosition[0].factor, 0.00002);
  EXPECT_DOUBLE_EQ(tp::physical_max(tp::table::kTwistAngular[0]), 32.767);
  EXPECT_DOUBLE_EQ(tp::physical_max(tp::table::kTwistLinear[0]), 3.2767);
  EXPECT_DOUBLE_EQ(tp::physical_max(tp::table::kPoseOrientation[0]), 1.0);
  EXPECT_DOUBLE_EQ(tp::physical_max(tp::table::kPosePosition[0]), 0.65534);
  EXPECT_EQ(tp::invalid_raw(tp::table::kPoseOrientation[0]), -4096);
  EXPECT_EQ(tp::invalid_raw(tp::table::kTimestamp[0]), 0xFFFFFFFFFFFFll);
}
