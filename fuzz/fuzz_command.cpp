// SPDX-License-Identifier: Apache-2.0
// tacse3 fuzz: command parsing/validation; an accepted command is exactly its canonical encoding.
//
// Input: [ctrl][len][payload...]; ctrl bits 0..5 = node id in the identifier, bit 6 = recompute
// the CRC, bit 7 = CAN FD frame.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const tp::Endpoint self{};  // node 1
  tp::CanFrame f;
  f.id = tp::compose_id(self.layout, static_cast<std::uint8_t>(data[0] & 0x3Fu),
                        tp::MessageId::kCommand);
  f.fd = (data[0] & 0x80u) != 0;
  const std::size_t avail = size - 2;
  f.len = static_cast<std::uint8_t>(data[1] % 65u);
  if (f.len > avail) f.len = static_cast<std::uint8_t>(avail);
  std::memcpy(f.data.data(), data + 2, f.len);
  if ((data[0] & 0x40u) != 0 && f.len > 0) f.data[f.len - 1u] = tp::frame_crc(f);

  tp::CommandReceiver rx(self);
  const tp::CommandResult r = rx.receive(f);
  if (r.addressed) {
    const tp::Ack ack = tp::make_ack(r);
    tp::CanFrame out;
    if (tp::encode(ack, tp::TxConfig{}, out) != tp::Status::kOk) __builtin_trap();
    tp::Decoded d;
    if (tp::decode(out, self.layout, d) != tp::Status::kOk) __builtin_trap();
  }
  if (r.addressed && r.code == tp::AckCode::kAck) {
    // Canonical: re-encoding the decoded command gives the very same 8 bytes.
    tp::CanFrame again;
    if (tp::encode(r.command, tp::TxConfig{}, again) != tp::Status::kOk) __builtin_trap();
    if (again.len != 8 || std::memcmp(again.data.data(), f.data.data(), 8) != 0) __builtin_trap();
    if (rx.stats().accepted != 1) __builtin_trap();
  }
  return 0;
}
