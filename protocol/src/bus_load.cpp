// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: frame lengths with bit stuffing and the table's worst-case bus load.
#include "tacse3/protocol/bus_load.hpp"

#include <array>

namespace tacse3::protocol {
namespace {

// Bits from SOF to the end of the data field of a classic frame, MSB first, as sent.
struct BitBuffer {
  std::array<std::uint8_t, 160> bit{};
  unsigned n = 0;
  void push(std::uint32_t value, unsigned count) noexcept {
    for (unsigned i = count; i-- > 0;) bit[n++] = static_cast<std::uint8_t>((value >> i) & 1u);
  }
};

// CAN CRC-15 (polynomial 0x4599) over the bit stream.
std::uint32_t can_crc15(const BitBuffer& b) noexcept {
  std::uint32_t crc = 0;
  for (unsigned i = 0; i < b.n; ++i) {
    const std::uint32_t next = b.bit[i] ^ ((crc >> 14) & 1u);
    crc = (crc << 1) & 0x7FFFu;
    if (next != 0) crc ^= 0x4599u;
  }
  return crc;
}

unsigned count_stuff_bits(const BitBuffer& b) noexcept {
  unsigned stuff = 0;
  unsigned run = 0;
  std::uint8_t last = 2;
  for (unsigned i = 0; i < b.n; ++i) {
    if (b.bit[i] == last) {
      ++run;
    } else {
      last = b.bit[i];
      run = 1;
    }
    if (run == 5) {
      // A stuff bit of the opposite level is inserted and starts a new run.
      ++stuff;
      last = static_cast<std::uint8_t>(1u - last);
      run = 1;
    }
  }
  return stuff;
}

}  // namespace

double frame_time_worst_s(unsigned len, bool extended, bool fd, bool brs,
                          const BitTiming& t) noexcept {
  if (!fd) return static_cast<double>(classic_frame_bits_worst(len, extended)) / t.nominal_bps;
  const FdBits b = fd_frame_bits_worst(len, extended);
  const double data_bps = brs ? t.data_bps : t.nominal_bps;
  return static_cast<double>(b.nominal) / t.nominal_bps + static_cast<double>(b.data) / data_bps;
}

unsigned frame_bits_on_wire(const CanFrame& f, const BitTiming& t, bool* exact) noexcept {
  if (f.fd || f.len > kClassicMaxLen) {
    if (exact != nullptr) *exact = false;
    const double s = frame_time_worst_s(f.len, f.extended, true, f.brs, t);
    return static_cast<unsigned>(s * t.nominal_bps + 0.5);
  }
  if (exact != nullptr) *exact = true;
  BitBuffer b;
  b.push(0, 1);  // SOF
  if (f.extended) {
    b.push((f.id >> 18) & 0x7FFu, 11);  // base id
    b.push(1, 1);                       // SRR
    b.push(1, 1);                       // IDE
    b.push(f.id & 0x3FFFFu, 18);        // id extension
    b.push(0, 1);                       // RTR (data frame)
    b.push(0, 2);                       // r1, r0
  } else {
    b.push(f.id & 0x7FFu, 11);
    b.push(0, 1);  // RTR
    b.push(0, 1);  // IDE
    b.push(0, 1);  // r0
  }
  b.push(f.len, 4);
  for (unsigned i = 0; i < f.len; ++i) b.push(f.data[i], 8);
  b.push(can_crc15(b), 15);
  // CRC delimiter, ACK slot, ACK delimiter, EOF (7) and intermission (3) are not stuffed.
  return b.n + count_stuff_bits(b) + 13u;
}

BusLoad worst_case_bus_load(IdMode ids, FrameMode mode, const BitTiming& timing,
                            bool brs) noexcept {
  BusLoad out;
  const bool extended = ids == IdMode::kExtended;
  for (const MessageDef& m : kMessages) {
    if (m.stream == Stream::kClassicCycle && mode != FrameMode::kClassic) continue;
    if (m.stream == Stream::kFdCycle && mode != FrameMode::kFd) continue;
    BusLoadLine& l = out.lines[out.count++];
    l.message = &m;
    l.fd = mode == FrameMode::kFd && m.sender == Sender::kGripper;
    l.rate_hz = m.max_rate_hz;
    l.frame_time_s = frame_time_worst_s(m.length, extended, l.fd, l.fd && brs, timing);
    l.load = l.rate_hz * l.frame_time_s;
    out.frames_per_s += l.rate_hz;
    out.load += l.load;
  }
  return out;
}

}  // namespace tacse3::protocol
