// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: helpers to open a SocketCanChannel on the fake socket layer and make frames.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "fake_socket.hpp"
#include "tacse3/hal/can/socketcan.hpp"

namespace tacse3::test {

// A classic 8-byte frame whose id and first byte carry `n`, so order survives into the fake.
inline protocol::CanFrame numbered_frame(std::uint32_t n, bool extended = false) {
  protocol::CanFrame f;
  f.id = extended ? (0x1ACE0000u | n) : (0x020u + (n & 0x1Fu));
  f.extended = extended;
  f.len = 8;
  f.data[0] = static_cast<std::uint8_t>(n);
  f.data[1] = static_cast<std::uint8_t>(n >> 8);
  return f;
}

// The number carried by a written frame (see numbered_frame).
inline std::uint32_t frame_number(const FakeSocketOps::Written& w) {
  return static_cast<std::uint32_t>(w.frame.data[0]) |
         (static_cast<std::uint32_t>(w.frame.data[1]) << 8);
}

inline std::unique_ptr<hal::can::SocketCanChannel> open_on(FakeSocketOps& ops,
                                                           hal::can::SocketCanOptions o = {}) {
  o.ops = &ops;
  std::string error;
  auto ch = hal::can::SocketCanChannel::open(ops.iface, o, error);
  EXPECT_NE(ch, nullptr) << error;
  return ch;
}

}  // namespace tacse3::test
