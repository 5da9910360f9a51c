// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the kAuto stick/slip detector on the shear's planar rigid content.
#pragma once

#include <Eigen/Core>

#include "tacse3/dsp/calibration.hpp"

namespace tacse3::dsp {

// One sensor's stick/slip decision (docs/dsp/motion.md, stick/slip detector). Input per frame:
// the planar rigid content X of the shear over Ω read as a displacement (planar_content()), the
// same content of this frame's shear increments over Ω_t ∩ Ω_{t−1} (the change dX), and the
// load's relative rate of fall ρ_L. It smooths X and dX exponentially (τ = slip_smoothing_s) and
// decides with hysteresis:
//  * slip onset: ρ − max(0, ρ_L) > slip_relax_rate_on for slip_on_frames consecutive frames with
//    |X| > slip_min_shift_m, ρ = −X·dX / (|X|² Δt) the relative relaxation rate; no frame with
//    ρ_L > release_load_rate counts (a release, not a slide);
//  * slip end: at rest (|dX|/Δt < stick_rest_speed_m_s) with |X| ≤ slip_exit_fraction of its
//    peak during the slip;
//  * stick confirmed: at rest for stick_confirm_s, or for slip_on_frames frames with
//    |X| ≤ slip_min_shift_m (an unloaded contact).
// The fixed-point MotionEstimator and the double reference dsp_ref::MotionRef both decide with
// this class; only the features they feed it are computed apart. State: a few scalars, no heap.
class SlipDetector {
 public:
  struct Features {
    double shift_m = 0.0;         // |X| smoothed (m)
    double rate_m_s = 0.0;        // |dX|/Δt smoothed (m/s)
    double relax_rate = 0.0;      // ρ (1/s)
    double load_drop_rate = 0.0;  // ρ_L as given (1/s)
  };
  struct Step {
    bool onset = false;      // stick → slip at the end of this frame
    bool ended = false;      // slip → stick at the end of this frame
    bool confirmed = false;  // the stick is confirmed this frame
  };

  // The thresholds are Calibration's fields of the same names (validated by the caller).
  void configure(const Calibration& cal) noexcept;
  // Forget the state: the next contact starts sticking (static friction first). features()
  // keeps the last frame's values.
  void reset() noexcept;

  // One frame in contact. raw: X (unsmoothed); step: the content of the increments; dt_s > 0.
  // The decision of this frame (slipping() before the call) is the one taken up to the previous
  // frame; the returned transitions apply from the next.
  Step update(const Eigen::Vector3d& raw, const Eigen::Vector3d& step, double load_drop_rate,
              double dt_s) noexcept;
  // Smoothing only, without a decision (the reference following another detector's choices).
  void observe(const Eigen::Vector3d& raw, const Eigen::Vector3d& step, double load_drop_rate,
               double dt_s) noexcept;
  // Take a decision made elsewhere: slipping, or a slide that ended (restarts the state).
  void set_slipping(bool slipping) noexcept;

  bool slipping() const noexcept { return slipping_; }
  const Features& features() const noexcept { return features_; }

 private:
  double relax_rate_on_ = 0.0;
  int on_frames_ = 1;
  double min_shift_m_ = 0.0;
  double exit_fraction_ = 0.0;
  double rest_speed_ = 0.0;
  double confirm_s_ = 0.0;
  double smoothing_s_ = 0.0;
  double release_load_rate_ = kReleaseRuleOff;

  bool slipping_ = false;
  int evidence_frames_ = 0;
  int unloaded_rest_frames_ = 0;  // consecutive frames at rest with |X| ≤ slip_min_shift_m
  double rest_s_ = 0.0;
  double peak_shift_m_ = 0.0;
  Eigen::Vector3d content_ = Eigen::Vector3d::Zero();  // smoothed X
  Eigen::Vector3d change_ = Eigen::Vector3d::Zero();   // smoothed dX
  bool have_content_ = false;
  Features features_;
};

}  // namespace tacse3::dsp
