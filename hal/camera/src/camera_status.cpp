// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: camera status codes and their messages.
#include <cstdarg>
#include <cstdio>

#include "tacse3/hal/camera.hpp"

namespace tacse3::hal {

const char* to_string(CameraError e) noexcept {
  switch (e) {
    case CameraError::kOk:
      return "ok";
    case CameraError::kTimeout:
      return "timed out waiting for a frame";
    case CameraError::kNotFound:
      return "camera not found";
    case CameraError::kPermission:
      return "permission denied";
    case CameraError::kBusy:
      return "camera busy";
    case CameraError::kNotSupported:
      return "not supported by the camera";
    case CameraError::kDisconnected:
      return "camera disconnected";
    case CameraError::kCorruptFrame:
      return "corrupt frame discarded";
    case CameraError::kIo:
      return "I/O error";
    case CameraError::kBadConfig:
      return "bad camera configuration";
    case CameraError::kBadState:
      return "call not valid in the camera's current state";
    case CameraError::kUnavailable:
      return "not compiled in";
  }
  return "unknown camera error";
}

const char* to_string(TimestampSource s) noexcept {
  switch (s) {
    case TimestampSource::kDriver:
      return "driver (monotonic)";
    case TimestampSource::kSensor:
      return "sensor";
    case TimestampSource::kDequeue:
      return "dequeue time";
    case TimestampSource::kSimulated:
      return "simulated";
  }
  return "unknown";
}

const char* to_string(LinkState s) noexcept {
  switch (s) {
    case LinkState::kClosed:
      return "closed";
    case LinkState::kOpen:
      return "open";
    case LinkState::kStreaming:
      return "streaming";
    case LinkState::kDisconnected:
      return "disconnected";
    case LinkState::kFailed:
      return "failed";
  }
  return "unknown";
}

CameraStatus CameraStatus::error(CameraError code, const char* fmt, ...) noexcept {
  CameraStatus s;
  s.code = code;
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(s.text.data(), s.text.size(), fmt, args);
  va_end(args);
  return s;
}

CameraStatus validate(const CameraConfig& c) noexcept {
  if (c.width < 16 || c.width > 4096 || c.width % 2 != 0) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "camera width %d: must be even and within 16..4096", c.width);
  }
  if (c.height < 16 || c.height > 4096) {
    return CameraStatus::error(CameraError::kBadConfig, "camera height %d: must be within 16..4096",
                               c.height);
  }
  if (c.fps < 1 || c.fps > 1000) {
    return CameraStatus::error(CameraError::kBadConfig, "camera fps %d: must be within 1..1000",
                               c.fps);
  }
  if (c.buffer_count < 2 || c.buffer_count > 16) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "camera buffer_count %d: must be within 2..16", c.buffer_count);
  }
  if (c.mjpeg_output != dsp::PixelFormat::kGrey && c.mjpeg_output != dsp::PixelFormat::kRgb888) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "camera mjpeg_output: must be GREY or RGB888");
  }
  if (c.reconnect.initial_ms < 1 || c.reconnect.max_ms < c.reconnect.initial_ms ||
      c.reconnect.max_attempts < 0) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "camera reconnect: need 1 <= initial_ms (%d) <= max_ms (%d) and "
                               "max_attempts (%d) >= 0",
                               c.reconnect.initial_ms, c.reconnect.max_ms,
                               c.reconnect.max_attempts);
  }
  return CameraStatus::success();
}

}  // namespace tacse3::hal
