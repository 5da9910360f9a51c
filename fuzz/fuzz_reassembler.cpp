// SPDX-License-Identifier: Apache-2.0
// tacse3 fuzz: the cycle reassembler on arbitrary sequences of (mostly well-formed) cycle frames.
//
// Input: records of [ctrl][payload bytes]; ctrl bits 0..2 pick the message (Timestamp ..
// PosePosition, CycleFd, Status), bit 3 corrupts the CRC, bit 4 sends it as node 2, bit 5 uses
// a wrong length. Classic records take 7 payload bytes, CycleFd 63; the CRC is computed.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "tacse3/protocol/protocol.hpp"

namespace tp = tacse3::protocol;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static constexpr tp::MessageId kIds[8] = {
      tp::MessageId::kTimestamp,       tp::MessageId::kTwistAngular, tp::MessageId::kTwistLinear,
      tp::MessageId::kPoseOrientation, tp::MessageId::kPosePosition, tp::MessageId::kCycleFd,
      tp::MessageId::kStatus,          tp::MessageId::kTimestamp};
  tp::CycleReassembler r(tp::Endpoint{});
  std::size_t i = 0;
  std::uint32_t emitted = 0;
  bool have_t = false;
  std::uint64_t last_t = 0;
  while (i < size) {
    const std::uint8_t ctrl = data[i++];
    const tp::MessageId id = kIds[ctrl & 7u];
    tp::TxConfig tx;
    tx.endpoint.node_id = (ctrl & 16u) != 0 ? 2 : 1;
    tx.frame_mode = id == tp::MessageId::kCycleFd ? tp::FrameMode::kFd : tp::FrameMode::kClassic;
    tp::CanFrame f;
    (void)tp::prepare_frame(id, tx, f);
    const std::size_t n = f.len - 1u;
    const std::size_t take = size - i < n ? size - i : n;
    std::memcpy(f.data.data(), data + i, take);
    i += take;
    tp::finish_frame(f);
    if ((ctrl & 8u) != 0) f.data[f.len - 1u] ^= 0x5A;
    if ((ctrl & 32u) != 0) f.len = static_cast<std::uint8_t>(f.len == 64 ? 48 : 7);
    tp::Cycle c;
    if (r.feed(f, c) == tp::CycleReassembler::Result::kComplete) {
      ++emitted;
      // Emitted cycles have strictly increasing valid timestamps.
      if (c.timestamp_us != tp::kTimestampInvalid) {
        if (have_t && c.timestamp_us <= last_t) __builtin_trap();
        have_t = true;
        last_t = c.timestamp_us;
      }
    }
  }
  const tp::ReassemblerStats& s = r.stats();
  if (s.samples != emitted || s.samples > s.frames) __builtin_trap();
  return 0;
}
