// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: SocketCAN socket setup (filters, FD), frame sizes, RX, and open failures.
#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "channel_fixture.hpp"
#include "tacse3/protocol/ids.hpp"

namespace can = tacse3::hal::can;
namespace tp = tacse3::protocol;
using tacse3::test::FakeSocketOps;
using tacse3::test::numbered_frame;
using tacse3::test::open_on;

namespace {

canfd_frame kernel_frame(canid_t id, std::uint8_t len, std::uint8_t first = 0xA5) {
  canfd_frame f{};
  f.can_id = id;
  f.len = len;
  f.data[0] = first;
  return f;
}

}  // namespace

// ---- kernel filters ----------------------------------------------------------------------

TEST(SocketCanFilters, StandardLayoutPassesOnlyThisNodesCommandId) {
  tp::Endpoint ep;
  ep.node_id = 5;
  const std::vector<can::SocketCanFilter> f = can::command_filters(ep);
  ASSERT_EQ(f.size(), 1u);
  // node 5 << 5 | Command 0x10 = 0x0B0; mask: all 11 bits + EFF + RTR (data frames, 11-bit only)
  EXPECT_EQ(f[0].id, 0x0B0u);
  EXPECT_EQ(f[0].mask, 0x7FFu | CAN_EFF_FLAG | CAN_RTR_FLAG);

  FakeSocketOps ops;
  can::SocketCanOptions o;
  o.filters = f;
  auto ch = open_on(ops, o);
  const FakeSocketOps::Sock* rx = ops.rx_socket();
  ASSERT_NE(rx, nullptr);
  ASSERT_TRUE(rx->filter_set);
  ASSERT_EQ(rx->filters.size(), 1u);
  EXPECT_EQ(rx->filters[0].can_id, 0x0B0u);
  EXPECT_EQ(rx->filters[0].can_mask, 0xC00007FFu);
  EXPECT_EQ(rx->err_mask, 0u);

  // What the kernel delivers through that list: only node 5's command data frame.
  ops.push_frame(kernel_frame(0x0B0, 8, 1), CAN_MTU);                      // node 5 command
  ops.push_frame(kernel_frame(0x0D0, 8, 2), CAN_MTU);                      // node 6 command
  ops.push_frame(kernel_frame(0x0A1, 8, 3), CAN_MTU);                      // node 5 Timestamp
  ops.push_frame(kernel_frame(0x0B0 | CAN_RTR_FLAG, 0, 4), CAN_MTU);       // remote frame
  ops.push_frame(kernel_frame(0x1ACE00B0 | CAN_EFF_FLAG, 8, 5), CAN_MTU);  // 29-bit, same low bits
  can::RxFrame r;
  ASSERT_EQ(ch->receive(r, 0), can::RxResult::kFrame);
  EXPECT_EQ(r.frame.id, 0x0B0u);
  EXPECT_FALSE(r.frame.extended);
  EXPECT_EQ(r.frame.data[0], 1u);
  EXPECT_EQ(ch->receive(r, 0), can::RxResult::kTimeout);
  EXPECT_EQ(ch->stats().rx_frames, 1u);
}

TEST(SocketCanFilters, ExtendedLayoutUsesTheBaseAndTheEffFlag) {
  tp::Endpoint ep;
  ep.node_id = 63;
  ep.layout.mode = tp::IdMode::kExtended;
  ep.layout.extended_base = 0x12340000u;
  const std::vector<can::SocketCanFilter> f = can::command_filters(ep);
  ASSERT_EQ(f.size(), 1u);
  // 0x12340000 | 63 << 5 | 0x10 = 0x123407F0
  EXPECT_EQ(f[0].id, 0x123407F0u | CAN_EFF_FLAG);
  EXPECT_EQ(f[0].mask, 0x1FFFFFFFu | CAN_EFF_FLAG | CAN_RTR_FLAG);

  FakeSocketOps ops;
  can::SocketCanOptions o;
  o.filters = f;
  auto ch = open_on(ops, o);
  ASSERT_EQ(ops.rx_socket()->filters.size(), 1u);
  EXPECT_EQ(ops.rx_socket()->filters[0].can_id, 0x923407F0u);
  EXPECT_EQ(ops.rx_socket()->filters[0].can_mask, 0xDFFFFFFFu);
  ops.push_frame(kernel_frame(0x7F0, 8, 1), CAN_MTU);                      // 11-bit
  ops.push_frame(kernel_frame(0x1ACE07F0 | CAN_EFF_FLAG, 8, 2), CAN_MTU);  // other base
  ops.push_frame(kernel_frame(0x123407F0 | CAN_EFF_FLAG, 8, 3), CAN_MTU);  // ours
  can::RxFrame r;
  ASSERT_EQ(ch->receive(r, 0), can::RxResult::kFrame);
  EXPECT_TRUE(r.frame.extended);
  EXPECT_EQ(r.frame.id, 0x123407F0u);
  EXPECT_EQ(r.frame.data[0], 3u);
  EXPECT_EQ(ch->receive(r, 0), can::RxResult::kTimeout);
}

