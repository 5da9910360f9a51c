// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: command validation and ACK/NACK construction.
#include "tacse3/protocol/commands.hpp"

#include <cstring>
#include <variant>

#include "tacse3/protocol/crc8.hpp"

namespace tacse3::protocol {
namespace {

// Number of argument bytes (from byte 2) each command uses; the rest of bytes 2..5 is reserved.
int argument_bytes(std::uint8_t code) noexcept {
  switch (static_cast<CommandCode>(code)) {
    case CommandCode::kTare:
    case CommandCode::kResetPose:
    case CommandCode::kStopRecording:
      return 0;
    case CommandCode::kSetFingerSeparation:
    case CommandCode::kSetFusion:
    case CommandCode::kStartRecording:
      return 2;
    case CommandCode::kSetRateDivider:
    case CommandCode::kSetStream:
    case CommandCode::kQuery:
      return 1;
  }
  return -1;
}

bool in_range(const SignalDef& s, std::int64_t raw) noexcept {
  return raw >= s.raw_min && raw <= s.raw_max;
}

}  // namespace

CommandResult validate_command(const CanFrame& f, const Endpoint& self) noexcept {
  CommandResult r;
  SplitId id;
  if (split_id(self.layout, f.id, f.extended, id) != Status::kOk) return r;
  if (id.node != self.node_id || id.message != static_cast<std::uint8_t>(MessageId::kCommand)) {
    return r;
  }
  r.addressed = true;
  const std::size_t n = f.len <= f.data.size() ? f.len : f.data.size();
  if (n >= 1) r.echo_code = f.data[0];
  if (n >= 7) r.echo_sequence = static_cast<std::uint8_t>(f.data[6] >> 4);
  for (std::size_t i = 0; i < 4; ++i) {
    if (2 + i < n) r.echo_args[i] = f.data[2 + i];
  }
  if (f.len != 8) {
    r.code = AckCode::kBadLength;
    return r;
  }
  if (frame_crc(f) != f.data[7]) {
    r.code = AckCode::kBadCrc;
    return r;
  }
  const int used = argument_bytes(f.data[0]);
  if (used < 0) {
    r.code = AckCode::kUnknownCommand;
    return r;
  }
  if (f.data[1] != self.node_id) {
    r.code = AckCode::kWrongNode;
    return r;
  }
  bool reserved_clear = (f.data[6] & 0x0Fu) == 0;
  for (int i = 2 + used; i < 6; ++i) reserved_clear = reserved_clear && f.data[i] == 0;
  if (!reserved_clear) {
    r.code = AckCode::kReservedNotZero;
    return r;
  }
  Decoded d;
  const Command* cmd = nullptr;
  if (decode(f, self.layout, d) == Status::kOk) cmd = std::get_if<Command>(&d.payload);
  if (cmd == nullptr) {
    r.code = AckCode::kInternalError;  // unreachable: identifier, length and CRC were checked
    return r;
  }
  r.command = *cmd;
  const auto& s = table::kCommand;
  bool ok = true;
  switch (r.command.code) {
    case CommandCode::kSetFingerSeparation:
      ok = in_range(s[2], f.data[2] | (static_cast<std::int64_t>(f.data[3]) << 8));
      break;
    case CommandCode::kSetFusion:
      ok = in_range(s[3], f.data[2]) && in_range(s[4], f.data[3]);
      break;
    case CommandCode::kSetRateDivider:
      ok = in_range(s[5], f.data[2]);
      break;
    case CommandCode::kSetStream:
      ok = in_range(s[6], f.data[2]);
      break;
    case CommandCode::kQuery:
      ok = in_range(s[7], f.data[2]);
      break;
    case CommandCode::kTare:
    case CommandCode::kResetPose:
    case CommandCode::kStartRecording:  // every uint16 is a recording number
    case CommandCode::kStopRecording:
      break;
  }
  r.code = ok ? AckCode::kAck : AckCode::kOutOfRange;
  return r;
}

Ack make_ack(const CommandResult& r) noexcept {
  Ack a;
  a.command = static_cast<CommandCode>(r.echo_code);
  a.result = r.code;
  a.sequence = r.echo_sequence;
  a.data = r.echo_args;
  return a;
}

CommandResult CommandReceiver::receive(const CanFrame& f) noexcept {
  CommandResult r = validate_command(f, self_);
  if (!r.addressed) {
    SplitId id;
    if (split_id(self_.layout, f.id, f.extended, id) == Status::kOk &&
        id.message == static_cast<std::uint8_t>(MessageId::kCommand)) {
      ++stats_.other_node;
    }
    return r;
  }
  switch (r.code) {
    case AckCode::kAck:
      ++stats_.accepted;
      break;
    case AckCode::kUnknownCommand:
      ++stats_.unknown_command;
      break;
    case AckCode::kBadLength:
      ++stats_.bad_length;
      break;
    case AckCode::kBadCrc:
      ++stats_.bad_crc;
      break;
    case AckCode::kWrongNode:
      ++stats_.wrong_node;
      break;
    case AckCode::kOutOfRange:
      ++stats_.out_of_range;
      break;
    case AckCode::kReservedNotZero:
      ++stats_.reserved_not_zero;
      break;
    case AckCode::kBusy:
    case AckCode::kInternalError:
    case AckCode::kAlreadyRecording:
    case AckCode::kNotRecording:
    case AckCode::kNoRecordDir:
    case AckCode::kRecordingExists:
    case AckCode::kDiskError:
      break;
  }
  return r;
}

}  // namespace tacse3::protocol
