// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: a minimal SocketCAN raw socket channel (classic and CAN FD).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/hal/can/channel.hpp"

namespace tacse3::hal::can {

struct SocketCanFilter {
  std::uint32_t id = 0;    // SocketCAN can_id incl. CAN_EFF_FLAG for 29-bit ids
  std::uint32_t mask = 0;  // SocketCAN can_mask
};

struct SocketCanOptions {
  bool fd = false;                       // enable CAN_RAW_FD_FRAMES (send/receive FD frames)
  std::vector<SocketCanFilter> filters;  // empty: receive everything
};

class SocketCanChannel final : public Channel {
 public:
  // Open a raw socket bound to `iface`. nullptr on failure with `error` set; when the kernel has
  // no AF_CAN support the error says so explicitly.
  static std::unique_ptr<SocketCanChannel> open(const std::string& iface,
                                                const SocketCanOptions& options,
                                                std::string& error);
  ~SocketCanChannel() override;

  bool send(const CanFrame& f) override;
  RxResult receive(RxFrame& out, int timeout_ms) override;
  const std::string& last_error() const override { return error_; }

  std::uint64_t skipped_frames() const { return skipped_; }  // error / remote frames

 private:
  SocketCanChannel(int fd, std::string iface, bool fd_enabled)
      : fd_(fd), iface_(std::move(iface)), fd_enabled_(fd_enabled) {}
  int fd_ = -1;
  std::string iface_;
  bool fd_enabled_ = false;
  std::string error_;
  std::uint64_t skipped_ = 0;
};

}  // namespace tacse3::hal::can