// ---- socket setup and frame sizes --------------------------------------------------------

TEST(SocketCanSetup, OpensTwoNonBlockingSocketsBoundToTheInterface) {
  FakeSocketOps ops;
  auto ch = open_on(ops);
  ASSERT_EQ(ops.sockets.size(), 2u);
  for (const FakeSocketOps::Sock& s : ops.sockets) {
    EXPECT_TRUE(s.open);
    EXPECT_EQ(s.type, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC);
    EXPECT_EQ(s.bound_ifindex, 7);
    EXPECT_FALSE(s.fd_frames);
  }
  EXPECT_FALSE(ops.rx_socket()->filter_set);  // no filters given: the kernel's receive-all
  EXPECT_EQ(ch->tx_queue_capacity(), 64u);
  ch.reset();
  EXPECT_EQ(ops.open_count(), 0);
}

TEST(SocketCanSetup, ClassicFramesAre16BytesFdFramesAre72WithBrsByPolicy) {
  FakeSocketOps ops;
  can::SocketCanOptions o;
  o.fd = true;
  auto ch = open_on(ops, o);
  EXPECT_TRUE(ops.tx_socket()->fd_frames);
  EXPECT_TRUE(ops.rx_socket()->fd_frames);
  tp::CanFrame fd;
  fd.id = 0x026;
  fd.fd = true;
  fd.brs = true;
  fd.len = 64;
  for (std::size_t i = 0; i < 64; ++i) fd.data[i] = static_cast<std::uint8_t>(i + 1);
  ASSERT_TRUE(ch->send(fd));
  fd.brs = false;
  ASSERT_TRUE(ch->send(fd));
  ASSERT_TRUE(ch->send(numbered_frame(7)));
  ASSERT_EQ(ops.written.size(), 3u);
  EXPECT_EQ(ops.written[0].size, CANFD_MTU);
  EXPECT_EQ(ops.written[0].frame.len, 64u);
  EXPECT_EQ(ops.written[0].frame.flags, CANFD_BRS);
  EXPECT_EQ(ops.written[0].frame.data[63], 64u);
  EXPECT_EQ(ops.written[1].frame.flags, 0u);
  EXPECT_EQ(ops.written[2].size, CAN_MTU);
  EXPECT_EQ(ops.written[2].frame.len, 8u);
  EXPECT_EQ(ops.written[2].frame.can_id, 0x027u);

  FakeSocketOps always_ops;
  o.brs = can::BrsPolicy::kAlways;
  auto always = open_on(always_ops, o);
  ASSERT_TRUE(always->send(fd));  // fd.brs is false here
  EXPECT_EQ(always_ops.written[0].frame.flags, CANFD_BRS);

  FakeSocketOps never_ops;
  o.brs = can::BrsPolicy::kNever;
  auto never = open_on(never_ops, o);
  fd.brs = true;
  ASSERT_TRUE(never->send(fd));
  EXPECT_EQ(never_ops.written[0].frame.flags, 0u);
}

// [can] mode = "fd" on an interface brought up without FD: the kernel refuses 72-byte writes
// with EINVAL. Each FD frame is dropped and counted (it would never go), and the message says why.
TEST(SocketCanSetup, FdFramesOnAClassicOnlyInterfaceAreDroppedWithTheCause) {
  FakeSocketOps ops;
  ops.iface_fd = false;
  can::SocketCanOptions o;
  o.fd = true;
  auto ch = open_on(ops, o);
  tp::CanFrame fd;
  fd.id = 0x026;
  fd.fd = true;
  fd.len = 64;
  ASSERT_TRUE(ch->send(fd));
  ASSERT_TRUE(ch->send(numbered_frame(1)));
  EXPECT_EQ(ch->stats().tx_errors, 1u);
  EXPECT_EQ(ch->stats().tx_frames, 1u);
  EXPECT_EQ(ch->stats().tx_queue_depth, 0u);
  EXPECT_EQ(ch->last_error(),
            "vcan0: write of id 0x26 failed: EINVAL (Invalid argument); frame dropped (CAN FD "
            "frame on an interface without FD: set 'fd on' on the interface or [can] mode = "
            "\"classic\")");
}

