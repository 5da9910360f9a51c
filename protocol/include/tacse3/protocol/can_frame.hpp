// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: an OS-independent CAN / CAN FD frame value type.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace tacse3::protocol {

inline constexpr std::uint32_t kStandardIdMask = 0x7FFu;          // 11-bit identifier
inline constexpr std::uint32_t kExtendedIdMask = 0x1FFFFFFFu;     // 29-bit identifier
inline constexpr std::uint32_t kCrcIdExtendedFlag = 0x80000000u;  // bit 31 of the CRC id word
inline constexpr std::size_t kClassicMaxLen = 8;
inline constexpr std::size_t kFdMaxLen = 64;

// One data frame as it is on the bus. The layout mirrors SocketCAN's canfd_frame without
// depending on it: `id` holds the bare identifier and the flags are separate booleans.
struct CanFrame {
  std::uint32_t id = 0;   // 11-bit (extended == false) or 29-bit identifier, no flag bits
  bool extended = false;  // IDE: 29-bit identifier
  bool fd = false;        // FDF: CAN FD frame
  bool brs = false;       // CAN FD bit-rate switch (data phase at the data bit rate)
  std::uint8_t len = 0;   // payload length in bytes (classic 0..8; FD one of kFdLengths)
  std::array<std::uint8_t, kFdMaxLen> data{};
};

// The identifier as the CRC-8 covers it: SocketCAN's can_id with CAN_EFF_FLAG (bit 31) set for
// a 29-bit identifier and the RTR/ERR bits clear.
constexpr std::uint32_t crc_id_word(const CanFrame& f) noexcept {
  return f.extended ? ((f.id & kExtendedIdMask) | kCrcIdExtendedFlag) : (f.id & kStandardIdMask);
}

// Payload lengths a CAN FD frame can carry (DLC 0..15).
inline constexpr std::array<std::uint8_t, 16> kFdLengths = {0, 1,  2,  3,  4,  5,  6,  7,
                                                            8, 12, 16, 20, 24, 32, 48, 64};

constexpr bool is_valid_length(bool fd, std::size_t len) noexcept {
  if (!fd) return len <= kClassicMaxLen;
  for (auto l : kFdLengths) {
    if (l == len) return true;
  }
  return false;
}

// DLC code (0..15) of a valid payload length, or -1.
constexpr int length_to_dlc(std::size_t len) noexcept {
  for (std::size_t i = 0; i < kFdLengths.size(); ++i) {
    if (kFdLengths[i] == len) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace tacse3::protocol
