// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: encoder and decoder for every message (raw, table-driven, and typed).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <variant>

#include "tacse3/protocol/can_frame.hpp"
#include "tacse3/protocol/ids.hpp"
#include "tacse3/protocol/message_table.hpp"
#include "tacse3/protocol/status.hpp"
#include "tacse3/protocol/types.hpp"

namespace tacse3::protocol {

inline constexpr std::uint8_t kProtocolVersionMajor = 1;
inline constexpr std::uint8_t kProtocolVersionMinor = 1;
inline constexpr std::uint8_t kProtocolVersionPatch = 0;

// How the gripper (or the controller, for commands) transmits.
struct TxConfig {
  Endpoint endpoint{};  // node id of the gripper + identifier layout
  FrameMode frame_mode = FrameMode::kClassic;
  bool brs = true;  // CAN FD mode: switch to the data bit rate
};

// ---- raw layer -------------------------------------------------------------------------------
// Raw integer values of a message's signals, in table order (SignalDef::start etc.). A
// multiplexed signal is present only when the multiplexor selects it.
struct RawMessage {
  std::array<std::int64_t, kMaxSignals> value{};
  std::uint64_t present = 0;  // bit i set: signal i is present
};

// Read every present signal of `def` from `data` (at least def.length bytes). Infallible.
void unpack_raw(const MessageDef& def, const std::uint8_t* data, RawMessage& out) noexcept;
// Write the present signals of `raw` into `data` (def.length bytes, zeroed first). The CRC signal
// is written as given; use finish_frame() to compute it. Values are truncated to their width.
void pack_raw(const MessageDef& def, const RawMessage& raw, std::uint8_t* data) noexcept;

// Set identifier, format and length of `f` for `id` under `tx` (payload untouched).
Status prepare_frame(MessageId id, const TxConfig& tx, CanFrame& f) noexcept;
// Compute and store the CRC-8 (last payload byte).
void finish_frame(CanFrame& f) noexcept;

// Scaling of one signal: physical -> raw with round-half-away-from-zero and saturation into
// [raw_min, raw_max]; NaN or +-inf -> the invalid marker (or raw_min if the signal has none).
std::int64_t quantize(const SignalDef& s, double value, bool* saturated = nullptr) noexcept;
// raw -> physical; the invalid marker -> NaN.
double dequantize(const SignalDef& s, std::int64_t raw) noexcept;

// ---- typed messages ------------------------------------------------------------------------
struct TimestampMsg {
  std::uint64_t timestamp_us = 0;  // kTimestampInvalid = not available
  bool estimate_valid = false;
  bool single_sensor = false;
  bool pose_reset = false;
  bool saturated = false;
  std::uint8_t counter = 0;
};

struct AngularMsg {
  Vec3 angular;  // rad/s
  Saturation saturated;
  std::uint8_t counter = 0;
};

struct LinearMsg {
  Vec3 linear;  // m/s
  Saturation saturated;
  std::uint8_t counter = 0;
};

struct OrientationMsg {
  Quaternion orientation;
  std::uint8_t counter = 0;
};

struct PositionMsg {
  Vec3 position;  // m
  Saturation saturated;
  std::uint8_t counter = 0;
};

// One pipeline cycle: what the encoder takes and what the reassembler / FD decoder returns.
struct Cycle {
  std::uint64_t timestamp_us = 0;  // sensor sample time, board monotonic clock
  bool estimate_valid = false;
  bool single_sensor = false;
  bool pose_reset = false;
  Vec3 angular;            // rad/s, gripper frame
  Vec3 linear;             // m/s, gripper frame
  Quaternion orientation;  // unit quaternion, gripper frame
  Vec3 position;           // m, gripper frame
  // Output only (ignored by the encoder, set in CycleFrames::sent and by the decoders):
  Saturation angular_saturated;
  Saturation linear_saturated;
  Saturation position_saturated;
  bool saturated = false;
  std::uint8_t counter = 0;
};

struct StatusMsg {
  State state = State::kBooting;
  SensorHealth health_left = SensorHealth::kNotAvailable;
  SensorHealth health_right = SensorHealth::kNotAvailable;
  bool contact_left = false;
  bool contact_right = false;
  bool slip_left = false;
  bool slip_right = false;
  bool stream_enabled = true;
  FusionMethod fusion = FusionMethod::kJoint;
  VelocityMode velocity_mode = VelocityMode::kAuto;
  double confidence = 0.0;  // 0..1, NaN = not available
  std::uint8_t rate_divider = 1;
  FaultCode fault = FaultCode::kNone;
  std::uint8_t rejected_commands = 0;  // mod 256
  bool calibrated = false;             // a fitted calibration runs (0: UNCALIBRATED)
  std::uint8_t counter = 0;
};

struct ContactMsg {
  double area_left_m2 = 0.0;  // NaN = not available
  double area_right_m2 = 0.0;
  double confidence_left = 0.0;  // 0..1
  double confidence_right = 0.0;
  std::uint8_t counter = 0;
};

struct TimingMsg {
  double dsp_time_s = 0.0;  // NaN = not available
  double latency_p50_s = 0.0;
  double latency_p99_s = 0.0;
  std::uint8_t counter = 0;
};

struct CountersMsg {
  std::uint16_t dropped_left = 0;  // mod 65536
  std::uint16_t dropped_right = 0;
  std::uint16_t can_tx_dropped = 0;
  std::uint8_t counter = 0;
};

// A command as decoded (generic, not validated; see commands.hpp for validation) or to encode.
struct Command {
  CommandCode code = CommandCode::kTare;
  std::uint8_t target_node = 0;      // decoded payload byte 1; the encoder writes the target's node
  std::uint8_t sequence = 0;         // 0..15, echoed in the Ack
  double finger_separation_m = 0.0;  // kSetFingerSeparation
  FusionMethod fusion = FusionMethod::kJoint;        // kSetFusion
  VelocityMode velocity_mode = VelocityMode::kAuto;  // kSetFusion
  std::uint8_t rate_divider = 1;                     // kSetRateDivider
  bool stream_enabled = true;                        // kSetStream
  QueryItem query = QueryItem::kProtocolVersion;     // kQuery
  std::uint16_t recording_number = 0;                // kStartRecording
  std::array<std::uint8_t, 4> args{};                // decoded payload bytes 2..5 as received
};

struct Ack {
  CommandCode command = CommandCode::kTare;
  AckCode result = AckCode::kAck;
  std::uint8_t sequence = 0;
  std::array<std::uint8_t, 4> data{};  // payload bytes 2..5 (see docs/can-protocol.md)
};

struct Version {
  std::uint8_t major = 0;
  std::uint8_t minor = 0;
  std::uint8_t patch = 0;
};

// Decoded content of an Ack to a QUERY command.
struct QueryReply {
  QueryItem item = QueryItem::kProtocolVersion;
  Version version;                                   // kProtocolVersion, kFirmwareVersion
  double finger_separation_m = 0.0;                  // kFingerSeparation
  FusionMethod fusion = FusionMethod::kJoint;        // kFusion
  VelocityMode velocity_mode = VelocityMode::kAuto;  // kFusion
  bool stream_enabled = false;                       // kStream
  std::uint8_t rate_divider = 1;                     // kStream
  bool fd_mode = false;                              // kStream
  bool extended_ids = false;                         // kStream
};

using Payload = std::variant<TimestampMsg, AngularMsg, LinearMsg, OrientationMsg, PositionMsg,
                             Cycle, StatusMsg, ContactMsg, TimingMsg, CountersMsg, Command, Ack>;

struct Decoded {
  MessageId message = MessageId::kTimestamp;
  std::uint8_t node_id = 0;
  Payload payload;
};

// ---- encoder -------------------------------------------------------------------------------
inline constexpr std::size_t kClassicCycleFrames = 5;

struct CycleFrames {
  std::array<CanFrame, kClassicCycleFrames> frames{};
  std::size_t count = 0;  // 5 classic frames (Timestamp, TwistAngular, TwistLinear,
                          // PoseOrientation, PosePosition, in that order) or 1 CycleFd frame
  Cycle sent;             // the cycle exactly as a receiver decodes it (quantised, flags set)
};

// Encode one cycle. `counter` is taken mod 16. Values outside a field's range are clamped and
// flagged; NaN/inf fields are sent as invalid. A quaternion is normalised and sent with w >= 0;
// if it is not finite or its norm is outside [0.5, 2] it is sent as invalid.
// Fails only on a bad node id / extended base.
Status encode_cycle(const Cycle& in, std::uint8_t counter, const TxConfig& tx,
                    CycleFrames& out) noexcept;

Status encode(const StatusMsg& m, const TxConfig& tx, CanFrame& out) noexcept;
Status encode(const ContactMsg& m, const TxConfig& tx, CanFrame& out) noexcept;
Status encode(const TimingMsg& m, const TxConfig& tx, CanFrame& out) noexcept;
Status encode(const CountersMsg& m, const TxConfig& tx, CanFrame& out) noexcept;

// The periodic status emission: Status, StatusContact, StatusTiming, StatusCounters sharing one
// status counter (each message's own counter field is ignored).
struct StatusGroup {
  StatusMsg status;
  ContactMsg contact;
  TimingMsg timing;
  CountersMsg counters;
};
Status encode_status_group(const StatusGroup& g, std::uint8_t counter, const TxConfig& tx,
                           std::array<CanFrame, 4>& out) noexcept;

// Controller side: encode a command addressed to tx.endpoint.node_id (written to both the
// identifier and TargetNode). kBadArgument if an argument is outside its documented range.
Status encode(const Command& c, const TxConfig& tx, CanFrame& out) noexcept;
// Gripper side: encode an ACK/NACK.
Status encode(const Ack& a, const TxConfig& tx, CanFrame& out) noexcept;

// ---- decoder -------------------------------------------------------------------------------
// Decode any tacse3 frame of any node under `layout`: identifier, length/format, CRC, then the
// typed payload. Reserved bits are ignored. Commands are decoded but not validated.
Status decode(const CanFrame& f, const IdLayout& layout, Decoded& out) noexcept;

// Check only identifier, length/format and CRC (what decode() checks before unpacking).
Status check_frame(const CanFrame& f, const IdLayout& layout, SplitId& id,
                   const MessageDef*& def) noexcept;

// Query replies (QUERY command): build the Ack data / read it back.
Ack make_query_reply(const Command& query, const QueryReply& reply) noexcept;
Status decode_query_reply(const Ack& a, QueryReply& out) noexcept;

}  // namespace tacse3::protocol
