// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: dsp::SlipDetector's decision rules on synthetic feature sequences (the whole
// estimator on rendered shear is in test_slip_detector.cpp).
#include <gtest/gtest.h>

#include <cmath>

#include "tacse3/dsp/slip_detector.hpp"

namespace tacse3::dsp {
namespace {

constexpr double kDt = 1.0 / 120.0;

Calibration detector_calibration() {
  Calibration cal;
  cal.slip_relax_rate_on = 3.0;
  cal.slip_on_frames = 4;
  cal.slip_min_shift_m = 20e-6;
  cal.slip_exit_fraction = 0.25;
  cal.stick_rest_speed_m_s = 0.05e-3;
  cal.stick_confirm_s = 1.0;
  cal.slip_smoothing_s = 0.0;  // unsmoothed: the features are the inputs, checked exactly
  cal.release_load_rate = 4.0;
  return cal;
}

// Shear content X = [0, x, 0] (a uniform shear along x) and its change.
Eigen::Vector3d along_x(double x) {
  return Eigen::Vector3d(0.0, x, 0.0);
}

TEST(SlipDetectorRules, FeaturesAreTheRelativeRelaxationOfTheContent) {
  SlipDetector d;
  d.configure(detector_calibration());
  d.reset();
  (void)d.update(along_x(100e-6), along_x(0.0), 0.0, kDt);
  (void)d.update(along_x(99e-6), along_x(-1e-6), 0.5, kDt);
  const SlipDetector::Features& f = d.features();
  EXPECT_DOUBLE_EQ(f.shift_m, 99e-6);
  EXPECT_DOUBLE_EQ(f.rate_m_s, 1e-6 / kDt);
  EXPECT_DOUBLE_EQ(f.relax_rate, 1e-6 / (99e-6 * kDt));  // ρ = −X·dX / (|X|² Δt)
  EXPECT_DOUBLE_EQ(f.load_drop_rate, 0.5);
}

// A stick motion loads the gel (ρ < 0) and holds it: no onset, and the stick is confirmed once
// the contact has rested for stick_confirm_s.
TEST(SlipDetectorRules, ALoadHeldAtRestIsConfirmedStuckAfterTheConfirmTime) {
  SlipDetector d;
  const Calibration cal = detector_calibration();
  d.configure(cal);
  d.reset();
  double x = 0.0;
  for (int k = 0; k < 60; ++k) {  // 0.5 s ramp at 1 mm/s
    x += 1e-3 * kDt;
    const SlipDetector::Step s = d.update(along_x(x), along_x(1e-3 * kDt), 0.0, kDt);
    EXPECT_FALSE(s.onset || s.confirmed) << k;
  }
  int confirmed_at = -1;
  for (int k = 0; k < 200 && confirmed_at < 0; ++k) {
    const SlipDetector::Step s = d.update(along_x(x), along_x(0.0), 0.0, kDt);
    EXPECT_FALSE(s.onset);
    if (s.confirmed) confirmed_at = k;
  }
  // rest_s accumulates Δt per frame from the first frame at rest: confirmed on the frame where
  // k + 1 frames reach 1 s (floating sums of 1/120 may land one frame either side).
  const int expected = static_cast<int>(std::lround(cal.stick_confirm_s / kDt)) - 1;
  EXPECT_NEAR(confirmed_at, expected, 1);
  EXPECT_FALSE(d.slipping());
}

// A held shear that relaxes at ρ = 10/s (> slip_relax_rate_on) starts a slip after exactly
// slip_on_frames frames; once at rest below slip_exit_fraction of the peak, the slip ends.
TEST(SlipDetectorRules, RelaxationStartsASlipAfterOnFramesAndRestBelowTheExitEndsIt) {
  SlipDetector d;
  const Calibration cal = detector_calibration();
  d.configure(cal);
  d.reset();
  const double x0 = 300e-6;
  (void)d.update(along_x(x0), along_x(0.0), 0.0, kDt);
  const double decay = std::exp(-10.0 * kDt);
  double x = x0;
  int onset_at = -1;
  for (int k = 0; k < 10 && onset_at < 0; ++k) {
    const double next = x * decay;
    if (d.update(along_x(next), along_x(next - x), 0.0, kDt).onset) onset_at = k;
    x = next;
  }
  EXPECT_EQ(onset_at, cal.slip_on_frames - 1);
  ASSERT_TRUE(d.slipping());
  // Decay on until at rest: the slide ends on the first frame both at rest and at most a quarter
  // of the peak (the peak is the content at the onset).
  const double peak = x;
  bool ended = false;
  for (int k = 0; k < 2000 && !ended; ++k) {
    const double next = x * decay;
    ended = d.update(along_x(next), along_x(next - x), 0.0, kDt).ended;
    if (ended) {
      EXPECT_LT(std::abs(next - x) / kDt, cal.stick_rest_speed_m_s);
      EXPECT_LE(next, cal.slip_exit_fraction * peak);
    }
    x = next;
  }
  EXPECT_TRUE(ended);
  EXPECT_FALSE(d.slipping());
}

// The same relaxation while the load falls faster than release_load_rate is a release: no onset.
// With the load falling at 8/s under a rate of 9/s, ρ − ρ_L ≈ 2.4/s stays below the 3/s onset.
TEST(SlipDetectorRules, RelaxationWithTheLoadIsNotASlip) {
  for (const double load_drop : {5.0, 8.0}) {
    SlipDetector d;
    Calibration cal = detector_calibration();
    cal.release_load_rate = load_drop == 5.0 ? 4.0 : 9.0;
    d.configure(cal);
    d.reset();
    double x = 300e-6;
    (void)d.update(along_x(x), along_x(0.0), 0.0, kDt);
    const double decay = std::exp(-10.0 * kDt);
    for (int k = 0; k < 40; ++k) {
      const double next = x * decay;
      EXPECT_FALSE(d.update(along_x(next), along_x(next - x), load_drop, kDt).onset) << load_drop;
      x = next;
    }
  }
}

// An unloaded contact (|X| ≤ slip_min_shift_m) at rest is confirmed after slip_on_frames frames,
// its first frame counting.
TEST(SlipDetectorRules, AnUnloadedContactAtRestIsConfirmedAfterOnFrames) {
  SlipDetector d;
  const Calibration cal = detector_calibration();
  d.configure(cal);
  d.reset();
  for (int k = 0; k < cal.slip_on_frames; ++k) {
    const SlipDetector::Step s = d.update(along_x(5e-6), along_x(0.0), 0.0, kDt);
    EXPECT_EQ(s.confirmed, k == cal.slip_on_frames - 1) << k;
  }
}

TEST(SlipDetectorRules, AFollowedDecisionSetsAndClearsTheSlip) {
  SlipDetector d;
  d.configure(detector_calibration());
  d.reset();
  d.observe(along_x(100e-6), along_x(0.0), 0.0, kDt);
  d.set_slipping(true);
  EXPECT_TRUE(d.slipping());
  EXPECT_DOUBLE_EQ(d.features().shift_m, 100e-6);  // features kept
  d.set_slipping(false);                           // a slide that ended: the state restarts
  EXPECT_FALSE(d.slipping());
  // Restarted: the next frame's content is its own X, with no change (as on a first frame).
  (void)d.update(along_x(50e-6), along_x(-50e-6), 0.0, kDt);
  EXPECT_DOUBLE_EQ(d.features().shift_m, 50e-6);
  EXPECT_DOUBLE_EQ(d.features().rate_m_s, 0.0);
}

}  // namespace
}  // namespace tacse3::dsp
