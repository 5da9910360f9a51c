// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: the `replay` camera backend: one sensor of a recording directory, paced or fast.
#pragma once

#include <memory>
#include <string>

#include "tacse3/hal/camera.hpp"

namespace tacse3::hal {

struct ReplayCameraConfig {
  std::string dir;       // recording directory (docs/recording-format.md)
  bool right = false;    // which sensor of the recording: left (false) or right
  bool realtime = true;  // pace to frames.csv's t_ns; false: as fast as consumed
  bool loop = false;     // start over after the last frame instead of ending
  int buffer_count = 4;  // 2..16 decoded-frame buffers, all allocated in open()
  // Delay of every frame (its stamp and, paced, its delivery) after start(), >= 0: two replay
  // cameras with different phases play two free-running cameras' offset between the pads.
  std::int64_t phase_ns = 0;
};

// Statistics beyond CameraStats: how the PNG decoder's memory was served.
struct ReplayDecodeStats {
  std::uint64_t decodes = 0;            // PNGs decoded
  std::uint64_t arena_allocations = 0;  // libspng/zlib allocations served by the decoder arena
  std::uint64_t heap_fallbacks = 0;     // allocations the arena could not hold (went to malloc)
  std::size_t arena_peak_bytes = 0;     // most arena bytes one decode used
  std::size_t arena_bytes = 0;          // the arena's size, set by open()'s trial decode
};

// A Camera replaying one sensor of a recording. open() validates the whole recording
// (RecordingReader: recording.json, frames.csv, every PNG's presence and header; errors name the
// file), reads the file sizes and allocates the frame buffers, a file buffer as large as the
// largest PNG and the decoder's arena. next_frame() reads and decodes the next PNG on the
// calling (capture) thread without touching the heap: the file is read with read(2) into the
// file buffer and libspng gets an arena allocator (spng_ctx_new2) that is reset per frame.
//
// Timestamps: CLOCK_MONOTONIC, TimestampSource::kSimulated: frame i of the recording is stamped
// start + (t_i - t_0), where start is the time of start() plus one nominal period plus the
// phase; every loop adds the recording's span plus one nominal period. Sequence numbers count
// delivered frames from 0 (loops continue counting).
//
// Errors: a corrupt or vanished PNG gives kCorruptFrame naming the file (counted in
// stats.corrupt; the next call continues with the next frame). The end of the recording (no loop)
// is reported as kDisconnected with the message "... end of recording ..." and the link state
// becomes kFailed: it is reported at once by the first call after the last frame, and again by
// every later call after waiting out its timeout (bounded, so a capture loop does not spin).
std::unique_ptr<Camera> make_replay_camera(const ReplayCameraConfig& config);

// The decoder statistics of a camera made by make_replay_camera() (zero for any other camera).
ReplayDecodeStats replay_decode_stats(const Camera& camera) noexcept;

}  // namespace tacse3::hal