TEST(SocketCanSetup, ExtendedIdsCarryTheEffFlag) {
  FakeSocketOps ops;
  auto ch = open_on(ops);
  ASSERT_TRUE(ch->send(numbered_frame(0x21, true)));
  ASSERT_EQ(ops.written.size(), 1u);
  EXPECT_EQ(ops.written[0].frame.can_id, 0x1ACE0021u | CAN_EFF_FLAG);
}

TEST(SocketCanRx, ReceivesClassicAndFdFramesAndSkipsRemoteFrames) {
  FakeSocketOps ops;
  can::SocketCanOptions o;
  o.fd = true;
  auto ch = open_on(ops, o);
  canfd_frame fd = kernel_frame(0x030, 48, 9);
  fd.flags = CANFD_BRS;
  fd.data[47] = 0x47;
  ops.push_frame(kernel_frame(0x030 | CAN_RTR_FLAG, 0), CAN_MTU);
  ops.push_frame(fd, CANFD_MTU);
  ops.push_frame(kernel_frame(0x030, 3, 8), CAN_MTU);
  can::RxFrame r;
  ASSERT_EQ(ch->receive(r, 10), can::RxResult::kFrame);
  EXPECT_TRUE(r.frame.fd);
  EXPECT_TRUE(r.frame.brs);
  EXPECT_EQ(r.frame.len, 48u);
  EXPECT_EQ(r.frame.data[47], 0x47u);
  EXPECT_GT(r.time_us, 0u);
  ASSERT_EQ(ch->receive(r, 10), can::RxResult::kFrame);
  EXPECT_FALSE(r.frame.fd);
  EXPECT_EQ(r.frame.len, 3u);
  EXPECT_EQ(r.frame.data[0], 8u);
  EXPECT_EQ(r.frame.data[47], 0u);  // nothing left over from the previous, longer frame
  const std::int64_t before = ops.now;
  EXPECT_EQ(ch->receive(r, 25), can::RxResult::kTimeout);
  EXPECT_EQ(ops.now, before + 25);  // waited in poll, did not spin
  EXPECT_EQ(ch->stats().rx_frames, 2u);
  EXPECT_EQ(ch->counters().rx_skipped, 1u);
}

// The RX thread's socket: the interface goes down (ENETDOWN once), receive() keeps returning
// timeouts after waiting (no busy loop, no kError storm), and reopens when the link is back.
TEST(SocketCanRx, ReopensItsSocketAfterTheInterfaceComesBack) {
  FakeSocketOps ops;
  tp::Endpoint ep;
  ep.node_id = 2;
  can::SocketCanOptions o;
  o.filters = can::command_filters(ep);
  auto ch = open_on(ops, o);
  const int first_rx = ops.rx_socket()->fd;
  ops.set_up(false);
  can::RxFrame r;
  const std::int64_t t0 = ops.now;
  EXPECT_EQ(ch->receive(r, 50), can::RxResult::kTimeout);
  EXPECT_EQ(ops.now, t0 + 50);
  EXPECT_NE(ch->last_error().find("vcan0: read: ENETDOWN"), std::string::npos) << ch->last_error();
  EXPECT_EQ(ch->receive(r, 500), can::RxResult::kTimeout);  // retries at +100 and +300 fail
  EXPECT_EQ(ops.now, t0 + 550);
  ops.set_up(true);
  EXPECT_EQ(ch->receive(r, 1000), can::RxResult::kTimeout);  // reopened at +700
  EXPECT_EQ(ch->counters().rx_reopens, 1u);
  ASSERT_NE(ops.rx_socket(), nullptr);
  EXPECT_NE(ops.rx_socket()->fd, first_rx);
  ASSERT_EQ(ops.rx_socket()->filters.size(), 1u);
  EXPECT_EQ(ops.rx_socket()->filters[0].can_id, 0x050u);
  ops.push_frame(kernel_frame(0x050, 8, 0x77), CAN_MTU);
  ASSERT_EQ(ch->receive(r, 10), can::RxResult::kFrame);
  EXPECT_EQ(r.frame.data[0], 0x77u);
}

// ---- open failures -----------------------------------------------------------------------

