// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: table-driven pack/unpack, scaling and the typed encoder/decoder.
#include "tacse3/protocol/codec.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include "tacse3/protocol/crc8.hpp"

namespace tacse3::protocol {
namespace {

// Signal positions inside the tables, checked against the names at compile time so that a
// table edit cannot silently shift a field.
constexpr bool named(std::span<const SignalDef> sigs, std::size_t i, std::string_view name) {
  return i < sigs.size() && sigs[i].name == name;
}
// Three-axis frames: X, Y, Z at 0..2, saturation flags at 3..5, counter at 6.
static_assert(named(table::kTwistAngular, 0, "AngVelX") &&
              named(table::kTwistAngular, 3, "AngVelXSat") &&
              named(table::kTwistAngular, 6, "Counter"));
static_assert(named(table::kTwistLinear, 0, "LinVelX") &&
              named(table::kTwistLinear, 5, "LinVelZSat") &&
              named(table::kTwistLinear, 6, "Counter"));
static_assert(named(table::kPosePosition, 0, "PosX") && named(table::kPosePosition, 4, "PosYSat") &&
              named(table::kPosePosition, 6, "Counter"));
static_assert(named(table::kPoseOrientation, 0, "QuatW") &&
              named(table::kPoseOrientation, 3, "QuatZ") &&
              named(table::kPoseOrientation, 4, "Counter"));
static_assert(named(table::kTimestamp, 0, "SampleTime") &&
              named(table::kTimestamp, 1, "EstimateValid") &&
              named(table::kTimestamp, 2, "SingleSensor") &&
              named(table::kTimestamp, 3, "PoseReset") &&
              named(table::kTimestamp, 4, "Saturated") && named(table::kTimestamp, 5, "Counter"));
static_assert(named(table::kStatus, 0, "State") && named(table::kStatus, 1, "HealthLeft") &&
              named(table::kStatus, 2, "HealthRight") && named(table::kStatus, 3, "ContactLeft") &&
              named(table::kStatus, 4, "ContactRight") && named(table::kStatus, 5, "SlipLeft") &&
              named(table::kStatus, 6, "SlipRight") && named(table::kStatus, 7, "StreamEnabled") &&
              named(table::kStatus, 8, "FusionMethod") &&
              named(table::kStatus, 9, "VelocityMode") && named(table::kStatus, 10, "Confidence") &&
              named(table::kStatus, 11, "RateDivider") && named(table::kStatus, 12, "FaultCode") &&
              named(table::kStatus, 13, "RejectedCommands") &&
              named(table::kStatus, 14, "Calibrated") && named(table::kStatus, 15, "Counter"));
static_assert(named(table::kStatusContact, 0, "AreaLeft") &&
              named(table::kStatusContact, 1, "AreaRight") &&
              named(table::kStatusContact, 2, "ConfidenceLeft") &&
              named(table::kStatusContact, 3, "ConfidenceRight") &&
              named(table::kStatusContact, 4, "Counter"));
static_assert(named(table::kStatusTiming, 0, "DspTime") &&
              named(table::kStatusTiming, 1, "LatencyP50") &&
              named(table::kStatusTiming, 2, "LatencyP99") &&
              named(table::kStatusTiming, 3, "Counter"));
static_assert(named(table::kStatusCounters, 0, "DroppedLeft") &&
              named(table::kStatusCounters, 1, "DroppedRight") &&
              named(table::kStatusCounters, 2, "CanTxDropped") &&
              named(table::kStatusCounters, 3, "Counter"));
static_assert(named(table::kCommand, 0, "CommandCode") && named(table::kCommand, 1, "TargetNode") &&
              named(table::kCommand, 2, "FingerSeparation") &&
              named(table::kCommand, 3, "FusionMethod") &&
              named(table::kCommand, 4, "VelocityMode") &&
              named(table::kCommand, 5, "RateDivider") &&
              named(table::kCommand, 6, "StreamEnable") && named(table::kCommand, 7, "QueryItem") &&
              named(table::kCommand, 8, "RecordingNumber") &&
              named(table::kCommand, 9, "Sequence"));
static_assert(named(table::kAck, 0, "AckCommand") && named(table::kAck, 1, "AckResult") &&
              named(table::kAck, 10, "Sequence"));

constexpr std::size_t kCycleBlockBytes = 7;  // FD: bytes 35..62 stay reserved (0)

std::uint64_t get_bits(const std::uint8_t* data, unsigned start, unsigned len) noexcept {
  std::uint64_t v = 0;
  for (unsigned i = 0; i < len; ++i) {
    const unsigned bit = start + i;
    v |= static_cast<std::uint64_t>((data[bit >> 3] >> (bit & 7u)) & 1u) << i;
  }
  return v;
}

void put_bits(std::uint8_t* data, unsigned start, unsigned len, std::uint64_t v) noexcept {
  for (unsigned i = 0; i < len; ++i) {
    const unsigned bit = start + i;
    const auto mask = static_cast<std::uint8_t>(1u << (bit & 7u));
    if (((v >> i) & 1u) != 0) {
      data[bit >> 3] = static_cast<std::uint8_t>(data[bit >> 3] | mask);
    } else {
      data[bit >> 3] = static_cast<std::uint8_t>(data[bit >> 3] & ~mask);
    }
  }
}

std::int64_t sign_extend(std::uint64_t v, unsigned len) noexcept {
  if (len >= 64) return static_cast<std::int64_t>(v);
  const std::uint64_t sign = std::uint64_t{1} << (len - 1);
  if ((v & sign) != 0) v |= ~((std::uint64_t{1} << len) - 1);
  return static_cast<std::int64_t>(v);
}

bool tx_ok(const TxConfig& tx) noexcept {
  if (!is_valid_node_id(tx.endpoint.node_id)) return false;
  if (tx.endpoint.layout.mode == IdMode::kExtended &&
      !is_valid_extended_base(tx.endpoint.layout.extended_base)) {
    return false;
  }
  return true;
}

double nan() noexcept {
  return std::numeric_limits<double>::quiet_NaN();
}

void set(RawMessage& r, std::size_t i, std::int64_t v) noexcept {
  r.value[i] = v;
  r.present |= std::uint64_t{1} << i;
}

void set_flag(RawMessage& r, std::size_t i, bool b) noexcept {
  set(r, i, b ? 1 : 0);
}

// ---- cycle blocks ------------------------------------------------------------------------------
struct CycleRaw {
  RawMessage ts, ang, lin, ori, pos;
};

void vec3_to_raw(std::span<const SignalDef> sigs, const Vec3& v, std::uint8_t counter,
                 RawMessage& r, Saturation& sat) noexcept {
  bool sx = false, sy = false, sz = false;
  set(r, 0, quantize(sigs[0], v.x, &sx));
  set(r, 1, quantize(sigs[1], v.y, &sy));
  set(r, 2, quantize(sigs[2], v.z, &sz));
  set_flag(r, 3, sx);
  set_flag(r, 4, sy);
  set_flag(r, 5, sz);
  set(r, 6, counter);
  sat = Saturation{sx, sy, sz};
}

void vec3_from_raw(std::span<const SignalDef> sigs, const RawMessage& r, Vec3& v,
                   Saturation& sat) noexcept {
  v.x = dequantize(sigs[0], r.value[0]);
  v.y = dequantize(sigs[1], r.value[1]);
  v.z = dequantize(sigs[2], r.value[2]);
  sat = Saturation{r.value[3] != 0, r.value[4] != 0, r.value[5] != 0};
}

void orientation_to_raw(const Quaternion& q, std::uint8_t counter, RawMessage& r) noexcept {
  const auto& s = table::kPoseOrientation;
  const double n2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  if (!all_finite(q) || !(n2 >= 0.25 && n2 <= 4.0)) {
    for (std::size_t i = 0; i < 4; ++i) set(r, i, invalid_raw(s[i]));
  } else {
    // q and -q are the same rotation; send the one with w >= 0.
    const double k = (q.w < 0.0 ? -1.0 : 1.0) / std::sqrt(n2);
    set(r, 0, quantize(s[0], q.w * k));
    set(r, 1, quantize(s[1], q.x * k));
    set(r, 2, quantize(s[2], q.y * k));
    set(r, 3, quantize(s[3], q.z * k));
  }
  set(r, 4, counter);
}

CycleRaw cycle_to_raw(const Cycle& in, std::uint8_t counter, Cycle& sent) noexcept {
  CycleRaw c;
  vec3_to_raw(table::kTwistAngular, in.angular, counter, c.ang, sent.angular_saturated);
  vec3_to_raw(table::kTwistLinear, in.linear, counter, c.lin, sent.linear_saturated);
  vec3_to_raw(table::kPosePosition, in.position, counter, c.pos, sent.position_saturated);
  orientation_to_raw(in.orientation, counter, c.ori);
  const bool saturated =
      sent.angular_saturated.any() || sent.linear_saturated.any() || sent.position_saturated.any();
  const std::int64_t t = in.timestamp_us <= static_cast<std::uint64_t>(table::kTimestamp[0].raw_max)
                             ? static_cast<std::int64_t>(in.timestamp_us)
                             : invalid_raw(table::kTimestamp[0]);
  set(c.ts, 0, t);
  set_flag(c.ts, 1, in.estimate_valid);
  set_flag(c.ts, 2, in.single_sensor);
  set_flag(c.ts, 3, in.pose_reset);
  set_flag(c.ts, 4, saturated);
  set(c.ts, 5, counter);
  return c;
}

void timestamp_from_raw(const RawMessage& r, TimestampMsg& m) noexcept {
  m.timestamp_us = static_cast<std::uint64_t>(r.value[0]);
  m.estimate_valid = r.value[1] != 0;
  m.single_sensor = r.value[2] != 0;
  m.pose_reset = r.value[3] != 0;
  m.saturated = r.value[4] != 0;
  m.counter = static_cast<std::uint8_t>(r.value[5]);
}

void orientation_from_raw(const RawMessage& r, Quaternion& q) noexcept {
  const auto& s = table::kPoseOrientation;
  q.w = dequantize(s[0], r.value[0]);
  q.x = dequantize(s[1], r.value[1]);
  q.y = dequantize(s[2], r.value[2]);
  q.z = dequantize(s[3], r.value[3]);
}

const MessageDef& def_of(MessageId id) noexcept {
  return message_def(id);
}

// Encode one 8-byte message from its raw values.
Status encode_raw(MessageId id, const RawMessage& raw, const TxConfig& tx, CanFrame& out) noexcept {
  if (!tx_ok(tx)) return Status::kBadArgument;
  const Status s = prepare_frame(id, tx, out);
  if (s != Status::kOk) return s;
  pack_raw(def_of(id), raw, out.data.data());
  finish_frame(out);
  return Status::kOk;
}

}  // namespace

// ---- raw layer -------------------------------------------------------------------------------
void unpack_raw(const MessageDef& def, const std::uint8_t* data, RawMessage& out) noexcept {
  out = RawMessage{};
  const std::size_t mux_i = multiplexor_index(def);
  std::int64_t mux = -1;
  if (mux_i != kNoSignal) {
    const SignalDef& m = def.signals[mux_i];
    mux = static_cast<std::int64_t>(get_bits(data, m.start, m.length));
  }
  for (std::size_t i = 0; i < def.signals.size() && i < kMaxSignals; ++i) {
    const SignalDef& s = def.signals[i];
    if (s.mux >= 0 && s.mux != mux) continue;
    const std::uint64_t v = get_bits(data, s.start, s.length);
    set(out, i, s.is_signed ? sign_extend(v, s.length) : static_cast<std::int64_t>(v));
  }
}

void pack_raw(const MessageDef& def, const RawMessage& raw, std::uint8_t* data) noexcept {
  std::memset(data, 0, def.length);
  for (std::size_t i = 0; i < def.signals.size() && i < kMaxSignals; ++i) {
    if ((raw.present & (std::uint64_t{1} << i)) == 0) continue;
    const SignalDef& s = def.signals[i];
    put_bits(data, s.start, s.length, static_cast<std::uint64_t>(raw.value[i]));
  }
}

Status prepare_frame(MessageId id, const TxConfig& tx, CanFrame& f) noexcept {
  if (!tx_ok(tx)) return Status::kBadArgument;
  const MessageDef& def = def_of(id);
  if (def.fd_only && tx.frame_mode != FrameMode::kFd) return Status::kBadArgument;
  f.id = compose_id(tx.endpoint.layout, tx.endpoint.node_id, id);
  f.extended = tx.endpoint.layout.mode == IdMode::kExtended;
  f.fd = tx.frame_mode == FrameMode::kFd;
  f.brs = f.fd && tx.brs;
  f.len = def.length;
  return Status::kOk;
}

void finish_frame(CanFrame& f) noexcept {
  if (f.len == 0) return;
  f.data[f.len - 1u] = frame_crc(f);
}

std::int64_t quantize(const SignalDef& s, double value, bool* saturated) noexcept {
  if (saturated != nullptr) *saturated = false;
  if (!std::isfinite(value)) return s.invalid != Invalid::kNone ? invalid_raw(s) : s.raw_min;
  const double r = std::round(value / s.factor);  // half away from zero
  if (r < static_cast<double>(s.raw_min)) {
    if (saturated != nullptr) *saturated = true;
    return s.raw_min;
  }
  if (r > static_cast<double>(s.raw_max)) {
    if (saturated != nullptr) *saturated = true;
    return s.raw_max;
  }
  return static_cast<std::int64_t>(r);
}

double dequantize(const SignalDef& s, std::int64_t raw) noexcept {
  if (s.invalid != Invalid::kNone && raw == invalid_raw(s)) return nan();
  return static_cast<double>(raw) * s.factor;
}

// ---- encoder ---------------------------------------------------------------------------------
Status encode_cycle(const Cycle& in, std::uint8_t counter, const TxConfig& tx,
                    CycleFrames& out) noexcept {
  if (!tx_ok(tx)) return Status::kBadArgument;
  counter = static_cast<std::uint8_t>(counter & 0x0Fu);
  out.sent = Cycle{};
  const CycleRaw raw = cycle_to_raw(in, counter, out.sent);
  const RawMessage* blocks[table::kFdBlocks] = {&raw.ts, &raw.ang, &raw.lin, &raw.ori, &raw.pos};
  const MessageId ids[table::kFdBlocks] = {MessageId::kTimestamp, MessageId::kTwistAngular,
                                           MessageId::kTwistLinear, MessageId::kPoseOrientation,
                                           MessageId::kPosePosition};
  if (tx.frame_mode == FrameMode::kClassic) {
    for (std::size_t b = 0; b < table::kFdBlocks; ++b) {
      CanFrame& f = out.frames[b];
      f = CanFrame{};
      (void)prepare_frame(ids[b], tx, f);
      pack_raw(def_of(ids[b]), *blocks[b], f.data.data());
      finish_frame(f);
    }
    out.count = table::kFdBlocks;
  } else {
    CanFrame& f = out.frames[0];
    f = CanFrame{};
    (void)prepare_frame(MessageId::kCycleFd, tx, f);
    for (std::size_t b = 0; b < table::kFdBlocks; ++b) {
      std::uint8_t tmp[8];
      pack_raw(def_of(ids[b]), *blocks[b], tmp);
      std::memcpy(f.data.data() + b * kCycleBlockBytes, tmp, kCycleBlockBytes);
    }
    finish_frame(f);
    out.count = 1;
  }
  // What the receiver will decode.
  TimestampMsg ts;
  timestamp_from_raw(raw.ts, ts);
  out.sent.timestamp_us = ts.timestamp_us;
  out.sent.estimate_valid = ts.estimate_valid;
  out.sent.single_sensor = ts.single_sensor;
  out.sent.pose_reset = ts.pose_reset;
  out.sent.saturated = ts.saturated;
  out.sent.counter = counter;
  Saturation ignored;
  vec3_from_raw(table::kTwistAngular, raw.ang, out.sent.angular, ignored);
  vec3_from_raw(table::kTwistLinear, raw.lin, out.sent.linear, ignored);
  vec3_from_raw(table::kPosePosition, raw.pos, out.sent.position, ignored);
  orientation_from_raw(raw.ori, out.sent.orientation);
  return Status::kOk;
}

Status encode(const StatusMsg& m, const TxConfig& tx, CanFrame& out) noexcept {
  const auto& s = table::kStatus;
  RawMessage r;
  set(r, 0, static_cast<std::int64_t>(m.state) & 0x0F);
  set(r, 1, static_cast<std::int64_t>(m.health_left) & 0x03);
  set(r, 2, static_cast<std::int64_t>(m.health_right) & 0x03);
  set_flag(r, 3, m.contact_left);
  set_flag(r, 4, m.contact_right);
  set_flag(r, 5, m.slip_left);
  set_flag(r, 6, m.slip_right);
  set_flag(r, 7, m.stream_enabled);
  set(r, 8, static_cast<std::int64_t>(m.fusion) & 0x01);
  set(r, 9, static_cast<std::int64_t>(m.velocity_mode) & 0x03);
  set(r, 10, quantize(s[10], m.confidence));
  set(r, 11, m.rate_divider);
  set(r, 12, static_cast<std::int64_t>(m.fault));
  set(r, 13, m.rejected_commands);
  set_flag(r, 14, m.calibrated);
  set(r, 15, m.counter & 0x0F);
  return encode_raw(MessageId::kStatus, r, tx, out);
}

Status encode(const ContactMsg& m, const TxConfig& tx, CanFrame& out) noexcept {
  const auto& s = table::kStatusContact;
  RawMessage r;
  set(r, 0, quantize(s[0], m.area_left_m2));
  set(r, 1, quantize(s[1], m.area_right_m2));
  set(r, 2, quantize(s[2], m.confidence_left));
  set(r, 3, quantize(s[3], m.confidence_right));
  set(r, 4, m.counter & 0x0F);
  return encode_raw(MessageId::kStatusContact, r, tx, out);
}

Status encode(const TimingMsg& m, const TxConfig& tx, CanFrame& out) noexcept {
  const auto& s = table::kStatusTiming;
  RawMessage r;
  set(r, 0, quantize(s[0], m.dsp_time_s));
  set(r, 1, quantize(s[1], m.latency_p50_s));
  set(r, 2, quantize(s[2], m.latency_p99_s));
  set(r, 3, m.counter & 0x0F);
  return encode_raw(MessageId::kStatusTiming, r, tx, out);
}

Status encode(const CountersMsg& m, const TxConfig& tx, CanFrame& out) noexcept {
  RawMessage r;
  set(r, 0, m.dropped_left);
  set(r, 1, m.dropped_right);
  set(r, 2, m.can_tx_dropped);
  set(r, 3, m.counter & 0x0F);
  return encode_raw(MessageId::kStatusCounters, r, tx, out);
}

Status encode_status_group(const StatusGroup& g, std::uint8_t counter, const TxConfig& tx,
                           std::array<CanFrame, 4>& out) noexcept {
  StatusMsg s = g.status;
  ContactMsg c = g.contact;
  TimingMsg t = g.timing;
  CountersMsg n = g.counters;
  s.counter = c.counter = t.counter = n.counter = static_cast<std::uint8_t>(counter & 0x0Fu);
  Status st = encode(s, tx, out[0]);
  if (st == Status::kOk) st = encode(c, tx, out[1]);
  if (st == Status::kOk) st = encode(t, tx, out[2]);
  if (st == Status::kOk) st = encode(n, tx, out[3]);
  return st;
}

Status encode(const Command& c, const TxConfig& tx, CanFrame& out) noexcept {
  const auto& s = table::kCommand;
  RawMessage r;
  set(r, 0, static_cast<std::int64_t>(c.code));
  set(r, 1, tx.endpoint.node_id);
  switch (c.code) {
    case CommandCode::kTare:
    case CommandCode::kResetPose:
      break;
    case CommandCode::kSetFingerSeparation: {
      bool sat = false;
      const std::int64_t v = quantize(s[2], c.finger_separation_m, &sat);
      if (sat || !std::isfinite(c.finger_separation_m)) return Status::kBadArgument;
      set(r, 2, v);
      break;
    }
    case CommandCode::kSetFusion:
      if (static_cast<std::int64_t>(c.fusion) > s[3].raw_max ||
          static_cast<std::int64_t>(c.velocity_mode) > s[4].raw_max) {
        return Status::kBadArgument;
      }
      set(r, 3, static_cast<std::int64_t>(c.fusion));
      set(r, 4, static_cast<std::int64_t>(c.velocity_mode));
      break;
    case CommandCode::kSetRateDivider:
      if (c.rate_divider < s[5].raw_min || c.rate_divider > s[5].raw_max) {
        return Status::kBadArgument;
      }
      set(r, 5, c.rate_divider);
      break;
    case CommandCode::kSetStream:
      set_flag(r, 6, c.stream_enabled);
      break;
    case CommandCode::kQuery:
      if (static_cast<std::int64_t>(c.query) > s[7].raw_max) return Status::kBadArgument;
      set(r, 7, static_cast<std::int64_t>(c.query));
      break;
    case CommandCode::kStartRecording:
      set(r, 8, c.recording_number);
      break;
    case CommandCode::kStopRecording:
      break;
    default:
      return Status::kBadArgument;
  }
  set(r, 9, c.sequence & 0x0F);
  return encode_raw(MessageId::kCommand, r, tx, out);
}

Status encode(const Ack& a, const TxConfig& tx, CanFrame& out) noexcept {
  if (!tx_ok(tx)) return Status::kBadArgument;
  const Status s = prepare_frame(MessageId::kAck, tx, out);
  if (s != Status::kOk) return s;
  std::memset(out.data.data(), 0, out.len);
  // Bytes 2..5 are opaque here (argument echo or query data), so they are copied, not packed.
  out.data[0] = static_cast<std::uint8_t>(a.command);
  out.data[1] = static_cast<std::uint8_t>(a.result);
  std::memcpy(out.data.data() + 2, a.data.data(), a.data.size());
  out.data[6] = static_cast<std::uint8_t>((a.sequence & 0x0Fu) << 4);
  finish_frame(out);
  return Status::kOk;
}

// ---- decoder ---------------------------------------------------------------------------------
Status check_frame(const CanFrame& f, const IdLayout& layout, SplitId& id,
                   const MessageDef*& def) noexcept {
  def = nullptr;
  Status s = split_id(layout, f.id, f.extended, id);
  if (s != Status::kOk) return s;
  const MessageDef* d = find_message(id.message);
  if (d == nullptr) return Status::kUnknownId;
  def = d;
  if (!is_valid_length(f.fd, f.len)) return Status::kBadLength;
  if (f.len != d->length) return Status::kBadLength;
  if (d->fd_only && !f.fd) return Status::kBadLength;
  if (frame_crc(f) != f.data[f.len - 1u]) return Status::kBadCrc;
  return Status::kOk;
}

namespace {

Cycle cycle_from_blocks(const std::uint8_t* data, Status& st) noexcept {
  Cycle c;
  RawMessage r;
  TimestampMsg ts;
  unpack_raw(def_of(MessageId::kTimestamp), data, r);
  timestamp_from_raw(r, ts);
  c.timestamp_us = ts.timestamp_us;
  c.estimate_valid = ts.estimate_valid;
  c.single_sensor = ts.single_sensor;
  c.pose_reset = ts.pose_reset;
  c.saturated = ts.saturated;
  c.counter = ts.counter;
  bool counters_agree = true;
  unpack_raw(def_of(MessageId::kTwistAngular), data + kCycleBlockBytes, r);
  vec3_from_raw(table::kTwistAngular, r, c.angular, c.angular_saturated);
  counters_agree = counters_agree && r.value[6] == c.counter;
  unpack_raw(def_of(MessageId::kTwistLinear), data + 2 * kCycleBlockBytes, r);
  vec3_from_raw(table::kTwistLinear, r, c.linear, c.linear_saturated);
  counters_agree = counters_agree && r.value[6] == c.counter;
  unpack_raw(def_of(MessageId::kPoseOrientation), data + 3 * kCycleBlockBytes, r);
  orientation_from_raw(r, c.orientation);
  counters_agree = counters_agree && r.value[4] == c.counter;
  unpack_raw(def_of(MessageId::kPosePosition), data + 4 * kCycleBlockBytes, r);
  vec3_from_raw(table::kPosePosition, r, c.position, c.position_saturated);
  counters_agree = counters_agree && r.value[6] == c.counter;
  st = counters_agree ? Status::kOk : Status::kBadCounter;
  return c;
}

}  // namespace

Status decode(const CanFrame& f, const IdLayout& layout, Decoded& out) noexcept {
  SplitId id;
  const MessageDef* def = nullptr;
  const Status s = check_frame(f, layout, id, def);
  if (s != Status::kOk) return s;
  out.message = def->id;
  out.node_id = id.node;
  RawMessage r;
  const std::uint8_t* d = f.data.data();
  switch (def->id) {
    case MessageId::kTimestamp: {
      unpack_raw(*def, d, r);
      TimestampMsg m;
      timestamp_from_raw(r, m);
      out.payload = m;
      return Status::kOk;
    }
    case MessageId::kTwistAngular: {
      unpack_raw(*def, d, r);
      AngularMsg m;
      vec3_from_raw(table::kTwistAngular, r, m.angular, m.saturated);
      m.counter = static_cast<std::uint8_t>(r.value[6]);
      out.payload = m;
      return Status::kOk;
    }
    case MessageId::kTwistLinear: {
      unpack_raw(*def, d, r);
      LinearMsg m;
      vec3_from_raw(table::kTwistLinear, r, m.linear, m.saturated);
      m.counter = static_cast<std::uint8_t>(r.value[6]);
      out.payload = m;
      return Status::kOk;
    }
    case MessageId::kPoseOrientation: {
      unpack_raw(*def, d, r);
      OrientationMsg m;
      orientation_from_raw(r, m.orientation);
      m.counter = static_cast<std::uint8_t>(r.value[4]);
      out.payload = m;
      return Status::kOk;
    }
    case MessageId::kPosePosition: {
      unpack_raw(*def, d, r);
      PositionMsg m;
      vec3_from_raw(table::kPosePosition, r, m.position, m.saturated);
      m.counter = static_cast<std::uint8_t>(r.value[6]);
      out.payload = m;
      return Status::kOk;
    }
    case MessageId::kCycleFd: {
      Status st = Status::kOk;
      const Cycle c = cycle_from_blocks(d, st);
      if (st != Status::kOk) return st;
      out.payload = c;
      return Status::kOk;
    }
    case MessageId::kStatus: {
      unpack_raw(*def, d, r);
      StatusMsg m;
      m.state = static_cast<State>(r.value[0]);
      m.health_left = static_cast<SensorHealth>(r.value[1]);
      m.health_right = static_cast<SensorHealth>(r.value[2]);
      m.contact_left = r.value[3] != 0;
      m.contact_right = r.value[4] != 0;
      m.slip_left = r.value[5] != 0;
      m.slip_right = r.value[6] != 0;
      m.stream_enabled = r.value[7] != 0;
      m.fusion = static_cast<FusionMethod>(r.value[8]);
      m.velocity_mode = static_cast<VelocityMode>(r.value[9]);
      m.confidence = dequantize(table::kStatus[10], r.value[10]);
      m.rate_divider = static_cast<std::uint8_t>(r.value[11]);
      m.fault = static_cast<FaultCode>(r.value[12]);
      m.rejected_commands = static_cast<std::uint8_t>(r.value[13]);
      m.calibrated = r.value[14] != 0;
      m.counter = static_cast<std::uint8_t>(r.value[15]);
      out.payload = m;
      return Status::kOk;
    }
    case MessageId::kStatusContact: {
      unpack_raw(*def, d, r);
      const auto& s2 = table::kStatusContact;
      ContactMsg m;
      m.area_left_m2 = dequantize(s2[0], r.value[0]);
      m.area_right_m2 = dequantize(s2[1], r.value[1]);
      m.confidence_left = dequantize(s2[2], r.value[2]);
      m.confidence_right = dequantize(s2[3], r.value[3]);
      m.counter = static_cast<std::uint8_t>(r.value[4]);
      out.payload = m;
      return Status::kOk;
    }
    case MessageId::kStatusTiming: {
      unpack_raw(*def, d, r);
      const auto& s2 = table::kStatusTiming;
      TimingMsg m;
      m.dsp_time_s = dequantize(s2[0], r.value[0]);
      m.latency_p50_s = dequantize(s2[1], r.value[1]);
      m.latency_p99_s = dequantize(s2[2], r.value[2]);
      m.counter = static_cast<std::uint8_t>(r.value[3]);
      out.payload = m;
      return Status::kOk;
    }
    case MessageId::kStatusCounters: {
      unpack_raw(*def, d, r);
      CountersMsg m;
      m.dropped_left = static_cast<std::uint16_t>(r.value[0]);
      m.dropped_right = static_cast<std::uint16_t>(r.value[1]);
      m.can_tx_dropped = static_cast<std::uint16_t>(r.value[2]);
      m.counter = static_cast<std::uint8_t>(r.value[3]);
      out.payload = m;
      return Status::kOk;
    }
    case MessageId::kCommand: {
      unpack_raw(*def, d, r);
      const auto& s2 = table::kCommand;
      Command m;
      m.code = static_cast<CommandCode>(r.value[0]);
      m.target_node = static_cast<std::uint8_t>(r.value[1]);
      if ((r.present & (1u << 2)) != 0) m.finger_separation_m = dequantize(s2[2], r.value[2]);
      if ((r.present & (1u << 3)) != 0) m.fusion = static_cast<FusionMethod>(r.value[3]);
      if ((r.present & (1u << 4)) != 0) m.velocity_mode = static_cast<VelocityMode>(r.value[4]);
      if ((r.present & (1u << 5)) != 0) m.rate_divider = static_cast<std::uint8_t>(r.value[5]);
      if ((r.present & (1u << 6)) != 0) m.stream_enabled = r.value[6] != 0;
      if ((r.present & (1u << 7)) != 0) m.query = static_cast<QueryItem>(r.value[7]);
      if ((r.present & (1u << 8)) != 0) {
        m.recording_number = static_cast<std::uint16_t>(r.value[8]);
      }
      m.sequence = static_cast<std::uint8_t>(r.value[9]);
      std::memcpy(m.args.data(), d + 2, m.args.size());
      out.payload = m;
      return Status::kOk;
    }
    case MessageId::kAck: {
      Ack m;
      m.command = static_cast<CommandCode>(d[0]);
      m.result = static_cast<AckCode>(d[1]);
      std::memcpy(m.data.data(), d + 2, m.data.size());
      m.sequence = static_cast<std::uint8_t>(d[6] >> 4);
      out.payload = m;
      return Status::kOk;
    }
  }
  return Status::kUnknownId;
}

// ---- query replies ---------------------------------------------------------------------------
Ack make_query_reply(const Command& query, const QueryReply& reply) noexcept {
  Ack a;
  a.command = CommandCode::kQuery;
  a.result = AckCode::kAck;
  a.sequence = static_cast<std::uint8_t>(query.sequence & 0x0Fu);
  a.data[0] = static_cast<std::uint8_t>(reply.item);
  switch (reply.item) {
    case QueryItem::kProtocolVersion:
    case QueryItem::kFirmwareVersion:
      a.data[1] = reply.version.major;
      a.data[2] = reply.version.minor;
      a.data[3] = reply.version.patch;
      break;
    case QueryItem::kFingerSeparation: {
      const auto raw = static_cast<std::uint16_t>(
          quantize(table::kFingerSeparationArg, reply.finger_separation_m));
      a.data[1] = static_cast<std::uint8_t>(raw & 0xFFu);
      a.data[2] = static_cast<std::uint8_t>(raw >> 8);
      break;
    }
    case QueryItem::kFusion:
      a.data[1] = static_cast<std::uint8_t>(reply.fusion);
      a.data[2] = static_cast<std::uint8_t>(reply.velocity_mode);
      break;
    case QueryItem::kStream:
      a.data[1] = reply.stream_enabled ? 1 : 0;
      a.data[2] = reply.rate_divider;
      a.data[3] =
          static_cast<std::uint8_t>((reply.fd_mode ? 1u : 0u) | (reply.extended_ids ? 2u : 0u));
      break;
  }
  return a;
}

Status decode_query_reply(const Ack& a, QueryReply& out) noexcept {
  if (a.command != CommandCode::kQuery || a.result != AckCode::kAck) {
    return Status::kWrongMessage;
  }
  out = QueryReply{};
  out.item = static_cast<QueryItem>(a.data[0]);
  switch (out.item) {
    case QueryItem::kProtocolVersion:
    case QueryItem::kFirmwareVersion:
      out.version = Version{a.data[1], a.data[2], a.data[3]};
      return Status::kOk;
    case QueryItem::kFingerSeparation:
      out.finger_separation_m = dequantize(
          table::kFingerSeparationArg,
          static_cast<std::int64_t>(a.data[1] | (static_cast<unsigned>(a.data[2]) << 8)));
      return Status::kOk;
    case QueryItem::kFusion:
      out.fusion = static_cast<FusionMethod>(a.data[1]);
      out.velocity_mode = static_cast<VelocityMode>(a.data[2]);
      return Status::kOk;
    case QueryItem::kStream:
      out.stream_enabled = a.data[1] != 0;
      out.rate_divider = a.data[2];
      out.fd_mode = (a.data[3] & 1u) != 0;
      out.extended_ids = (a.data[3] & 2u) != 0;
      return Status::kOk;
  }
  return Status::kBadArgument;
}

}  // namespace tacse3::protocol
