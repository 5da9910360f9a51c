// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: command validation (gripper side) and ACK/NACK construction.
#pragma once

#include <cstdint>

#include "tacse3/protocol/codec.hpp"

namespace tacse3::protocol {

struct CommandStats {
  std::uint32_t accepted = 0;
  std::uint32_t other_node = 0;  // commands for another node (ignored, not an error)
  std::uint32_t unknown_command = 0;
  std::uint32_t bad_length = 0;
  std::uint32_t bad_crc = 0;
  std::uint32_t wrong_node = 0;
  std::uint32_t out_of_range = 0;
  std::uint32_t reserved_not_zero = 0;
  std::uint32_t rejected() const noexcept {
    return unknown_command + bad_length + bad_crc + wrong_node + out_of_range + reserved_not_zero;
  }
};

struct CommandResult {
  bool addressed = false;          // a Command frame for this node: answer it with make_ack()
  AckCode code = AckCode::kAck;    // kAck: valid, `command` may be applied (all or nothing)
  Command command;                 // decoded fields (meaningful when code == kAck)
  std::uint8_t echo_code = 0;      // payload byte 0 as received (0 if absent)
  std::uint8_t echo_sequence = 0;  // sequence as received (0 if absent)
  std::array<std::uint8_t, 4> echo_args{};  // payload bytes 2..5 as received
};

// Validate one command frame without applying anything. Checks, in order: identifier (this node's
// Command id, else not addressed), length 8, CRC, known command code, TargetNode == node id,
// reserved bits zero, argument ranges. The first failing check is the NACK reason.
CommandResult validate_command(const CanFrame& f, const Endpoint& self) noexcept;

// The ACK/NACK answering `r`: command code and sequence echoed, bytes 2..5 echo the arguments.
Ack make_ack(const CommandResult& r) noexcept;

// validate_command() plus counting, for the firmware's command path.
class CommandReceiver {
 public:
  explicit CommandReceiver(const Endpoint& self = Endpoint{}) noexcept : self_(self) {}
  CommandResult receive(const CanFrame& f) noexcept;
  const CommandStats& stats() const noexcept { return stats_; }
  const Endpoint& endpoint() const noexcept { return self_; }

 private:
  Endpoint self_;
  CommandStats stats_;
};

}  // namespace tacse3::protocol
