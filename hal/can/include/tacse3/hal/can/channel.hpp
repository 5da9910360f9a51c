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

// The CAN controller's fault confinement state as the channel last saw it (ISO 11898-1), plus
// kDown for "the interface is down or gone" (no socket can send).
enum class BusState : std::uint8_t {
  kErrorActive = 0,
  kErrorWarning,
  kErrorPassive,
  kBusOff,
  kDown
};
const char* to_string(BusState s) noexcept;

struct ChannelStats {
  std::uint64_t tx_frames = 0;   // handed to the kernel (or written, for the log backend)
  std::uint64_t tx_dropped = 0;  // dropped by the TX policy (queue full / ENOBUFS: oldest dropped)
  std::uint64_t tx_errors = 0;   // other send failures
  std::uint64_t rx_frames = 0;   // data frames returned by receive()
  std::uint64_t error_frames = 0;  // CAN error frames seen
  std::uint64_t bus_off_events = 0;
  std::uint64_t restarts = 0;        // recoveries from bus-off / interface down
  std::uint32_t tx_queue_depth = 0;  // frames waiting now
  BusState bus_state = BusState::kErrorActive;
};

// A bidirectional CAN channel. Error frames and remote frames are skipped (and counted by the
// implementation), so receive() returns data frames only.
//
// Threading: send() and service() from one thread (the daemon's DSP/TX thread); receive() from
// one other thread (the command RX thread); stats() from any thread.
class Channel {
 public:
  virtual ~Channel() = default;
  Channel() = default;
  Channel(const Channel&) = delete;
  Channel& operator=(const Channel&) = delete;

  // Hand one frame to the channel. Never blocks: a backend with a TX queue queues the frame when
  // the kernel cannot take it now. false only for a frame it cannot accept (invalid, no output),
  // counted in tx_errors, with last_error() set.
  virtual bool send(const CanFrame& f) = 0;
  // Wait up to timeout_ms (< 0: forever) for the next data frame.
  virtual RxResult receive(RxFrame& out, int timeout_ms) = 0;
  virtual const std::string& last_error() const = 0;

  // Counters and bus state; callable from any thread.
  virtual ChannelStats stats() const { return {}; }
  // Non-blocking: flush the TX queue as far as the socket accepts, handle error frames and
  // recovery. Call once per cycle from the sending thread.
  virtual void service() {}
};

}  // namespace tacse3::hal::can
