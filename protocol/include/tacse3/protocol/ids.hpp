// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: message ids and the identifier layout (node id + message id).
#pragma once

#include <cstdint>

#include "tacse3/protocol/can_frame.hpp"
#include "tacse3/protocol/status.hpp"

namespace tacse3::protocol {

// Message id: the low 5 bits of every identifier. 0x00 is never used, so no tacse3 frame ever
// has identifier 0x000 (CANopen NMT), 0x080 (SYNC) or 0x100 (TIME).
enum class MessageId : std::uint8_t {
  kTimestamp = 0x01,        // cyclic: sample time + cycle flags
  kTwistAngular = 0x02,     // cyclic: angular velocity
  kTwistLinear = 0x03,      // cyclic: linear velocity
  kPoseOrientation = 0x04,  // cyclic: orientation quaternion
  kPosePosition = 0x05,     // cyclic: position
  kCycleFd = 0x06,          // cyclic, CAN FD mode: the whole cycle in one 64-byte frame
  kStatus = 0x08,           // heartbeat: state, health, flags, configuration
  kStatusContact = 0x09,    // contact areas, per-sensor confidence
  kStatusTiming = 0x0A,     // DSP time, latency
  kStatusCounters = 0x0B,   // dropped-frame counters
  kCommand = 0x10,          // controller -> gripper
  kAck = 0x11,              // gripper -> controller, ACK/NACK of a command
};

inline constexpr std::uint32_t kMessageIdBits = 5;
inline constexpr std::uint32_t kMessageIdMask = 0x1Fu;
inline constexpr std::uint32_t kNodeIdBits = 6;
inline constexpr std::uint32_t kNodeIdMask = 0x3Fu;
inline constexpr std::uint8_t kMinNodeId = 1;  // node 0 is reserved (it would produce id 0x000)
inline constexpr std::uint8_t kMaxNodeId = 63;
inline constexpr std::uint8_t kDefaultNodeId = 1;
// 29-bit option: identifier = extended_base | node << 5 | message. The base occupies bits
// 11..28 and can be changed per installation (e.g. to stay clear of J1939 traffic).
inline constexpr std::uint32_t kDefaultExtendedBase = 0x1ACE0000u;

enum class IdMode : std::uint8_t { kStandard = 0, kExtended = 1 };
enum class FrameMode : std::uint8_t { kClassic = 0, kFd = 1 };

struct IdLayout {
  IdMode mode = IdMode::kStandard;
  std::uint32_t extended_base = kDefaultExtendedBase;
};

// One gripper on the bus: its node id and the identifier layout of the bus.
struct Endpoint {
  std::uint8_t node_id = kDefaultNodeId;
  IdLayout layout{};
};

constexpr bool is_valid_node_id(unsigned node) noexcept {
  return node >= kMinNodeId && node <= kMaxNodeId;
}

constexpr bool is_valid_extended_base(std::uint32_t base) noexcept {
  return (base & ~kExtendedIdMask) == 0 && (base & kStandardIdMask) == 0;
}

// Identifier of `msg` sent by / addressed to `node` (no validation; see make_frame_id).
constexpr std::uint32_t compose_id(const IdLayout& layout, std::uint8_t node,
                                   MessageId msg) noexcept {
  const std::uint32_t low = (static_cast<std::uint32_t>(node & kNodeIdMask) << kMessageIdBits) |
                            (static_cast<std::uint32_t>(msg) & kMessageIdMask);
  return layout.mode == IdMode::kExtended ? (layout.extended_base | low) : low;
}

struct SplitId {
  std::uint8_t node = 0;
  std::uint8_t message = 0;  // raw 5-bit message id (may be one that is not in the table)
};

// Split an identifier under `layout`. kUnknownId if the format (11/29-bit) or the extended base
// does not match, or the node id is 0.
constexpr Status split_id(const IdLayout& layout, std::uint32_t id, bool extended,
                          SplitId& out) noexcept {
  if (layout.mode == IdMode::kStandard) {
    if (extended || id > kStandardIdMask) return Status::kUnknownId;
  } else {
    if (!extended || id > kExtendedIdMask) return Status::kUnknownId;
    if ((id & ~kStandardIdMask) != layout.extended_base) return Status::kUnknownId;
  }
  const auto node = static_cast<std::uint8_t>((id >> kMessageIdBits) & kNodeIdMask);
  if (node == 0) return Status::kUnknownId;
  out.node = node;
  out.message = static_cast<std::uint8_t>(id & kMessageIdMask);
  return Status::kOk;
}

}  // namespace tacse3::protocol
