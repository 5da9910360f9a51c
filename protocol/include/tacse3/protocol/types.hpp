// SPDX-License-Identifier: Apache-2.0
// tacse3 protocol: physical value types and the enumerations carried on the bus.
#pragma once

#include <cmath>
#include <cstdint>

namespace tacse3::protocol {

// Every physical value is SI, in the gripper frame G. A NaN component means "invalid / not
// available": the encoder sends the field's invalid marker, the decoder returns NaN for it.
struct Vec3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
};

// Unit quaternion w + xi + yj + zk (Hamilton convention), rotation of the object in G.
struct Quaternion {
  double w = 1.0;
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
};

inline bool all_finite(const Vec3& v) noexcept {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
inline bool all_finite(const Quaternion& q) noexcept {
  return std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
}

// Per-axis saturation flags: the value was outside the field's range and was clamped to the
// nearest representable value (never to the invalid marker).
struct Saturation {
  bool x = false;
  bool y = false;
  bool z = false;
  constexpr bool any() const noexcept { return x || y || z; }
};

enum class State : std::uint8_t {
  kBooting = 0,
  kNoContact = 1,
  kTracking = 2,
  kDegradedSingleSensor = 3,
  kFault = 4,
};

enum class SensorHealth : std::uint8_t {
  kOk = 0,
  kStale = 1,
  kLost = 2,
  kNotAvailable = 3,
};

enum class FusionMethod : std::uint8_t {
  kJoint = 0,  // both sensors' points in the gripper frame, one solve (default)
  kPaper = 1,  // xi = (xi_1 + S xi_2) / 2
};

enum class VelocityMode : std::uint8_t {
  kAuto = 0,          // per-frame stick/slip detection picks the proxy (default)
  kVelocity = 1,      // shear proportional to contact velocity (paper's model)
  kDisplacement = 2,  // shear increments are contact displacements
};

// Fault / warning code of the Status frame. 0 = none. Receivers show unknown codes by number.
enum class FaultCode : std::uint8_t {
  kNone = 0,
  kLeftSensorLost = 1,
  kRightSensorLost = 2,
  kBothSensorsLost = 3,
  kCalibrationInvalid = 4,
  kDspOverrun = 5,
  kCanErrorPassive = 6,
  kCanBusOffRecovered = 7,
};

enum class CommandCode : std::uint8_t {
  kTare = 0x01,
  kResetPose = 0x02,
  kSetFingerSeparation = 0x03,
  kSetFusion = 0x04,
  kSetRateDivider = 0x05,
  kSetStream = 0x06,
  kQuery = 0x07,
  kStartRecording = 0x08,
  kStopRecording = 0x09,
};

// Result byte of the Ack frame: 0 = ACK, anything else is a NACK with that reason.
enum class AckCode : std::uint8_t {
  kAck = 0,
  kUnknownCommand = 1,
  kBadLength = 2,
  kBadCrc = 3,
  kWrongNode = 4,  // payload's target node differs from the identifier's node
  kOutOfRange = 5,
  kReservedNotZero = 6,
  kBusy = 7,  // valid, but not allowed in the current state (firmware decides)
  kInternalError = 8,
  // Recording commands (the firmware's decision, like kBusy).
  kAlreadyRecording = 9,
  kNotRecording = 10,
  kNoRecordDir = 11,      // the board file has no [record] dir and tacse3d no --record-root
  kRecordingExists = 12,  // the recording number's directory exists: never overwritten
  kDiskError = 13,        // the recording could not be created, or a write failed
};

enum class QueryItem : std::uint8_t {
  kProtocolVersion = 0,
  kFirmwareVersion = 1,
  kFingerSeparation = 2,
  kFusion = 3,
  kStream = 4,
};

constexpr const char* to_string(State s) noexcept {
  switch (s) {
    case State::kBooting:
      return "BOOTING";
    case State::kNoContact:
      return "NO_CONTACT";
    case State::kTracking:
      return "TRACKING";
    case State::kDegradedSingleSensor:
      return "DEGRADED_SINGLE_SENSOR";
    case State::kFault:
      return "FAULT";
  }
  return nullptr;
}

constexpr const char* to_string(SensorHealth h) noexcept {
  switch (h) {
    case SensorHealth::kOk:
      return "OK";
    case SensorHealth::kStale:
      return "STALE";
    case SensorHealth::kLost:
      return "LOST";
    case SensorHealth::kNotAvailable:
      return "NOT_AVAILABLE";
  }
  return nullptr;
}

constexpr const char* to_string(FusionMethod m) noexcept {
  switch (m) {
    case FusionMethod::kJoint:
      return "JOINT";
    case FusionMethod::kPaper:
      return "PAPER";
  }
  return nullptr;
}

constexpr const char* to_string(VelocityMode m) noexcept {
  switch (m) {
    case VelocityMode::kAuto:
      return "AUTO";
    case VelocityMode::kVelocity:
      return "VELOCITY";
    case VelocityMode::kDisplacement:
      return "DISPLACEMENT";
  }
  return nullptr;
}

constexpr const char* to_string(FaultCode f) noexcept {
  switch (f) {
    case FaultCode::kNone:
      return "NONE";
    case FaultCode::kLeftSensorLost:
      return "LEFT_SENSOR_LOST";
    case FaultCode::kRightSensorLost:
      return "RIGHT_SENSOR_LOST";
    case FaultCode::kBothSensorsLost:
      return "BOTH_SENSORS_LOST";
    case FaultCode::kCalibrationInvalid:
      return "CALIBRATION_INVALID";
    case FaultCode::kDspOverrun:
      return "DSP_OVERRUN";
    case FaultCode::kCanErrorPassive:
      return "CAN_ERROR_PASSIVE";
    case FaultCode::kCanBusOffRecovered:
      return "CAN_BUS_OFF_RECOVERED";
  }
  return nullptr;
}

constexpr const char* to_string(CommandCode c) noexcept {
  switch (c) {
    case CommandCode::kTare:
      return "TARE";
    case CommandCode::kResetPose:
      return "RESET_POSE";
    case CommandCode::kSetFingerSeparation:
      return "SET_FINGER_SEPARATION";
    case CommandCode::kSetFusion:
      return "SET_FUSION";
    case CommandCode::kSetRateDivider:
      return "SET_RATE_DIVIDER";
    case CommandCode::kSetStream:
      return "SET_STREAM";
    case CommandCode::kQuery:
      return "QUERY";
    case CommandCode::kStartRecording:
      return "START_RECORDING";
    case CommandCode::kStopRecording:
      return "STOP_RECORDING";
  }
  return nullptr;
}

constexpr const char* to_string(AckCode a) noexcept {
  switch (a) {
    case AckCode::kAck:
      return "ACK";
    case AckCode::kUnknownCommand:
      return "UNKNOWN_COMMAND";
    case AckCode::kBadLength:
      return "BAD_LENGTH";
    case AckCode::kBadCrc:
      return "BAD_CRC";
    case AckCode::kWrongNode:
      return "WRONG_NODE";
    case AckCode::kOutOfRange:
      return "OUT_OF_RANGE";
    case AckCode::kReservedNotZero:
      return "RESERVED_NOT_ZERO";
    case AckCode::kBusy:
      return "BUSY";
    case AckCode::kInternalError:
      return "INTERNAL_ERROR";
    case AckCode::kAlreadyRecording:
      return "ALREADY_RECORDING";
    case AckCode::kNotRecording:
      return "NOT_RECORDING";
    case AckCode::kNoRecordDir:
      return "NO_RECORD_DIR";
    case AckCode::kRecordingExists:
      return "RECORDING_EXISTS";
    case AckCode::kDiskError:
      return "DISK_ERROR";
  }
  return nullptr;
}

constexpr const char* to_string(QueryItem q) noexcept {
  switch (q) {
    case QueryItem::kProtocolVersion:
      return "PROTOCOL_VERSION";
    case QueryItem::kFirmwareVersion:
      return "FIRMWARE_VERSION";
    case QueryItem::kFingerSeparation:
      return "FINGER_SEPARATION";
    case QueryItem::kFusion:
      return "FUSION";
    case QueryItem::kStream:
      return "STREAM";
  }
  return nullptr;
}

}  // namespace tacse3::protocol
