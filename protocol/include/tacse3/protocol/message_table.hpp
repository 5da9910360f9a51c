// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: the constexpr message table, the single source of ids, fields and scaling.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "tacse3/protocol/ids.hpp"

namespace tacse3::protocol {

// Everything on the bus is described here: the codec packs and unpacks through these
// definitions, tacse3-dbcgen writes protocol/tacse3.dbc from them, and the bus-load test sums
// them. Bit numbering is Intel / little-endian: bit b is bit (b % 8) of payload byte b / 8, and a
// field of n bits starting at b occupies bits b .. b+n-1 (DBC "@1").

enum class Invalid : std::uint8_t {
  kNone,          // every raw value is a value
  kMostNegative,  // signed field: the most negative integer means invalid / not available
  kAllOnes,       // unsigned field: the all-ones value means invalid / not available
};

enum class Role : std::uint8_t {
  kValue,        // scaled physical value
  kFlag,         // 1-bit boolean
  kEnum,         // enumeration (value table)
  kCount,        // plain integer (counter of events, id, divider)
  kCounter,      // 4-bit rolling counter / sequence number
  kCrc,          // CRC-8 (last payload byte)
  kMultiplexor,  // selects the multiplexed signals (command code)
};

struct ValueName {
  std::int64_t raw;
  std::string_view name;
};

struct SignalDef {
  std::string_view name;
  std::uint16_t start = 0;  // first (least significant) bit
  std::uint8_t length = 1;  // bits
  bool is_signed = false;
  double factor = 1.0;       // physical = raw * factor (offset is always 0)
  std::int64_t raw_min = 0;  // valid raw range; the encoder saturates into it
  std::int64_t raw_max = 0;
  std::string_view unit{};
  Invalid invalid = Invalid::kNone;
  Role role = Role::kValue;
  std::int16_t mux = -1;  // >= 0: present only when the message's multiplexor equals mux
  std::span<const ValueName> values{};
  std::string_view comment{};
};

constexpr std::int64_t invalid_raw(const SignalDef& s) noexcept {
  switch (s.invalid) {
    case Invalid::kMostNegative:
      return -(std::int64_t{1} << (s.length - 1));
    case Invalid::kAllOnes:
      return (std::int64_t{1} << s.length) - 1;
    case Invalid::kNone:
      break;
  }
  return 0;
}

constexpr double physical_min(const SignalDef& s) noexcept {
  return static_cast<double>(s.raw_min) * s.factor;
}
constexpr double physical_max(const SignalDef& s) noexcept {
  return static_cast<double>(s.raw_max) * s.factor;
}

// When the gripper sends a message (for the bus-load sum and the docs).
enum class Stream : std::uint8_t {
  kClassicCycle,  // every cycle, classic mode only
  kFdCycle,       // every cycle, CAN FD mode only
  kAlways,        // both modes
};

enum class Sender : std::uint8_t { kGripper, kController };

struct MessageDef {
  MessageId id;
  std::string_view name;
  std::uint8_t length;  // payload bytes
  bool fd_only;         // exists only as a CAN FD frame
  Sender sender;
  Stream stream;
  double nominal_rate_hz;  // steady-state rate per node (at rate divider 1)
  double max_rate_hz;      // worst-case rate per node used for the bus-load bound
  std::span<const SignalDef> signals;
  std::string_view comment;
};

inline constexpr double kCycleRateHz = 120.0;
inline constexpr double kStatusRateHz = 10.0;
// Commands are the controller's traffic; the bus-load bound budgets this many per second and node
// (and as many ACKs).
inline constexpr double kCommandBudgetHz = 10.0;
inline constexpr std::size_t kMaxSignals = 40;
inline constexpr std::uint64_t kTimestampInvalid = 0xFFFFFFFFFFFFull;

namespace table {

inline constexpr ValueName kInvalidS16[] = {{-32768, "INVALID"}};
inline constexpr ValueName kInvalidS13[] = {{-4096, "INVALID"}};
inline constexpr ValueName kInvalidU8[] = {{255, "INVALID"}};
inline constexpr ValueName kInvalidU16[] = {{65535, "INVALID"}};
inline constexpr ValueName kInvalidU48[] = {{0xFFFFFFFFFFFFll, "INVALID"}};
inline constexpr ValueName kStateNames[] = {{0, "BOOTING"},
                                            {1, "NO_CONTACT"},
                                            {2, "TRACKING"},
                                            {3, "DEGRADED_SINGLE_SENSOR"},
                                            {4, "FAULT"}};
inline constexpr ValueName kHealthNames[] = {
    {0, "OK"}, {1, "STALE"}, {2, "LOST"}, {3, "NOT_AVAILABLE"}};
inline constexpr ValueName kFusionNames[] = {{0, "JOINT"}, {1, "PAPER"}};
inline constexpr ValueName kVelocityModeNames[] = {
    {0, "AUTO"}, {1, "VELOCITY"}, {2, "DISPLACEMENT"}};
inline constexpr ValueName kFaultNames[] = {{0, "NONE"},
                                            {1, "LEFT_SENSOR_LOST"},
                                            {2, "RIGHT_SENSOR_LOST"},
                                            {3, "BOTH_SENSORS_LOST"},
                                            {4, "CALIBRATION_INVALID"},
                                            {5, "DSP_OVERRUN"},
                                            {6, "CAN_ERROR_PASSIVE"},
                                            {7, "CAN_BUS_OFF_RECOVERED"}};
inline constexpr ValueName kCommandNames[] = {
    {1, "TARE"},       {2, "RESET_POSE"},       {3, "SET_FINGER_SEPARATION"},
    {4, "SET_FUSION"}, {5, "SET_RATE_DIVIDER"}, {6, "SET_STREAM"},
    {7, "QUERY"},      {8, "START_RECORDING"},  {9, "STOP_RECORDING"}};
inline constexpr ValueName kAckNames[] = {{0, "ACK"},
                                          {1, "UNKNOWN_COMMAND"},
                                          {2, "BAD_LENGTH"},
                                          {3, "BAD_CRC"},
                                          {4, "WRONG_NODE"},
                                          {5, "OUT_OF_RANGE"},
                                          {6, "RESERVED_NOT_ZERO"},
                                          {7, "BUSY"},
                                          {8, "INTERNAL_ERROR"},
                                          {9, "ALREADY_RECORDING"},
                                          {10, "NOT_RECORDING"},
                                          {11, "NO_RECORD_DIR"},
                                          {12, "RECORDING_EXISTS"},
                                          {13, "DISK_ERROR"}};
inline constexpr ValueName kQueryNames[] = {{0, "PROTOCOL_VERSION"},
                                            {1, "FIRMWARE_VERSION"},
                                            {2, "FINGER_SEPARATION"},
                                            {3, "FUSION"},
                                            {4, "STREAM"}};

constexpr SignalDef flag(std::string_view name, std::uint16_t start, std::string_view comment) {
  return {.name = name,
          .start = start,
          .length = 1,
          .raw_min = 0,
          .raw_max = 1,
          .role = Role::kFlag,
          .comment = comment};
}
constexpr SignalDef counter(std::string_view name, std::string_view comment) {
  return {.name = name,
          .start = 52,
          .length = 4,
          .raw_min = 0,
          .raw_max = 15,
          .role = Role::kCounter,
          .comment = comment};
}
constexpr SignalDef crc(std::uint16_t start) {
  return {.name = "Crc",
          .start = start,
          .length = 8,
          .raw_min = 0,
          .raw_max = 255,
          .role = Role::kCrc,
          .comment = "CRC-8/SAE-J1850 over the 4-byte identifier word and all preceding bytes"};
}
constexpr SignalDef s16(std::string_view name, std::uint16_t start, double factor,
                        std::string_view unit, std::string_view comment) {
  return {.name = name,
          .start = start,
          .length = 16,
          .is_signed = true,
          .factor = factor,
          .raw_min = -32767,
          .raw_max = 32767,
          .unit = unit,
          .invalid = Invalid::kMostNegative,
          .values = kInvalidS16,
          .comment = comment};
}
constexpr SignalDef quat(std::string_view name, std::uint16_t start, std::string_view comment) {
  return {.name = name,
          .start = start,
          .length = 13,
          .is_signed = true,
          .factor = 0.00025,
          .raw_min = -4000,
          .raw_max = 4000,
          .invalid = Invalid::kMostNegative,
          .values = kInvalidS13,
          .comment = comment};
}
constexpr SignalDef u16(std::string_view name, std::uint16_t start, double factor,
                        std::string_view unit, std::string_view comment) {
  return {.name = name,
          .start = start,
          .length = 16,
          .factor = factor,
          .raw_min = 0,
          .raw_max = 65534,
          .unit = unit,
          .invalid = Invalid::kAllOnes,
          .values = kInvalidU16,
          .comment = comment};
}
constexpr SignalDef count(std::string_view name, std::uint16_t start, std::uint8_t length,
                          std::int64_t raw_min, std::int64_t raw_max, std::string_view unit,
                          std::string_view comment, std::int16_t mux = -1) {
  return {.name = name,
          .start = start,
          .length = length,
          .raw_min = raw_min,
          .raw_max = raw_max,
          .unit = unit,
          .role = Role::kCount,
          .mux = mux,
          .comment = comment};
}
constexpr SignalDef enumeration(std::string_view name, std::uint16_t start, std::uint8_t length,
                                std::span<const ValueName> values, std::string_view comment,
                                std::int16_t mux = -1) {
  return {.name = name,
          .start = start,
          .length = length,
          .raw_min = values.front().raw,
          .raw_max = values.back().raw,
          .role = Role::kEnum,
          .mux = mux,
          .values = values,
          .comment = comment};
}
constexpr SignalDef confidence(std::string_view name, std::uint16_t start,
                               std::string_view comment) {
  return {.name = name,
          .start = start,
          .length = 8,
          .factor = 0.004,
          .raw_min = 0,
          .raw_max = 250,
          .invalid = Invalid::kAllOnes,
          .values = kInvalidU8,
          .comment = comment};
}

// ---- cyclic frames (one set per pipeline cycle) -------------------------------------------
inline constexpr SignalDef kTimestamp[] = {
    {.name = "SampleTime",
     .start = 0,
     .length = 48,
     .raw_min = 0,
     .raw_max = 0xFFFFFFFFFFFEll,
     .unit = "us",
     .invalid = Invalid::kAllOnes,
     .values = kInvalidU48,
     .comment = "Sensor sample time of this cycle on the board's monotonic clock"},
    flag("EstimateValid", 48, "1 = twist and pose of this cycle are a valid estimate"),
    flag("SingleSensor", 49, "1 = estimate from one sensor only (degraded)"),
    flag("PoseReset", 50, "1 = pose was reset or tared this cycle (pose discontinuity)"),
    flag("Saturated", 51, "1 = at least one field of this cycle was clamped to its range"),
    counter("Counter", "Cycle counter, shared by all frames of one cycle"),
    crc(56),
};

inline constexpr SignalDef kTwistAngular[] = {
    s16("AngVelX", 0, 0.001, "rad/s", "Angular velocity of the object about x of G"),
    s16("AngVelY", 16, 0.001, "rad/s", "Angular velocity of the object about y of G"),
    s16("AngVelZ", 32, 0.001, "rad/s", "Angular velocity of the object about z of G"),
    flag("AngVelXSat", 48, "1 = AngVelX was clamped to its range"),
    flag("AngVelYSat", 49, "1 = AngVelY was clamped to its range"),
    flag("AngVelZSat", 50, "1 = AngVelZ was clamped to its range"),
    counter("Counter", "Cycle counter, shared by all frames of one cycle"),
    crc(56),
};

inline constexpr SignalDef kTwistLinear[] = {
    s16("LinVelX", 0, 0.0001, "m/s", "Linear velocity of the object along x of G"),
    s16("LinVelY", 16, 0.0001, "m/s", "Linear velocity of the object along y of G"),
    s16("LinVelZ", 32, 0.0001, "m/s", "Linear velocity of the object along z of G"),
    flag("LinVelXSat", 48, "1 = LinVelX was clamped to its range"),
    flag("LinVelYSat", 49, "1 = LinVelY was clamped to its range"),
    flag("LinVelZSat", 50, "1 = LinVelZ was clamped to its range"),
    counter("Counter", "Cycle counter, shared by all frames of one cycle"),
    crc(56),
};

inline constexpr SignalDef kPoseOrientation[] = {
    quat("QuatW", 0, "Orientation quaternion w (unit quaternion, w >= 0)"),
    quat("QuatX", 13, "Orientation quaternion x"),
    quat("QuatY", 26, "Orientation quaternion y"),
    quat("QuatZ", 39, "Orientation quaternion z"),
    counter("Counter", "Cycle counter, shared by all frames of one cycle"),
    crc(56),
};

inline constexpr SignalDef kPosePosition[] = {
    s16("PosX", 0, 0.00002, "m", "Position of the object along x of G"),
    s16("PosY", 16, 0.00002, "m", "Position of the object along y of G"),
    s16("PosZ", 32, 0.00002, "m", "Position of the object along z of G"),
    flag("PosXSat", 48, "1 = PosX was clamped to its range"),
    flag("PosYSat", 49, "1 = PosY was clamped to its range"),
    flag("PosZSat", 50, "1 = PosZ was clamped to its range"),
    counter("Counter", "Cycle counter, shared by all frames of one cycle"),
    crc(56),
};

// CAN FD: the five classic payloads without their CRC byte (7 bytes each) back to back at byte
// offsets 0, 7, 14, 21, 28; bytes 35..62 reserved (0); CRC-8 in byte 63.
inline constexpr std::uint16_t kFdBlockBits = 56;
inline constexpr std::size_t kFdBlocks = 5;
inline constexpr std::string_view kFdCounterNames[kFdBlocks] = {
    "Counter", "CounterAngular", "CounterLinear", "CounterOrientation", "CounterPosition"};

constexpr std::size_t fd_signal_count() {
  return std::size(kTimestamp) - 1 + std::size(kTwistAngular) - 1 + std::size(kTwistLinear) - 1 +
         std::size(kPoseOrientation) - 1 + std::size(kPosePosition) - 1 + 1;
}

constexpr std::array<SignalDef, fd_signal_count()> make_fd_signals() {
  std::array<SignalDef, fd_signal_count()> out{};
  const std::span<const SignalDef> blocks[kFdBlocks] = {kTimestamp, kTwistAngular, kTwistLinear,
                                                        kPoseOrientation, kPosePosition};
  std::size_t n = 0;
  for (std::size_t b = 0; b < kFdBlocks; ++b) {
    for (const SignalDef& s : blocks[b]) {
      if (s.role == Role::kCrc) continue;
      SignalDef c = s;
      c.start = static_cast<std::uint16_t>(s.start + b * kFdBlockBits);
      if (s.role == Role::kCounter) {
        c.name = kFdCounterNames[b];
        c.comment = "Cycle counter; all five counters of the frame are equal";
      }
      out[n++] = c;
    }
  }
  out[n] = crc(63 * 8);
  return out;
}
inline constexpr auto kCycleFd = make_fd_signals();

// ---- status (10 Hz, and Status immediately on a change) -----------------------------------
inline constexpr SignalDef kStatus[] = {
    enumeration("State", 0, 4, kStateNames, "State machine state"),
    enumeration("HealthLeft", 4, 2, kHealthNames, "Left sensor health"),
    enumeration("HealthRight", 6, 2, kHealthNames, "Right sensor health"),
    flag("ContactLeft", 8, "1 = left sensor in contact"),
    flag("ContactRight", 9, "1 = right sensor in contact"),
    flag("SlipLeft", 10, "1 = slip detected on the left sensor"),
    flag("SlipRight", 11, "1 = slip detected on the right sensor"),
    flag("StreamEnabled", 12, "1 = cyclic stream enabled"),
    enumeration("FusionMethod", 13, 1, kFusionNames, "Dual-sensor fusion method"),
    enumeration("VelocityMode", 14, 2, kVelocityModeNames, "Velocity-proxy mode"),
    confidence("Confidence", 16, "Confidence of the estimate, 0..1"),
    count("RateDivider", 24, 8, 1, 120, "", "Stream rate = 120 Hz / RateDivider"),
    enumeration("FaultCode", 32, 8, kFaultNames, "Most recent fault or warning, 0 = none"),
    count("RejectedCommands", 40, 8, 0, 255, "", "Rejected command frames since boot, mod 256"),
    flag("Calibrated", 48,
         "1 = a fitted calibration runs; 0 = UNCALIBRATED, estimates not to scale"),
    counter("Counter", "Status counter, shared by the status frames of one emission"),
    crc(56),
};

inline constexpr SignalDef kStatusContact[] = {
    u16("AreaLeft", 0, 0.0000001, "m^2", "Contact area on the left sensor"),
    u16("AreaRight", 16, 0.0000001, "m^2", "Contact area on the right sensor"),
    confidence("ConfidenceLeft", 32, "Confidence of the left sensor's estimate, 0..1"),
    confidence("ConfidenceRight", 40, "Confidence of the right sensor's estimate, 0..1"),
    counter("Counter", "Status counter, shared by the status frames of one emission"),
    crc(56),
};

inline constexpr SignalDef kStatusTiming[] = {
    u16("DspTime", 0, 0.000001, "s", "DSP time of the last frame pair"),
    u16("LatencyP50", 16, 0.000001, "s", "Median sample-to-CAN latency since the last report"),
    u16("LatencyP99", 32, 0.000001, "s", "99th percentile sample-to-CAN latency"),
    counter("Counter", "Status counter, shared by the status frames of one emission"),
    crc(56),
};

inline constexpr SignalDef kStatusCounters[] = {
    count("DroppedLeft", 0, 16, 0, 65535, "frames", "Left sensor frames dropped, mod 65536"),
    count("DroppedRight", 16, 16, 0, 65535, "frames", "Right sensor frames dropped, mod 65536"),
    count("CanTxDropped", 32, 16, 0, 65535, "frames", "CAN frames dropped on TX, mod 65536"),
    counter("Counter", "Status counter, shared by the status frames of one emission"),
    crc(56),
};

// ---- commands and acknowledgements ----------------------------------------------------------
inline constexpr SignalDef kFingerSeparationArg = {
    .name = "FingerSeparation",
    .start = 16,
    .length = 16,
    .factor = 0.00001,
    .raw_min = 100,
    .raw_max = 25000,
    .unit = "m",
    .mux = 3,
    .comment = "Distance between the two sensor pads"};

inline constexpr SignalDef kRecordingNumberArg =
    count("RecordingNumber", 16, 16, 0, 65535, "",
          "Recording number N, chosen by the controller: the recording goes to rec-NNNNN", 8);

inline constexpr SignalDef kCommand[] = {
    {.name = "CommandCode",
     .start = 0,
     .length = 8,
     .raw_min = 1,
     .raw_max = 9,
     .role = Role::kMultiplexor,
     .values = kCommandNames,
     .comment = "Command code"},
    count("TargetNode", 8, 8, 1, 63, "", "Node id of the addressed gripper (must match the id)"),
    kFingerSeparationArg,
    enumeration("FusionMethod", 16, 8, kFusionNames, "Dual-sensor fusion method", 4),
    enumeration("VelocityMode", 24, 8, kVelocityModeNames, "Velocity-proxy mode", 4),
    count("RateDivider", 16, 8, 1, 120, "", "Stream rate = 120 Hz / RateDivider", 5),
    count("StreamEnable", 16, 8, 0, 1, "", "1 = enable, 0 = disable the cyclic stream", 6),
    enumeration("QueryItem", 16, 8, kQueryNames, "What to report in the Ack", 7),
    kRecordingNumberArg,
    counter("Sequence", "Chosen by the controller, echoed in the Ack"),
    crc(56),
};

inline constexpr SignalDef kAck[] = {
    {.name = "AckCommand",
     .start = 0,
     .length = 8,
     .raw_min = 0,
     .raw_max = 255,
     .role = Role::kMultiplexor,
     .values = kCommandNames,
     .comment = "Command code being answered"},
    enumeration("AckResult", 8, 8, kAckNames, "0 = ACK, otherwise the NACK reason"),
    kFingerSeparationArg,
    enumeration("FusionMethod", 16, 8, kFusionNames, "Dual-sensor fusion method", 4),
    enumeration("VelocityMode", 24, 8, kVelocityModeNames, "Velocity-proxy mode", 4),
    count("RateDivider", 16, 8, 1, 120, "", "Stream rate = 120 Hz / RateDivider", 5),
    count("StreamEnable", 16, 8, 0, 1, "", "1 = enable, 0 = disable the cyclic stream", 6),
    enumeration("QueryItem", 16, 8, kQueryNames, "Item reported in QueryData", 7),
    count("QueryData", 24, 24, 0, 0xFFFFFF, "", "Item data, layout per QueryItem (see docs)", 7),
    kRecordingNumberArg,
    counter("Sequence", "Sequence of the command being answered"),
    crc(56),
};

}  // namespace table

inline constexpr std::array<MessageDef, 12> kMessages = {{
    {MessageId::kTimestamp, "Timestamp", 8, false, Sender::kGripper, Stream::kClassicCycle,
     kCycleRateHz, kCycleRateHz, table::kTimestamp, "Cycle header: sample time and cycle flags"},
    {MessageId::kTwistAngular, "TwistAngular", 8, false, Sender::kGripper, Stream::kClassicCycle,
     kCycleRateHz, kCycleRateHz, table::kTwistAngular, "Angular twist of the object in G"},
    {MessageId::kTwistLinear, "TwistLinear", 8, false, Sender::kGripper, Stream::kClassicCycle,
     kCycleRateHz, kCycleRateHz, table::kTwistLinear, "Linear twist of the object in G"},
    {MessageId::kPoseOrientation, "PoseOrientation", 8, false, Sender::kGripper,
     Stream::kClassicCycle, kCycleRateHz, kCycleRateHz, table::kPoseOrientation,
     "Orientation of the object in G since the last pose reset"},
    {MessageId::kPosePosition, "PosePosition", 8, false, Sender::kGripper, Stream::kClassicCycle,
     kCycleRateHz, kCycleRateHz, table::kPosePosition,
     "Position of the object in G since the last pose reset"},
    {MessageId::kCycleFd, "CycleFd", 64, true, Sender::kGripper, Stream::kFdCycle, kCycleRateHz,
     kCycleRateHz, table::kCycleFd, "CAN FD mode: a whole cycle in one frame"},
    // Status: 10 Hz, plus one immediately on a change, at most one per cycle (per frame period
    // once the stream has stopped) in total.
    {MessageId::kStatus, "Status", 8, false, Sender::kGripper, Stream::kAlways, kStatusRateHz,
     kCycleRateHz, table::kStatus, "Heartbeat: state, sensor health, flags, configuration"},
    {MessageId::kStatusContact, "StatusContact", 8, false, Sender::kGripper, Stream::kAlways,
     kStatusRateHz, kStatusRateHz, table::kStatusContact,
     "Contact areas and per-sensor confidence"},
    {MessageId::kStatusTiming, "StatusTiming", 8, false, Sender::kGripper, Stream::kAlways,
     kStatusRateHz, kStatusRateHz, table::kStatusTiming, "DSP time and latency"},
    {MessageId::kStatusCounters, "StatusCounters", 8, false, Sender::kGripper, Stream::kAlways,
     kStatusRateHz, kStatusRateHz, table::kStatusCounters, "Dropped-frame counters"},
    {MessageId::kCommand, "Command", 8, false, Sender::kController, Stream::kAlways, 0.0,
     kCommandBudgetHz, table::kCommand, "Command from the controller"},
    {MessageId::kAck, "Ack", 8, false, Sender::kGripper, Stream::kAlways, 0.0, kCommandBudgetHz,
     table::kAck, "ACK/NACK of a command"},
}};

constexpr const MessageDef* find_message(std::uint8_t message_id) noexcept {
  for (const MessageDef& m : kMessages) {
    if (static_cast<std::uint8_t>(m.id) == message_id) return &m;
  }
  return nullptr;
}

constexpr const MessageDef& message_def(MessageId id) noexcept {
  for (const MessageDef& m : kMessages) {
    if (m.id == id) return m;
  }
  return kMessages[0];  // unreachable for a MessageId value
}

inline constexpr std::size_t kNoSignal = static_cast<std::size_t>(-1);

constexpr std::size_t signal_index(std::span<const SignalDef> sigs,
                                   std::string_view name) noexcept {
  for (std::size_t i = 0; i < sigs.size(); ++i) {
    if (sigs[i].name == name) return i;
  }
  return kNoSignal;
}

constexpr std::size_t multiplexor_index(const MessageDef& m) noexcept {
  for (std::size_t i = 0; i < m.signals.size(); ++i) {
    if (m.signals[i].role == Role::kMultiplexor) return i;
  }
  return kNoSignal;
}

}  // namespace tacse3::protocol
