// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: CRC-8/SAE-J1850 and the frame CRC rule (identifier word + payload).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "tacse3/protocol/can_frame.hpp"

namespace tacse3::protocol {

// CRC-8/SAE-J1850 (the AUTOSAR E2E Profile 1 CRC): polynomial x^8+x^4+x^3+x^2+1 (0x1D),
// initial value 0xFF, no input/output reflection, final XOR 0xFF. Check value: "123456789" -> 0x4B.
inline constexpr std::uint8_t kCrc8Poly = 0x1D;
inline constexpr std::uint8_t kCrc8Init = 0xFF;
inline constexpr std::uint8_t kCrc8XorOut = 0xFF;

namespace detail {
constexpr std::array<std::uint8_t, 256> make_crc8_table() noexcept {
  std::array<std::uint8_t, 256> t{};
  for (unsigned i = 0; i < 256; ++i) {
    unsigned c = i;
    for (int b = 0; b < 8; ++b) {
      c = (c & 0x80u) != 0 ? ((c << 1) ^ kCrc8Poly) : (c << 1);
    }
    t[i] = static_cast<std::uint8_t>(c & 0xFFu);
  }
  return t;
}
inline constexpr std::array<std::uint8_t, 256> kCrc8Table = make_crc8_table();
}  // namespace detail

// Register update without init/final XOR, so a CRC can be computed over several pieces.
constexpr std::uint8_t crc8_update(std::uint8_t crc, const std::uint8_t* data,
                                   std::size_t n) noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    crc = detail::kCrc8Table[static_cast<std::uint8_t>(crc ^ data[i])];
  }
  return crc;
}

constexpr std::uint8_t crc8(const std::uint8_t* data, std::size_t n) noexcept {
  return static_cast<std::uint8_t>(crc8_update(kCrc8Init, data, n) ^ kCrc8XorOut);
}

// The tacse3 frame CRC: over the 4-byte little-endian identifier word (crc_id_word) followed by
// payload bytes 0 .. len-2. The CRC itself is the last payload byte (byte 7 classic, 63 FD).
constexpr std::uint8_t frame_crc(const CanFrame& f) noexcept {
  const std::uint32_t w = crc_id_word(f);
  const std::uint8_t idb[4] = {
      static_cast<std::uint8_t>(w & 0xFFu), static_cast<std::uint8_t>((w >> 8) & 0xFFu),
      static_cast<std::uint8_t>((w >> 16) & 0xFFu), static_cast<std::uint8_t>((w >> 24) & 0xFFu)};
  std::uint8_t c = crc8_update(kCrc8Init, idb, 4);
  if (f.len > 1) c = crc8_update(c, f.data.data(), static_cast<std::size_t>(f.len) - 1);
  return static_cast<std::uint8_t>(c ^ kCrc8XorOut);
}

}  // namespace tacse3::protocol
