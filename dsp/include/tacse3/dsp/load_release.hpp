// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the release rule: a contact whose normal load falls fast is being let go.
#pragma once

#include "tacse3/dsp/calibration.hpp"

namespace tacse3::dsp {

// One sensor's normal load L = Σ z over Ω and its relative rate of fall
// ρ_L = −EMA(L_t − L_{t−1}) / (EMA(L) · Δt), EMA the exponential smoothing with
// τ = slip_smoothing_s (so ρ_L ≤ 1/slip_smoothing_s at a constant frame period). In a thin layer
// pressure is proportional to indentation, so L is the normal force up to a gain and ρ_L is
// unit-free. A grasp, sticking or sliding, holds its load; opening the pads sheds it much faster,
// and the gel let go springs back (docs/dsp/motion.md, release). The fixed-point MotionEstimator
// and the double reference both use this class, fed with their own L. State: two doubles.
class LoadRelease {
 public:
  // slip_smoothing_s and release_load_rate (validated by the caller).
  void configure(const Calibration& cal) noexcept;
  void reset() noexcept;
  // A frame in contact: load L_t, and L_{t−1} if the previous frame had contact (had_previous);
  // a contact's first frame starts the smoothing. Returns ρ_L (1/s); 0 without load. dt_s > 0.
  double update(double load, bool had_previous, double previous_load, double dt_s) noexcept;
  // ρ_L above release_load_rate, with the rule on (release_load_rate < kReleaseRuleOff).
  bool unloading_fast(double load_drop_rate) const noexcept {
    return rule_on() && load_drop_rate > release_load_rate_;
  }
  bool rule_on() const noexcept { return release_load_rate_ < kReleaseRuleOff; }

 private:
  double smoothing_s_ = 0.0;
  double release_load_rate_ = kReleaseRuleOff;
  double load_ = 0.0;         // smoothed L
  double load_change_ = 0.0;  // smoothed L_t − L_{t−1}
};

}  // namespace tacse3::dsp
