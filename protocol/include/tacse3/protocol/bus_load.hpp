// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: CAN frame lengths with bit stuffing and the bus load of the message table.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "tacse3/protocol/can_frame.hpp"
#include "tacse3/protocol/ids.hpp"
#include "tacse3/protocol/message_table.hpp"

namespace tacse3::protocol {

// Classic CAN data frame, worst-case bit stuffing, including the 3-bit intermission:
//   standard: 47 + 8n + floor((34 + 8n - 1) / 4)    (n = 8: 135 bits)
//   extended: 67 + 8n + floor((54 + 8n - 1) / 4)    (n = 8: 160 bits)
// 34 / 54 bits (SOF .. end of CRC, without data) are subject to stuffing; a stuff bit follows
// at most every 4 bits after the first 5.
constexpr unsigned classic_frame_bits_worst(unsigned len, bool extended) noexcept {
  const unsigned stuffed = (extended ? 54u : 34u) + 8u * len;
  const unsigned fixed = extended ? 67u : 47u;
  return fixed + 8u * len + (stuffed - 1u) / 4u;
}

// CAN FD data frame, worst-case stuffing, split into the bits sent at the nominal (arbitration)
// bit rate and those sent in the data phase (at the data bit rate when BRS is set):
//   nominal: arbitration field through BRS (17 std / 36 ext) + its stuff bits
//            + CRC delimiter, ACK, ACK delimiter, EOF, intermission (13)
//   data:    ESI + DLC (5) + 8n + remaining dynamic stuff bits + stuff count (4)
//            + CRC (17 for n <= 16, else 21) + fixed stuff bits (6 / 7)
struct FdBits {
  unsigned nominal = 0;
  unsigned data = 0;
};
constexpr FdBits fd_frame_bits_worst(unsigned len, bool extended) noexcept {
  const unsigned arb = extended ? 36u : 17u;
  const unsigned dynamic_region = arb + 5u + 8u * len;
  const unsigned stuff_total = (dynamic_region - 1u) / 4u;
  const unsigned stuff_nominal = (arb - 1u) / 4u;
  const unsigned crc_bits = len <= 16u ? 17u : 21u;
  const unsigned fixed_stuff = len <= 16u ? 6u : 7u;
  FdBits b;
  b.nominal = arb + stuff_nominal + 13u;
  b.data = 5u + 8u * len + (stuff_total - stuff_nominal) + 4u + crc_bits + fixed_stuff;
  return b;
}

struct BitTiming {
  double nominal_bps = 500000.0;
  double data_bps = 2000000.0;  // CAN FD data phase (used when BRS is set)
};

// Worst-case time one frame occupies the bus, in seconds.
double frame_time_worst_s(unsigned len, bool extended, bool fd, bool brs,
                          const BitTiming& t) noexcept;

// Exact length in bits of one classic frame as transmitted (actual stuff bits, CRC-15 computed),
// including the 3-bit intermission. FD frames: returns the worst-case nominal-equivalent bits.
unsigned frame_bits_on_wire(const CanFrame& f, const BitTiming& t, bool* exact = nullptr) noexcept;

struct BusLoadLine {
  const MessageDef* message = nullptr;
  bool fd = false;            // sent as a CAN FD frame in this mode
  double rate_hz = 0.0;       // worst-case frames per second
  double frame_time_s = 0.0;  // worst-case time per frame
  double load = 0.0;          // rate_hz * frame_time_s * 1 (fraction of the bus)
};

struct BusLoad {
  std::array<BusLoadLine, kMessages.size()> lines{};
  std::size_t count = 0;
  double frames_per_s = 0.0;
  double load = 0.0;  // fraction of bus time, 0..1
};

// Worst-case bus load of one node from the message table: every message sent in `mode` at its
// max_rate_hz, worst-case stuffing. In FD mode the gripper's frames are CAN FD frames (with
// `brs`), the controller's commands are counted as classic frames.
BusLoad worst_case_bus_load(IdMode ids, FrameMode mode, const BitTiming& timing,
                            bool brs = true) noexcept;

}  // namespace tacse3::protocol
