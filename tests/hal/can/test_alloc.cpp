// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: send() and service() allocate nothing after open, in every TX situation, for
// the SocketCAN and the Unix socket backends.
#include <gtest/gtest.h>
#include <linux/can/error.h>
#include <unistd.h>

#include <string>

#include "alloc/alloc_hooks.hpp"
#include "channel_fixture.hpp"
#include "tacse3/hal/can/unix_channel.hpp"

namespace can = tacse3::hal::can;
using tacse3::test::allocation_count;
using tacse3::test::FakeSocketOps;
using tacse3::test::numbered_frame;
using tacse3::test::open_on;
using tacse3::test::reset_allocation_count;

// One daemon cycle: the five classic frames of a cycle, then service().
void cycle(can::SocketCanChannel& ch, std::uint32_t n) {
  for (std::uint32_t k = 0; k < 5; ++k) ASSERT_TRUE(ch.send(numbered_frame(n * 5 + k)));
  ch.service();
}

TEST(SocketCanAlloc, SendAndServiceAllocateNothingAfterOpen) {
  FakeSocketOps ops;
  can::SocketCanOptions o;
  o.tx_queue = 16;
  auto ch = open_on(ops, o);
  ASSERT_NE(ch, nullptr);
  // The hooks must see allocations at all, or a zero below would prove nothing.
  reset_allocation_count();
  {
    int* p = new int(1);
    asm volatile("" : : "g"(p) : "memory");  // keep the compiler from eliding the pair
    delete p;
  }
  ASSERT_GE(allocation_count(), 1u);

  reset_allocation_count();
  std::uint32_t n = 0;
  for (int i = 0; i < 200; ++i) cycle(*ch, n++);  // kernel accepts
  ops.write_errno = ENOBUFS;  // sustained ENOBUFS: queue, drop oldest, error text
  for (int i = 0; i < 200; ++i) cycle(*ch, n++);
  ops.write_errno = EINVAL;  // per-frame errors: dropped with a message
  for (int i = 0; i < 20; ++i) cycle(*ch, n++);
  ops.write_errno = 0;
  ops.push_error_frame(CAN_ERR_CRTL | CAN_ERR_CNT, CAN_ERR_CRTL_TX_PASSIVE, 128, 0);
  for (int i = 0; i < 20; ++i) cycle(*ch, n++);
  ops.push_error_frame(CAN_ERR_BUSOFF);  // bus-off message, no writes
  for (int i = 0; i < 100; ++i) cycle(*ch, n++);
  ops.push_error_frame(CAN_ERR_RESTARTED);
  for (int i = 0; i < 20; ++i) cycle(*ch, n++);
  ops.set_up(false);  // ENETDOWN: down message, socket closed
  for (int i = 0; i < 20; ++i) cycle(*ch, n++);
  (void)ch->stats();
  (void)ch->counters();
  EXPECT_EQ(allocation_count(), 0u);

  // The measured loop really went through every path.
  const can::ChannelStats s = ch->stats();
  EXPECT_EQ(s.bus_off_events, 1u);
  EXPECT_EQ(s.restarts, 1u);
  EXPECT_EQ(s.bus_state, can::BusState::kDown);
  // Under EINVAL: the 16 frames queued by the ENOBUFS phase (the first send filled the ring
  // again), then the other 99 frames of the 20 cycles one by one.
  EXPECT_EQ(s.tx_errors, 16u + 99u);
  EXPECT_GT(s.tx_dropped, 0u);
  EXPECT_GT(ch->counters().enobufs, 0u);
}

// The Unix socket backend on the daemon's paths: send/service with a reading peer, a peer that
// stops reading (frames dropped), and a peer that hangs up (released by service, closed by
// receive); receive parsing a command line. Only connecting (in the test) allocates.
TEST(UnixSocketChannelAlloc, SendServiceAndReceiveAllocateNothingAfterOpen) {
  const std::string path = "/tmp/tacse3-unixcan-alloc-" + std::to_string(getpid()) + ".sock";
  std::string e;
  auto server = can::UnixSocketChannel::listen(path, e);
  ASSERT_NE(server, nullptr) << e;
  auto reader = can::UnixSocketChannel::connect(path, e);
  auto stalled = can::UnixSocketChannel::connect(path, e);
  auto leaving = can::UnixSocketChannel::connect(path, e);
  ASSERT_TRUE(reader && stalled && leaving) << e;
  can::RxFrame rx;
  for (int i = 0; i < 5; ++i) (void)server->receive(rx, 5);  // accept the three
  ASSERT_EQ(server->counters().peers, 3u);
  can::CanFrame cmd;
  cmd.id = 0x030;
  cmd.len = 1;
  ASSERT_TRUE(leaving->send(cmd));

  reset_allocation_count();
  std::uint32_t n = 0;
  for (int i = 0; i < 2000; ++i) {  // ~40 cycles' worth per drain: the stalled peer fills up
    for (std::uint32_t k = 0; k < 5; ++k) ASSERT_TRUE(server->send(numbered_frame(n++)));
    server->service();
    if (i % 50 == 0) {
      while (reader->receive(rx, 0) == can::RxResult::kFrame) {
      }
    }
  }
  ASSERT_EQ(server->receive(rx, 100), can::RxResult::kFrame);  // the leaving peer's command
  EXPECT_EQ(rx.frame.id, 0x030u);
  const std::uint64_t before_leave = allocation_count();
  EXPECT_EQ(before_leave, 0u);
  leaving.reset();  // the destructor's free() is the test's, not the channel's
  reset_allocation_count();
  for (int i = 0; i < 20; ++i) {
    ASSERT_TRUE(server->send(numbered_frame(n++)));
    server->service();
    (void)server->receive(rx, 2);
  }
  (void)server->stats();
  (void)server->counters();
  EXPECT_EQ(allocation_count(), 0u);
  EXPECT_EQ(server->counters().disconnected, 1u);
  EXPECT_EQ(server->counters().peers, 2u);
  EXPECT_GT(server->stats().tx_dropped, 0u);  // the stalled peer's
}
