// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: --record DIR, the frame pairs the DSP thread formed, through the streaming
// writer.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "tacse3/dsp/types.hpp"
#include "tacse3/protocol/types.hpp"
#include "tacse3/recording/stream_writer.hpp"

namespace tacse3::firmware {

struct RecorderConfig {
  std::array<bool, 2> sensors{true, true};  // which pads the board has (left, right)
  std::array<dsp::PixelFormat, 2> formats{dsp::PixelFormat::kGrey, dsp::PixelFormat::kGrey};
  int width = 320;
  int height = 240;
  double fps = 120.0;
  double pixel_pitch_mm = 0.075;
  double finger_separation_mm = 40.0;
  std::size_t ring_frames = 32;  // frame slots of the bounded ring (≈ 0.27 s at 120 Hz)
};

// Records what the daemon processes, in the recording format (docs/recording-format.md): one
// frames.csv row per instant at which every configured pad delivered (pairs on a two-pad board),
// stamped with the frame time. RGB888 sensors are recorded as RGB; any other format (YUYV, GREY,
// a mix) as 8-bit grey: the luma the pipeline itself uses (YUYV's Y bytes, RGB's BT.601 luma).
// record() is called on the DSP thread: it never blocks, allocates or touches the disk (the
// conversion buffers are allocated here, the PNGs are written by the writer's own thread); a
// full ring drops the frame (counted) and a write error stops the recording, never the stream.
class FrameRecorder {
 public:
  // *error names `dir` and the cause.
  static std::unique_ptr<FrameRecorder> start(const std::filesystem::path& dir,
                                              const RecorderConfig& config, std::string* error);
  // Frames of one instant (null for a pad without a frame at this instant).
  void record(std::int64_t t_ns, const dsp::FrameView* left, const dsp::FrameView* right) noexcept;
  // Writes what is queued and stops. Returns "" or the first write error.
  std::string close();
  bool failed() const noexcept { return writer_->failed(); }
  std::string error() const { return writer_->error(); }
  recording::StreamWriterStats stats() const noexcept { return writer_->stats(); }
  std::uint64_t skipped_incomplete() const noexcept { return incomplete_; }

 private:
  FrameRecorder() = default;
  bool to_image(std::size_t s, const dsp::FrameView& v, recording::StreamImage* out) noexcept;

  RecorderConfig config_;
  int channels_ = 1;
  std::unique_ptr<recording::StreamWriter> writer_;
  std::array<std::unique_ptr<std::uint8_t[]>, 2> grey_;  // conversion buffers, width x height
  std::uint64_t incomplete_ = 0;
};

// The directory of recording `number` under the record root: rec-NNNNN (five digits).
std::filesystem::path numbered_recording_dir(const std::filesystem::path& root,
                                             std::uint16_t number);

// START_RECORDING's disk work (housekeeping thread): a new recording rec-NNNNN under `root`
// (the board file's [record] dir) with `config` (its rig block as given). Returns kAck and
// *out, or the NACK reason with *message for the log: kNoRecordDir (root empty),
// kRecordingExists (never overwritten), kDiskError (root missing, not writable, ...).
protocol::AckCode start_numbered_recording(const std::string& root, std::uint16_t number,
                                           const RecorderConfig& config,
                                           std::unique_ptr<FrameRecorder>* out,
                                           std::string* message);

}  // namespace tacse3::firmware
