// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the kAuto stick/slip detector (see slip_detector.hpp).
#include "tacse3/dsp/slip_detector.hpp"

#include <algorithm>
#include <cmath>

namespace tacse3::dsp {

void SlipDetector::configure(const Calibration& cal) noexcept {
  relax_rate_on_ = cal.slip_relax_rate_on;
  on_frames_ = cal.slip_on_frames;
  min_shift_m_ = cal.slip_min_shift_m;
  exit_fraction_ = cal.slip_exit_fraction;
  rest_speed_ = cal.stick_rest_speed_m_s;
  confirm_s_ = cal.stick_confirm_s;
  smoothing_s_ = cal.slip_smoothing_s;
  release_load_rate_ = cal.release_load_rate;
}

void SlipDetector::reset() noexcept {
  slipping_ = false;
  evidence_frames_ = 0;
  unloaded_rest_frames_ = 0;
  rest_s_ = 0.0;
  peak_shift_m_ = 0.0;
  content_.setZero();
  change_.setZero();
  have_content_ = false;
}

void SlipDetector::set_slipping(bool slipping) noexcept {
  if (slipping == slipping_) return;
  if (slipping) {
    slipping_ = true;
    evidence_frames_ = 0;
  } else {
    reset();
  }
}

void SlipDetector::observe(const Eigen::Vector3d& raw, const Eigen::Vector3d& step,
                           double load_drop_rate, double dt_s) noexcept {
  // dX is read from the increments over Ω_t ∩ Ω_{t−1} (smoothed alike, which equals the change of
  // the smoothed X while Ω stays the same): rim cells entering or leaving Ω carry shear they did
  // not just gain or lose, and a rim burst read as a relaxation would start false slips.
  const double alpha = smoothing_s_ > 0.0 ? dt_s / (smoothing_s_ + dt_s) : 1.0;
  content_ = have_content_ ? Eigen::Vector3d(content_ + alpha * (raw - content_)) : raw;
  change_ =
      have_content_ ? Eigen::Vector3d(change_ + alpha * (step - change_)) : Eigen::Vector3d::Zero();
  have_content_ = true;
  const double x2 = content_.squaredNorm();
  features_.shift_m = std::sqrt(x2);
  features_.rate_m_s = change_.norm() / dt_s;
  features_.relax_rate = x2 > 0.0 ? -content_.dot(change_) / (x2 * dt_s) : 0.0;
  features_.load_drop_rate = load_drop_rate;
}

SlipDetector::Step SlipDetector::update(const Eigen::Vector3d& raw, const Eigen::Vector3d& step,
                                        double load_drop_rate, double dt_s) noexcept {
  observe(raw, step, load_drop_rate, dt_s);
  Step s;
  const Features& f = features_;
  const bool rest = f.rate_m_s < rest_speed_;
  if (slipping_) {
    peak_shift_m_ = std::max(peak_shift_m_, f.shift_m);
    if (rest && f.shift_m <= exit_fraction_ * peak_shift_m_) {
      // The slide is over and the gel has relaxed: stick again from here (increments only, so
      // the residual shear does not move the pose).
      reset();
      s.ended = true;
    }
    return s;
  }
  // Only relaxation beyond the load's own relative fall counts, and none while the load falls
  // faster than release_load_rate (a release).
  const bool release_rule = release_load_rate_ < kReleaseRuleOff;
  const bool unloading_fast = release_rule && load_drop_rate > release_load_rate_;
  const bool relaxing =
      f.shift_m > min_shift_m_ && !unloading_fast &&
      f.relax_rate - (release_rule ? std::max(0.0, load_drop_rate) : 0.0) > relax_rate_on_;
  evidence_frames_ = relaxing ? evidence_frames_ + 1 : 0;
  rest_s_ = rest ? rest_s_ + dt_s : 0.0;
  // Unloaded (|X| ≤ slip_min_shift_m, the least shift an onset needs): any slide it could be in
  // is slower than slip_min_shift_m · c_velocity / c_displacement, one this detector could never
  // call either. At rest for slip_on_frames frames (a contact's first frame counts, its change
  // reads zero) it is confirmed stuck; a loaded contact at rest may be sliding steadily at the
  // friction limit and needs stick_confirm_s. This drops what the velocity proxy read while the
  // contact formed (a growing mask's centroid moves with nothing sliding).
  const bool unloaded = f.shift_m <= min_shift_m_;
  unloaded_rest_frames_ = rest && unloaded ? unloaded_rest_frames_ + 1 : 0;
  if (evidence_frames_ >= on_frames_) {
    slipping_ = true;
    s.onset = true;
    evidence_frames_ = 0;
    peak_shift_m_ = f.shift_m;
  } else if (rest_s_ >= confirm_s_ || unloaded_rest_frames_ >= on_frames_) {
    s.confirmed = true;
  }
  return s;
}

}  // namespace tacse3::dsp
