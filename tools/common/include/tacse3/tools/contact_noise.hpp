// SPDX-License-Identifier: Apache-2.0
// tacse3 tools: the f^z noise of a recording, from its frames before contact (tacse3-calibrate).
#pragma once

#include <cstddef>
#include <vector>

namespace tacse3::tools {

// A recording starts with the pads open: the first frame is the pipeline's reference, so until
// the pads touch the object filter(f^z) is the flow's noise alone. Fed every frame's filtered f^z
// over the valid grid points (both pads), this finds that leading quiet run and its robust σ
// (1.4826 · median absolute deviation). The run ends at the contact onset: the first of
// kOnsetFrames consecutive frames with a point more than kOnsetSigma · σ above the run's median,
// where σ is the run's so far (the first kSeedFrames frames after the reference form the seed).
// kOnsetSigma is the multiple contact_tau_on is set to, so the onset is the first frame whose
// contact mask the fitted threshold would start.
class PreContactNoise {
 public:
  static constexpr std::size_t kSeedFrames = 3;
  static constexpr std::size_t kOnsetFrames = 3;
  static constexpr double kOnsetSigma = 6.0;
  // Values pooled for σ: one second at 120 Hz is plenty; later quiet frames only extend the run.
  static constexpr std::size_t kMaxPooledFrames = 120;

  // Frame `index` of the recording (0 is the reference and is skipped); frames in order.
  void add_frame(std::size_t index, const std::vector<double>& fz);

  // A contact onset was seen after at least kSeedFrames quiet frames.
  bool onset_found() const noexcept { return onset_ != kNone; }
  std::size_t onset_frame() const noexcept { return onset_; }  // first frame of the onset
  std::size_t quiet_frames() const noexcept { return quiet_; }
  double sigma() const noexcept { return sigma_; }
  double median() const noexcept { return median_; }

 private:
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  void refit();
  std::vector<float> pooled_;
  std::vector<std::vector<double>> pending_;  // frames over the bar, not yet an onset
  std::size_t pending_first_ = 0;
  std::size_t quiet_ = 0;
  std::size_t pooled_frames_ = 0;
  std::size_t onset_ = kNone;
  double sigma_ = 0.0, median_ = 0.0;
};

}  // namespace tacse3::tools
