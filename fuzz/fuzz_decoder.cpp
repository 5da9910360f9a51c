// SPDX-License-Identifier: Apache-2.0
// tacse3 fuzz: the frame decoder and the table-driven raw layer on arbitrary frames.
//
// Input: [flags][id: 4 bytes LE][len][payload...]; flags bit 0 = 29-bit id, bit 1 = CAN FD,
// bit 2 = BRS, bit 3 = decode under the 29-bit layout, bit 4 = recompute the CRC (reach the
// payload decoders, not only the CRC check).
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 6) return 0;
  tp::CanFrame f;
  const std::uint8_t flags = data[0];
  f.extended = (flags & 1u) != 0;
  f.fd = (flags & 2u) != 0;
  f.brs = (flags & 4u) != 0;
  std::uint32_t id = 0;
  std::memcpy(&id, data + 1, 4);
  f.id = id & (f.extended ? tp::kExtendedIdMask : tp::kStandardIdMask);
  const std::size_t avail = size - 6;
  f.len = static_cast<std::uint8_t>(data[5] % (tp::kFdMaxLen + 1));
  if (f.len > avail) f.len = static_cast<std::uint8_t>(avail);
  std::memcpy(f.data.data(), data + 6, f.len);
  if ((flags & 16u) != 0 && f.len > 0) f.data[f.len - 1u] = tp::frame_crc(f);

  tp::IdLayout layout;
  if ((flags & 8u) != 0) layout.mode = tp::IdMode::kExtended;
  tp::Decoded d;
  const tp::Status s = tp::decode(f, layout, d);
  if (s == tp::Status::kOk) {
    // Accepted frames are well-formed: valid length, matching CRC, a known message.
    const tp::MessageDef* def = tp::find_message(static_cast<std::uint8_t>(d.message));
    if (def == nullptr || def->length != f.len || tp::frame_crc(f) != f.data[f.len - 1u]) {
      __builtin_trap();
    }
    // unpack -> pack reproduces every bit a present signal covers.
    tp::RawMessage raw;
    tp::unpack_raw(*def, f.data.data(), raw);
    std::uint8_t out[64] = {};
    tp::pack_raw(*def, raw, out);
    tp::RawMessage again;
    tp::unpack_raw(*def, out, again);
    for (std::size_t i = 0; i < def->signals.size(); ++i) {
      if (raw.value[i] != again.value[i] || raw.present != again.present) __builtin_trap();
    }
    (void)tp::validate_command(f, tp::Endpoint{d.node_id, layout});
  }
  tp::CycleReassembler r(tp::Endpoint{1, layout});
  tp::Cycle c;
  (void)r.feed(f, c);
  (void)tp::frame_bits_on_wire(f, tp::BitTiming{});
  return 0;
}
