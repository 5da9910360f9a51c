// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the pixel pitch from stick translations (tacse3-calibrate, docs/calibration.md).
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "tacse3/tools/calibration_check.hpp"
#include "tacse3/tools/source.hpp"

namespace tacse3::tools {

// A stick translation (Motion::kStickTranslation) measures the pitch: while the contact sticks,
// the gel under it moves with the object, so the contact's material displacement in pixels times
// the pitch is the truth's translation.
bool is_stick_translation(const SourceInfo& info);

// One recording's measurement: per frame after the motion starts and per sensor, the truth's
// in-plane translation since the start (mm) and the contact's mean displacement since then
// (sensor px).
struct StickShift {
  std::string name;
  std::vector<double> truth_mm, shift_px;
  double pitch_mm() const noexcept;  // least squares truth = P shift (0: no sample)
};

// Replays `source` (its pipeline with the documented default calibration: only the flow and the
// contact mask are used) and measures its shift. "" or an error naming the recording.
std::string measure_stick_shift(FrameSource& source, StickShift* out);

struct PitchFit {
  double pitch_mm = 0.0;    // fitted (least squares over every sample of every recording)
  double claimed_mm = 0.0;  // the recordings' rig.pixel_pitch_mm (the first's)
  // Relative standard error of the fit: the scatter of the per-recording pitches over
  // sqrt(recordings), or of the per-frame ratios over sqrt(frames) with one recording.
  double relative_se = 0.0;
  std::vector<StickShift> recordings;
};

// Fits the pitch over the stick translations among `sources` (jobs in parallel). "" or an error;
// a set without stick translations is an error naming the motion to record.
std::string fit_pixel_pitch(const std::vector<FrameSource*>& sources, int jobs, bool progress,
                            PitchFit* out);

// "pixel pitch: fitted P mm/px from N stick translation(s) (± SE), replaces the recordings' C
// mm/px (ratio R)", one line per recording.
std::string format_pitch(const PitchFit& fit);

// A source whose rig pitch is replaced (the fit and its self-check then run with the fitted one).
class PitchOverrideSource final : public FrameSource {
 public:
  PitchOverrideSource(FrameSource& inner, double pixel_pitch_mm);
  const SourceInfo& info() const noexcept override { return info_; }
  std::string read(std::size_t index, std::array<const dsp::FrameView*, 2>* views) override {
    return inner_.read(index, views);
  }

 private:
  FrameSource& inner_;
  SourceInfo info_;
};

}  // namespace tacse3::tools
