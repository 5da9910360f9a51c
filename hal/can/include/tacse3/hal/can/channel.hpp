// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: the CAN channel interface shared by the SocketCAN and log backends.
#pragma once

#include <cstdint>
#include <string>

#include "tacse3/protocol/can_frame.hpp"

namespace tacse3::hal::can {

using protocol::CanFrame;

struct RxFrame {
  CanFrame frame;
  std::uint64_t time_us = 0;  // receive time (SocketCAN: CLOCK_REALTIME; log: the line's stamp)
};

enum class RxResult : std::uint8_t {
  kFrame,    // `out` holds a data frame
  kTimeout,  // nothing within the timeout
  kEnd,      // the source ended (end of a log file / stdin)
  kError,    // see last_error()
};

// A bidirectional CAN channel. Error frames and remote frames are skipped (and counted by the
// implementation), so receive() returns data frames only.
class Channel {
 public:
  virtual ~Channel() = default;
  Channel() = default;
  Channel(const Channel&) = delete;
  Channel& operator=(const Channel&) = delete;

  // Send one frame. false on failure, with last_error() set.
  virtual bool send(const CanFrame& f) = 0;
  // Wait up to timeout_ms (< 0: forever) for the next data frame.
  virtual RxResult receive(RxFrame& out, int timeout_ms) = 0;
  virtual const std::string& last_error() const = 0;
};

}  // namespace tacse3::hal::can
