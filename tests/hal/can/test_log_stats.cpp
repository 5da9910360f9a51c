// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: the candump -L log backend's ChannelStats.
#include <gtest/gtest.h>

#include <cstdio>

#include "tacse3/hal/can/log_channel.hpp"

namespace can = tacse3::hal::can;

TEST(LogChannelStats, CountsWrittenReadErrorAndRefusedFrames) {
  std::FILE* tmp = std::tmpfile();
  ASSERT_NE(tmp, nullptr);
  {
    can::LogChannel writer(nullptr, tmp, "can0");
    writer.set_clock([] { return std::uint64_t{1700000000000000}; });
    tacse3::protocol::CanFrame f;
    f.id = 0x021;
    f.len = 8;
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(writer.send(f));
    f.len = 9;  // not a valid classic length: refused
    EXPECT_FALSE(writer.send(f));
    writer.service();  // no queue: a no-op
    const can::ChannelStats s = writer.stats();
    EXPECT_EQ(s.tx_frames, 3u);
    EXPECT_EQ(s.tx_errors, 1u);
    EXPECT_EQ(s.tx_dropped, 0u);
    EXPECT_EQ(s.tx_queue_depth, 0u);
    EXPECT_EQ(s.bus_state, can::BusState::kErrorActive);
  }
  // An error frame (CAN_ERR_FLAG 0x20000000 | CAN_ERR_BUSOFF) and a remote frame in the log.
  std::fputs("(1700000000.000001) can0 20000040#0000000000000000\n", tmp);
  std::fputs("(1700000000.000002) can0 030#R\n", tmp);
  std::rewind(tmp);
  can::LogChannel reader(tmp, nullptr);
  can::RxFrame r;
  int frames = 0;
  while (reader.receive(r, 0) == can::RxResult::kFrame) ++frames;
  EXPECT_EQ(frames, 3);
  const can::ChannelStats s = reader.stats();
  EXPECT_EQ(s.rx_frames, 3u);
  EXPECT_EQ(s.error_frames, 1u);
  EXPECT_EQ(s.bus_off_events, 0u);  // the log backend reports, it does not interpret
  EXPECT_EQ(reader.skipped_frames(), 2u);
  can::LogChannel none(nullptr, nullptr);
  EXPECT_FALSE(none.send(tacse3::protocol::CanFrame{}));
  EXPECT_EQ(none.stats().tx_errors, 1u);
  std::fclose(tmp);
}
