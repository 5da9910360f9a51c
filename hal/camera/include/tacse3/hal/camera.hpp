// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: the camera interface every capture backend (V4L2, libcamera, sim, replay) implements.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "tacse3/dsp/types.hpp"

namespace tacse3::hal {

// Why a camera call did not deliver a frame. No exception crosses this interface.
enum class CameraError : std::uint8_t {
  kOk = 0,
  kTimeout,       // no frame within the timeout; the device is fine
  kNotFound,      // the device node or camera id does not exist
  kPermission,    // EACCES/EPERM opening the device (user not in group video?)
  kBusy,          // the device is in use by another process
  kNotSupported,  // not a capture device, or no acceptable format/size/streaming mode
  kDisconnected,  // the device was lost; the backend retries on later next_frame() calls
  kCorruptFrame,  // a frame was short, flagged bad by the driver, or failed to decode
  kIo,            // any other system or library failure
  kBadConfig,     // a CameraConfig field is out of range
  kBadState,      // the call is not valid in the current state (e.g. next_frame before start)
  kUnavailable,   // the backend or feature was not compiled in
};

const char* to_string(CameraError e) noexcept;

// Result of a camera call: a code plus a human-readable message naming the device and the cause.
// Fixed-size storage, so building one never allocates.
struct CameraStatus {
  CameraError code = CameraError::kOk;
  std::array<char, 224> text{};

  bool ok() const noexcept { return code == CameraError::kOk; }
  explicit operator bool() const noexcept { return ok(); }
  const char* message() const noexcept { return text[0] != '\0' ? text.data() : to_string(code); }

  static CameraStatus success() noexcept { return {}; }
  // printf-style message; truncated to the storage size.
  static CameraStatus error(CameraError code, const char* fmt, ...) noexcept
      __attribute__((format(printf, 2, 3)));
};

// Which clock a frame timestamp came from. All of them are CLOCK_MONOTONIC nanoseconds.
enum class TimestampSource : std::uint8_t {
  kDriver = 0,  // V4L2 buffer timestamp flagged V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC
  kSensor,      // libcamera SensorTimestamp (start of exposure of the first row)
  kDequeue,     // the driver gave none usable: clock_gettime(CLOCK_MONOTONIC) at dequeue
  kSimulated,   // a sim or replay backend
};

const char* to_string(TimestampSource s) noexcept;

// One captured frame. The view stays valid until the frame is passed to Camera::release().
struct Frame {
  dsp::FrameView view;               // data, size, width, height, stride, pixel format
  std::uint32_t sequence = 0;        // driver frame sequence number (wraps at 2^32)
  std::int64_t timestamp_ns = 0;     // CLOCK_MONOTONIC, see TimestampSource
  std::uint32_t dropped_before = 0;  // frames missing from the sequence just before this one
  TimestampSource timestamp_source = TimestampSource::kDriver;
  std::uint32_t slot = 0;  // the backend's buffer slot; opaque to the consumer
};

// Reconnect schedule after a disconnect: initial_ms, then x2 each attempt, capped at max_ms.
struct ReconnectPolicy {
  int initial_ms = 100;
  int max_ms = 5000;
  int max_attempts = 0;  // 0 = keep trying forever; otherwise give up (LinkState::kFailed)
};

struct CameraConfig {
  // V4L2: a device node (/dev/video0, /dev/tacse3-left).
  // libcamera: a camera id, "#N" for the N-th camera in id order, or empty for the first one.
  std::string device;
  int width = 320;
  int height = 240;
  int fps = 120;
  int buffer_count = 4;  // 2..16 driver buffers, all allocated at open()
  bool allow_mjpeg = true;
  // What MJPEG frames are decoded to: kGrey (luma only, cheapest) or kRgb888.
  dsp::PixelFormat mjpeg_output = dsp::PixelFormat::kGrey;
  ReconnectPolicy reconnect;
};

// Checks every field's range (device non-empty, even width, fps 1..1000, buffer_count 2..16,
// mjpeg_output GREY or RGB888, reconnect delays >= 1 ms). kBadConfig names the field.
CameraStatus validate(const CameraConfig& config) noexcept;

// What was negotiated. Fixed-size fields: refreshed on reconnect without allocating.
struct CameraInfo {
  std::array<char, 16> backend{};  // "v4l2", "libcamera", "sim", "replay"
  std::array<char, 32> driver{};   // e.g. "uvcvideo"
  std::array<char, 64> card{};     // device/camera name
  std::array<char, 8> fourcc{};    // the device's native format, e.g. "YUYV", "MJPG"
  dsp::PixelFormat format = dsp::PixelFormat::kGrey;  // what frames carry
  int width = 0;                                      // what frames carry
  int height = 0;
  int native_width = 0;   // what the device delivers: larger when the backend
  int native_height = 0;  // centre-crops (libcamera); 0 = the same as width/height
  int stride_bytes = 0;
  int buffer_count = 0;
  bool decoded = false;            // MJPEG decoded by the backend
  std::uint32_t interval_num = 0;  // granted frame interval in seconds = num / den
  std::uint32_t interval_den = 0;  // (0/0: the driver did not say)
  TimestampSource timestamp_source = TimestampSource::kDriver;

  double granted_fps() const noexcept {
    return interval_num == 0 ? 0.0 : static_cast<double>(interval_den) / interval_num;
  }
};

// Counters since open(). Safe to read from any thread.
struct CameraStats {
  std::uint64_t frames = 0;              // delivered by next_frame()
  std::uint64_t drops = 0;               // sequence gaps (frames the driver never delivered)
  std::uint64_t corrupt = 0;             // frames discarded: error flag, short, undecodable
  std::uint64_t timeouts = 0;            // next_frame() calls that timed out
  std::uint64_t disconnects = 0;         // device losses detected
  std::uint64_t reconnects = 0;          // successful reopens after a loss
  std::uint64_t reconnect_attempts = 0;  // reopen attempts, successful or not
};

enum class LinkState : std::uint8_t {
  kClosed = 0,  // before open() / after stop()
  kOpen,        // open() done, not streaming
  kStreaming,
  kDisconnected,  // lost; next_frame() retries following the ReconnectPolicy
  kFailed,        // gave up after ReconnectPolicy::max_attempts
};

const char* to_string(LinkState s) noexcept;

// A capture device. Threading: open/start/next_frame/stop/info are called from one capture
// thread; release() may be called from one other thread (or the same one); stats() and
// link_state() from anywhere. Every buffer is allocated in open() (and again only on reconnect).
class Camera {
 public:
  virtual ~Camera() = default;

  // Opens the device, negotiates the format and allocates every buffer.
  virtual CameraStatus open() = 0;
  // Starts streaming.
  virtual CameraStatus start() = 0;
  // Waits up to timeout_ms (< 0: forever) for the next frame. On kOk `frame` holds a buffer the
  // caller owns until release(frame). kTimeout: nothing yet. kCorruptFrame: a bad frame was
  // discarded (counted). kDisconnected: the device is lost; it is reported once per loss with
  // the cause, then later calls wait (bounded by timeout_ms) and retry with backoff, and return
  // frames again once the device is back. Frames still held block the reopen: release them.
  virtual CameraStatus next_frame(Frame& frame, int timeout_ms) = 0;
  // Hands a buffer back to the backend. Frames may be released in any order.
  virtual void release(const Frame& frame) = 0;
  // Stops streaming and frees the buffers. Release every frame first.
  virtual void stop() = 0;

  virtual const CameraInfo& info() const = 0;
  virtual CameraStats stats() const = 0;
  virtual LinkState link_state() const = 0;
};

}  // namespace tacse3::hal