TEST(SocketCanOpen, FailuresNameTheInterfaceTheCallAndErrnoAndLeakNothing) {
  std::string error;
  {
    FakeSocketOps ops;
    ops.bind_errno = EADDRNOTAVAIL;
    can::SocketCanOptions o;
    o.ops = &ops;
    EXPECT_EQ(can::SocketCanChannel::open("vcan0", o, error), nullptr);
    EXPECT_EQ(error, "vcan0: bind failed: EADDRNOTAVAIL (Cannot assign requested address)");
    EXPECT_EQ(ops.open_count(), 0);
  }
  {
    FakeSocketOps ops;
    can::SocketCanOptions o;
    o.ops = &ops;
    EXPECT_EQ(can::SocketCanChannel::open("can7", o, error), nullptr);
    EXPECT_NE(error.find("no CAN interface 'can7'"), std::string::npos) << error;
    EXPECT_NE(error.find("ENODEV"), std::string::npos) << error;
    EXPECT_EQ(ops.open_count(), 0);
  }
  {
    FakeSocketOps ops;
    ops.socket_errno = EAFNOSUPPORT;
    can::SocketCanOptions o;
    o.ops = &ops;
    EXPECT_EQ(can::SocketCanChannel::open("vcan0", o, error), nullptr);
    EXPECT_NE(error.find("vcan0: SocketCAN is not available on this host"), std::string::npos);
    EXPECT_NE(error.find("EAFNOSUPPORT"), std::string::npos) << error;
  }
  can::SocketCanOptions o;
  o.tx_queue = 0;
  EXPECT_EQ(can::SocketCanChannel::open("vcan0", o, error), nullptr);
  EXPECT_EQ(error, "vcan0: tx_queue 0 out of range (1..4096)");
  EXPECT_EQ(can::SocketCanChannel::open("an-interface-name-too-long", {}, error), nullptr);
  EXPECT_NE(error.find("invalid CAN interface name"), std::string::npos) << error;
}

// The real socket layer. This build host's kernel has no AF_CAN, so open fails and says so; in
// the vcan VM (no interface of that name) it fails naming the interface instead.
TEST(SocketCanOpen, RealSocketFailsWithAClearMessage) {
  std::string error;
  auto ch = can::SocketCanChannel::open("tacse3nope0", can::SocketCanOptions{}, error);
  EXPECT_EQ(ch, nullptr);
  const bool no_af_can =
      error.find("tacse3nope0: SocketCAN is not available on this host") != std::string::npos &&
      error.find("EAFNOSUPPORT") != std::string::npos;
  const bool no_iface = error.find("no CAN interface 'tacse3nope0'") != std::string::npos &&
                        error.find("ENODEV") != std::string::npos;
  EXPECT_TRUE(no_af_can || no_iface) << error;
}

// The real SocketOps turns -1/errno into -errno. The interface ioctls work on any socket, so
// they are checked on the loopback interface with a UDP socket (this host has no AF_CAN).
TEST(SystemSocketOps, ReturnsNegativeErrnoAndQueriesInterfaces) {
  can::SocketOps& ops = can::system_socket_ops();
  EXPECT_EQ(ops.close(-1), -EBADF);
  const int can_socket = ops.socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (can_socket >= 0) {
    ops.close(can_socket);  // a CAN-capable kernel (the vcan VM)
  } else {
    EXPECT_EQ(can_socket, -EAFNOSUPPORT);
  }
  const int udp = ops.socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  ASSERT_GE(udp, 0);
  EXPECT_EQ(ops.if_index(udp, "lo"), 1);  // loopback is always the first interface
  const int flags = ops.if_flags(udp, "lo");
  ASSERT_GE(flags, 0);
  EXPECT_NE(flags & IFF_UP, 0);
  EXPECT_NE(flags & IFF_LOOPBACK, 0);
  EXPECT_EQ(ops.if_index(udp, "tacse3nope0"), -ENODEV);
  EXPECT_EQ(ops.if_index(udp, "an-interface-name-too-long"), -ENODEV);
  const std::uint8_t byte = 0;
  EXPECT_EQ(ops.write(udp, &byte, 1), -EDESTADDRREQ);  // not connected
  EXPECT_EQ(ops.close(udp), 0);
  const std::int64_t t0 = ops.now_ms();
  EXPECT_EQ(ops.poll(nullptr, 0, 20), 0);
  EXPECT_GE(ops.now_ms() - t0, 20);
}
