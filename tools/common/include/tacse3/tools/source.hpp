// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: frame sources for the replay engine (a recording directory, or frames in memory).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tacse3/dsp/types.hpp"
#include "tacse3/recording/recording.hpp"

namespace tacse3::tools {

// What the replay engine needs to know about a recording besides its frames.
struct SourceInfo {
  std::string name;  // recording directory (or a label), used in messages
  int width = 320;
  int height = 240;
  std::array<bool, 2> has_sensor{false, false};  // [left, right]
  double pixel_pitch_mm = 0.1;
  double finger_separation_mm = 40.0;
  std::vector<std::int64_t> t_ns;             // one per frame, strictly increasing
  std::vector<recording::TruthSample> truth;  // empty without truth.csv
  std::vector<recording::SimLabel> labels;    // empty without sim_labels.csv
  std::string extra_json;                     // recording.json's full text, if any
  std::size_t frame_count() const noexcept { return t_ns.size(); }
  bool has_truth() const noexcept { return !truth.empty(); }
};

// A source of frame pairs. Frames are requested in increasing index order (sources may rely on
// it). `views[s]` is null for a sensor without a frame; the pointed-to views stay valid until the
// next read(). Returns an empty string or an error message naming the file.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual const SourceInfo& info() const noexcept = 0;
  virtual std::string read(std::size_t index, std::array<const dsp::FrameView*, 2>* views) = 0;
};

// The pipeline's frame size (DM-Tac). Anything else is refused when a source is opened.
inline constexpr int kPipelineWidth = 320;
inline constexpr int kPipelineHeight = 240;

// A recording directory (docs/recording-format.md), PNGs decoded with the recording library.
class RecordingSource final : public FrameSource {
 public:
  // Validates the directory (recording.json, frames.csv, PNG headers, truth.csv, sim_labels.csv)
  // and the frame size; *error names the file at fault.
  static std::unique_ptr<RecordingSource> open(const std::filesystem::path& dir,
                                               std::string* error);
  const SourceInfo& info() const noexcept override { return info_; }
  std::string read(std::size_t index, std::array<const dsp::FrameView*, 2>* views) override;
  const recording::RecordingReader& reader() const noexcept { return reader_; }

 private:
  explicit RecordingSource(recording::RecordingReader reader) : reader_(std::move(reader)) {}
  recording::RecordingReader reader_;
  SourceInfo info_;
  recording::RecordingReader::Frame frame_;
  std::array<int, 2> slot_{-1, -1};  // reader slot of [left, right]
  std::array<dsp::FrameView, 2> views_{};
};

// True for a recording written by the simulator: recording.json holds a "sim" object whose
// "generator" is "tacse3-sim" (docs/recording-format.md). Such a recording is replayed with the
// simulator's calibration when none is given.
bool is_simulator_recording(const SourceInfo& info);

// A FrameView of an 8-bit grey or RGB image held elsewhere.
dsp::FrameView frame_view(const std::uint8_t* data, int width, int height, int channels) noexcept;

}  // namespace tacse3::tools
