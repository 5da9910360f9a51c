// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: the SocketCAN TX queue, error-frame and recovery policies on a fake kernel.
#include <gtest/gtest.h>
#include <linux/can/error.h>

#include <atomic>
#include <thread>
#include <vector>

#include "channel_fixture.hpp"

namespace can = tacse3::hal::can;
using tacse3::test::FakeSocketOps;
using tacse3::test::frame_number;
using tacse3::test::numbered_frame;
using tacse3::test::open_on;

namespace {

can::SocketCanOptions with_queue(std::uint32_t n) {
  can::SocketCanOptions o;
  o.tx_queue = n;
  return o;
}

std::vector<std::uint32_t> written_numbers(const FakeSocketOps& ops, std::size_t from = 0) {
  std::vector<std::uint32_t> v;
  for (std::size_t i = from; i < ops.written.size(); ++i) v.push_back(frame_number(ops.written[i]));
  return v;
}

}  // namespace

TEST(SocketCanQueue, WritesStraightThroughWhenTheKernelAccepts) {
  FakeSocketOps ops;
  auto ch = open_on(ops, with_queue(4));
  for (std::uint32_t i = 0; i < 10; ++i) ASSERT_TRUE(ch->send(numbered_frame(i)));
  EXPECT_EQ(written_numbers(ops), (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
  const can::ChannelStats s = ch->stats();
  EXPECT_EQ(s.tx_frames, 10u);
  EXPECT_EQ(s.tx_dropped, 0u);
  EXPECT_EQ(s.tx_errors, 0u);
  EXPECT_EQ(s.tx_queue_depth, 0u);
  EXPECT_EQ(s.bus_state, can::BusState::kErrorActive);
  EXPECT_EQ(ops.written[0].size, CAN_MTU);
  EXPECT_EQ(ops.written[0].fd, ops.tx_socket()->fd);
}

// Sustained ENOBUFS: 20 frames into a queue of 8. Every frame is accepted by send(), the 12
// oldest are dropped and counted, and the 8 newest go out in order once the kernel takes them.
TEST(SocketCanQueue, DropsTheOldestUnderSustainedEnobufsAndFlushesInOrder) {
  FakeSocketOps ops;
  auto ch = open_on(ops, with_queue(8));
  ops.write_errno = ENOBUFS;
  for (std::uint32_t i = 0; i < 20; ++i) {
    ASSERT_TRUE(ch->send(numbered_frame(i)));
    ch->service();
  }
  can::ChannelStats s = ch->stats();
  EXPECT_EQ(s.tx_frames, 0u);
  EXPECT_EQ(s.tx_dropped, 12u);
  EXPECT_EQ(s.tx_errors, 0u);
  EXPECT_EQ(s.tx_queue_depth, 8u);
  EXPECT_EQ(s.bus_state, can::BusState::kErrorActive);  // ENOBUFS is back-pressure, not a fault
  // One write attempt per send() and one per service(): each refused, none retried in a loop.
  EXPECT_EQ(ops.write_calls, 40u);
  EXPECT_EQ(ch->counters().enobufs, 40u);
  EXPECT_EQ(ch->counters().tx_deferred, 40u);
  EXPECT_TRUE(ops.written.empty());

  ops.write_errno = 0;
  ch->service();
  EXPECT_EQ(written_numbers(ops), (std::vector<std::uint32_t>{12, 13, 14, 15, 16, 17, 18, 19}));
  s = ch->stats();
  EXPECT_EQ(s.tx_frames, 8u);
  EXPECT_EQ(s.tx_dropped, 12u);
  EXPECT_EQ(s.tx_queue_depth, 0u);
}

// The kernel takes some frames and then refuses: service() writes exactly as many as accepted
// and keeps the rest, in order, for the next call.
TEST(SocketCanQueue, FlushesAsFarAsTheKernelAcceptsWithoutBlocking) {
  FakeSocketOps ops;
  auto ch = open_on(ops, with_queue(16));
  ops.accept_budget = 0;
  for (std::uint32_t i = 0; i < 10; ++i) ASSERT_TRUE(ch->send(numbered_frame(i)));
  EXPECT_EQ(ch->stats().tx_queue_depth, 10u);
  ops.accept_budget = 3;
  ch->service();
  EXPECT_EQ(written_numbers(ops), (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(ch->stats().tx_queue_depth, 7u);
  ch->service();  // budget exhausted: one refused attempt, nothing written
  EXPECT_EQ(ops.written.size(), 3u);
  ops.accept_budget = -1;
  ch->service();
  EXPECT_EQ(written_numbers(ops), (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
  EXPECT_EQ(ch->stats().tx_queue_depth, 0u);
  EXPECT_EQ(ch->stats().tx_dropped, 0u);
}

TEST(SocketCanQueue, EagainKeepsTheFrameQueuedLikeEnobufs) {
  FakeSocketOps ops;
  auto ch = open_on(ops, with_queue(2));
  ops.write_errno = EAGAIN;
  for (std::uint32_t i = 0; i < 3; ++i) ASSERT_TRUE(ch->send(numbered_frame(i)));
  EXPECT_EQ(ch->stats().tx_dropped, 1u);
  EXPECT_EQ(ch->counters().enobufs, 0u);
  EXPECT_EQ(ch->counters().tx_deferred, 3u);
  ops.write_errno = 0;
  ch->service();
  EXPECT_EQ(written_numbers(ops), (std::vector<std::uint32_t>{1, 2}));
}

// A per-frame failure (EINVAL, EMSGSIZE) drops that frame, counts it and lets the rest through.
TEST(SocketCanQueue, OtherWriteErrorsDropOnlyTheFailingFrame) {
  FakeSocketOps ops;
  auto ch = open_on(ops, with_queue(8));
  ops.write_errno = EINVAL;
  ASSERT_TRUE(ch->send(numbered_frame(1)));
  EXPECT_EQ(ch->stats().tx_errors, 1u);
  EXPECT_EQ(ch->stats().tx_queue_depth, 0u);
  EXPECT_NE(ch->last_error().find("vcan0"), std::string::npos) << ch->last_error();
  EXPECT_NE(ch->last_error().find("EINVAL"), std::string::npos) << ch->last_error();
  ops.write_errno = 0;
  ASSERT_TRUE(ch->send(numbered_frame(2)));
  EXPECT_EQ(written_numbers(ops), (std::vector<std::uint32_t>{2}));
  EXPECT_EQ(ch->stats().tx_frames, 1u);
}

TEST(SocketCanQueue, RefusesInvalidFramesAndCountsThem) {
  FakeSocketOps ops;
  auto ch = open_on(ops);  // classic
  tacse3::protocol::CanFrame f = numbered_frame(1);
  f.len = 9;
  EXPECT_FALSE(ch->send(f));
  EXPECT_NE(ch->last_error().find("invalid classic frame length 9"), std::string::npos)
      << ch->last_error();
  f.fd = true;
  f.len = 64;
  EXPECT_FALSE(ch->send(f));
  EXPECT_NE(ch->last_error().find("without FD"), std::string::npos) << ch->last_error();
  EXPECT_EQ(ch->stats().tx_errors, 2u);
  EXPECT_EQ(ops.write_calls, 0u);
}

// ---- error frames ------------------------------------------------------------------------

TEST(SocketCanErrors, TracksWarningPassiveAndBackToActive) {
  FakeSocketOps ops;
  auto ch = open_on(ops);
  ops.push_error_frame(CAN_ERR_CRTL | CAN_ERR_CNT, CAN_ERR_CRTL_TX_WARNING, 97, 3);
  ch->service();
  EXPECT_EQ(ch->stats().bus_state, can::BusState::kErrorWarning);
  EXPECT_EQ(ch->counters().tx_error_counter, 97u);
  EXPECT_EQ(ch->counters().rx_error_counter, 3u);
  ops.push_error_frame(CAN_ERR_CRTL | CAN_ERR_CNT, CAN_ERR_CRTL_TX_PASSIVE, 130, 3);
  ch->service();
  EXPECT_EQ(ch->stats().bus_state, can::BusState::kErrorPassive);
  EXPECT_EQ(ch->counters().tx_error_counter, 130u);
  // Error-passive still transmits: frames go out.
  ASSERT_TRUE(ch->send(numbered_frame(5)));
  EXPECT_EQ(written_numbers(ops), (std::vector<std::uint32_t>{5}));
  ops.push_error_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_RX_WARNING);  // passive -> warning
  ch->service();
  EXPECT_EQ(ch->stats().bus_state, can::BusState::kErrorWarning);
  ops.push_error_frame(CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE);
  ch->service();
  const can::ChannelStats s = ch->stats();
  EXPECT_EQ(s.bus_state, can::BusState::kErrorActive);
  EXPECT_EQ(s.error_frames, 4u);
  EXPECT_EQ(s.bus_off_events, 0u);
  EXPECT_EQ(ch->counters().warning_events, 2u);
  EXPECT_EQ(ch->counters().passive_events, 1u);
}

// Bus-off: nothing is written (no spinning on a dead controller), the queue keeps the newest
// frames, and CAN_ERR_RESTARTED recovers: restart counted, gap losses counted, queue flushed.
TEST(SocketCanErrors, BusOffPausesTxAndRestartedRecovers) {
  FakeSocketOps ops;
  auto ch = open_on(ops, with_queue(4));
  ASSERT_TRUE(ch->send(numbered_frame(0)));
  ops.push_error_frame(CAN_ERR_BUSOFF);
  ch->service();
  EXPECT_EQ(ch->stats().bus_state, can::BusState::kBusOff);
  EXPECT_EQ(ch->stats().bus_off_events, 1u);
  EXPECT_NE(ch->last_error().find("vcan0: controller bus-off"), std::string::npos)
      << ch->last_error();
  const std::uint64_t calls = ops.write_calls;
  for (std::uint32_t i = 1; i <= 10; ++i) {
    ASSERT_TRUE(ch->send(numbered_frame(i)));
    ch->service();
    ops.now += 8;
  }
  EXPECT_EQ(ops.write_calls, calls);  // not a single write while bus-off
  can::ChannelStats s = ch->stats();
  EXPECT_EQ(s.tx_queue_depth, 4u);
  EXPECT_EQ(s.tx_dropped, 6u);
  ops.push_error_frame(CAN_ERR_BUSOFF);  // repeated report: still one event
  ch->service();
  EXPECT_EQ(ch->stats().bus_off_events, 1u);

  ops.push_error_frame(CAN_ERR_RESTARTED);
  ch->service();
  s = ch->stats();
  EXPECT_EQ(s.bus_state, can::BusState::kErrorActive);
  EXPECT_EQ(s.restarts, 1u);
  EXPECT_EQ(s.error_frames, 3u);
  EXPECT_EQ(s.tx_queue_depth, 0u);
  EXPECT_EQ(ch->counters().last_gap_dropped, 6u);
  EXPECT_EQ(ch->counters().gap_dropped, 6u);
  EXPECT_EQ(written_numbers(ops), (std::vector<std::uint32_t>{0, 7, 8, 9, 10}));
}

// The error classes the channel subscribes to: the fake delivers only subscribed classes, as
// the kernel does, so a flood of protocol/ACK errors never reaches the channel.
TEST(SocketCanErrors, SubscribesStateClassesButNotBusErrorFloods) {
  FakeSocketOps ops;
  auto ch = open_on(ops);
  const FakeSocketOps::Sock* tx = ops.tx_socket();
  ASSERT_NE(tx, nullptr);
  EXPECT_EQ(tx->err_mask,
            CAN_ERR_TX_TIMEOUT | CAN_ERR_CRTL | CAN_ERR_BUSOFF | CAN_ERR_RESTARTED | CAN_ERR_CNT);
  EXPECT_TRUE(tx->filter_set);
  EXPECT_TRUE(tx->filters.empty());  // no data frames on the TX socket
  for (int i = 0; i < 100; ++i) ops.push_error_frame(CAN_ERR_PROT | CAN_ERR_BUSERROR | CAN_ERR_ACK);
  ch->service();
  EXPECT_EQ(ch->stats().error_frames, 0u);
}

// ---- interface down / up -----------------------------------------------------------------

// `ip link set vcan0 down` for 1 s, then up, with the daemon sending one frame per 10 ms and
// calling service() every cycle. While down: no writes, reopen attempts with backoff (100, 200,
// 400, 800 ms), the newest frames kept. After up: one reopen, restart counted, queue flushed.
TEST(SocketCanLink, InterfaceDownThenUpReopensWithBackoff) {
  FakeSocketOps ops;
  auto ch = open_on(ops, with_queue(8));
  const int first_tx = ops.tx_socket()->fd;
  ASSERT_TRUE(ch->send(numbered_frame(0)));
  ops.set_up(false);
  const std::int64_t t0 = ops.now;
  std::uint32_t n = 1;
  // The first send after the link went down meets ENETDOWN.
  ASSERT_TRUE(ch->send(numbered_frame(n++)));
  EXPECT_EQ(ch->stats().bus_state, can::BusState::kDown);
  EXPECT_NE(ch->last_error().find("vcan0: write: ENETDOWN"), std::string::npos) << ch->last_error();
  EXPECT_EQ(ops.tx_socket(), nullptr);  // the TX socket was closed
  const std::uint64_t calls = ops.write_calls;
  while (ops.now < t0 + 1000) {
    ops.now += 10;
    ASSERT_TRUE(ch->send(numbered_frame(n++)));
    ch->service();
  }
  EXPECT_EQ(ops.write_calls, calls);
  EXPECT_EQ(ch->stats().bus_state, can::BusState::kDown);
  // Attempts at t0+100, +300 (100+200), +700 (+400); the next is due at +1500.
  EXPECT_EQ(ch->counters().reopen_attempts, 3u);
  EXPECT_NE(ch->last_error().find("vcan0: interface is down"), std::string::npos)
      << ch->last_error();

  ops.set_up(true);
  const std::uint32_t sent_while_down = n - 1;  // frames 1..n-1 were sent after the link went down
  while (ch->stats().bus_state == can::BusState::kDown && ops.now < t0 + 3000) {
    ops.now += 10;
    ch->service();
  }
  EXPECT_EQ(ops.now, t0 + 1500);
  const can::ChannelStats s = ch->stats();
  EXPECT_EQ(s.bus_state, can::BusState::kErrorActive);
  EXPECT_EQ(s.restarts, 1u);
  EXPECT_EQ(ch->counters().reopen_attempts, 4u);
  EXPECT_EQ(ch->counters().down_events, 1u);
  // The 101 frames sent while down went through a queue of 8: the 8 newest survive.
  EXPECT_EQ(sent_while_down, 101u);
  EXPECT_EQ(s.tx_dropped, 101u - 8u);
  EXPECT_EQ(ch->counters().last_gap_dropped, 93u);
  EXPECT_EQ(written_numbers(ops),
            (std::vector<std::uint32_t>{0, 94, 95, 96, 97, 98, 99, 100, 101}));
  // A new socket, configured like the first one.
  ASSERT_NE(ops.tx_socket(), nullptr);
  EXPECT_NE(ops.tx_socket()->fd, first_tx);
  EXPECT_EQ(ops.tx_socket()->bound_ifindex, ops.ifindex);
  EXPECT_EQ(ops.open_count(), 2);  // new TX + the RX socket; the failed probes were closed
}

// A USB adapter unplugged and replugged: the interface vanishes (ENXIO on write) and comes back
// with a new index; the channel rebinds by name.
TEST(SocketCanLink, InterfaceRemovedAndReturnedWithANewIndexIsRebound) {
  FakeSocketOps ops;
  auto ch = open_on(ops, with_queue(4));
  ops.set_exists(false, 0);
  ASSERT_TRUE(ch->send(numbered_frame(1)));
  EXPECT_EQ(ch->stats().bus_state, can::BusState::kDown);
  EXPECT_NE(ch->last_error().find("ENXIO"), std::string::npos) << ch->last_error();
  ops.now += 150;
  ch->service();  // attempt fails: no such interface
  EXPECT_NE(ch->last_error().find("no CAN interface 'vcan0'"), std::string::npos)
      << ch->last_error();
  ops.set_exists(true, 12);
  ops.now += 200;
  ch->service();
  EXPECT_EQ(ch->stats().bus_state, can::BusState::kErrorActive);
  EXPECT_EQ(ch->stats().restarts, 1u);
  EXPECT_EQ(ops.tx_socket()->bound_ifindex, 12);
  EXPECT_EQ(written_numbers(ops), (std::vector<std::uint32_t>{1}));
}

// The service starts before systemd-networkd brings can0 up: open succeeds in kDown.
TEST(SocketCanLink, OpensOnADownInterfaceAndPicksItUpLater) {
  FakeSocketOps ops;
  ops.up = false;
  auto ch = open_on(ops);
  ASSERT_NE(ch, nullptr);
  EXPECT_EQ(ch->stats().bus_state, can::BusState::kDown);
  ASSERT_TRUE(ch->send(numbered_frame(3)));
  EXPECT_EQ(ops.write_calls, 0u);
  ops.up = true;
  ops.now += 100;
  ch->service();
  EXPECT_EQ(ch->stats().bus_state, can::BusState::kErrorActive);
  EXPECT_EQ(written_numbers(ops), (std::vector<std::uint32_t>{3}));
}

// The TX socket learns of the link going down from its pending socket error even before a write.
TEST(SocketCanLink, DetectsDownFromTheSocketErrorWhileIdle) {
  FakeSocketOps ops;
  auto ch = open_on(ops);
  ops.set_up(false);
  ch->service();
  EXPECT_EQ(ch->stats().bus_state, can::BusState::kDown);
  EXPECT_NE(ch->last_error().find("vcan0: read: ENETDOWN"), std::string::npos) << ch->last_error();
}

TEST(BusState, Names) {
  EXPECT_STREQ(can::to_string(can::BusState::kErrorActive), "error-active");
  EXPECT_STREQ(can::to_string(can::BusState::kErrorWarning), "error-warning");
  EXPECT_STREQ(can::to_string(can::BusState::kErrorPassive), "error-passive");
  EXPECT_STREQ(can::to_string(can::BusState::kBusOff), "bus-off");
  EXPECT_STREQ(can::to_string(can::BusState::kDown), "down");
}

// ---- threads -----------------------------------------------------------------------------

// The daemon's layout: this thread sends and services, one thread receives, one reads stats.
// Each thread owns its socket; the counters only ever grow as seen from the stats thread.
TEST(SocketCanThreads, SendServiceReceiveAndStatsRunConcurrently) {
  FakeSocketOps ops;
  auto ch = open_on(ops, with_queue(64));
  constexpr std::uint32_t kFrames = 1000;
  std::atomic<bool> done{false};
  std::uint64_t received = 0;
  std::thread rx([&] {
    can::RxFrame r;
    while (received < kFrames) {
      if (ch->receive(r, 5) == can::RxResult::kFrame) {
        EXPECT_EQ(r.frame.id, 0x030u);
        ++received;
      }
    }
  });
  bool monotonic = true;
  std::thread reader([&] {
    can::ChannelStats last;
    while (!done.load()) {
      const can::ChannelStats s = ch->stats();
      monotonic = monotonic && s.tx_frames >= last.tx_frames && s.rx_frames >= last.rx_frames;
      last = s;
    }
  });
  canfd_frame command{};
  command.can_id = 0x030;
  command.len = 8;
  for (std::uint32_t i = 0; i < kFrames; ++i) {
    ASSERT_TRUE(ch->send(numbered_frame(i)));
    ch->service();
    ops.push_frame(command, CAN_MTU);
  }
  rx.join();
  done.store(true);
  reader.join();
  EXPECT_TRUE(monotonic);
  EXPECT_EQ(received, kFrames);
  const can::ChannelStats s = ch->stats();
  EXPECT_EQ(s.tx_frames, kFrames);
  EXPECT_EQ(s.rx_frames, kFrames);
  EXPECT_EQ(s.tx_dropped, 0u);
  ASSERT_EQ(ops.written.size(), kFrames);
  EXPECT_EQ(frame_number(ops.written[kFrames - 1]), kFrames - 1);
}
