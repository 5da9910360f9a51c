// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the calibration's pre-contact noise estimate, coverage rules and check tolerance.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "tacse3/tools/calibration_check.hpp"
#include "tacse3/tools/contact_noise.hpp"

namespace {

namespace tt = tacse3::tools;

constexpr std::size_t kPoints = 2400;  // two pads' 40x30 grids

// Gaussian noise of σ on every point, plus `blob` points at `height` (a contact).
std::vector<double> frame(std::mt19937& rng, double sigma, std::size_t blob, double height) {
  std::normal_distribution<double> n(0.0, sigma);
  std::vector<double> v(kPoints);
  for (std::size_t i = 0; i < kPoints; ++i) v[i] = n(rng) + (i < blob ? height : 0.0);
  return v;
}

TEST(PreContactNoise, MeasuresTheNoiseBeforeTheOnsetOnly) {
  std::mt19937 rng(1);
  tt::PreContactNoise z;
  z.add_frame(0, std::vector<double>(kPoints, 0.0));  // the reference: skipped
  for (std::size_t i = 1; i <= 20; ++i) z.add_frame(i, frame(rng, 0.004, 0, 0.0));
  // A contact covering most of the grid from frame 21 on: a share-of-the-grid estimate would
  // take it for noise.
  for (std::size_t i = 21; i <= 40; ++i) z.add_frame(i, frame(rng, 0.004, 2000, 0.2));
  ASSERT_TRUE(z.onset_found());
  EXPECT_EQ(z.onset_frame(), 21u);
  EXPECT_EQ(z.quiet_frames(), 20u);
  // 48000 samples: the MAD's standard error is about 0.5 %.
  EXPECT_NEAR(z.sigma(), 0.004, 0.004 * 0.03);
  EXPECT_NEAR(z.median(), 0.0, 1e-4);
}

TEST(PreContactNoise, AFrameOrTwoOverTheBarAreNoiseNotAnOnset) {
  std::mt19937 rng(2);
  tt::PreContactNoise z;
  for (std::size_t i = 1; i <= 10; ++i) z.add_frame(i, frame(rng, 0.004, 0, 0.0));
  for (std::size_t i = 11; i <= 12; ++i) z.add_frame(i, frame(rng, 0.004, 1, 1.0));  // spikes
  for (std::size_t i = 13; i <= 20; ++i) z.add_frame(i, frame(rng, 0.004, 0, 0.0));
  EXPECT_FALSE(z.onset_found());
  EXPECT_EQ(z.quiet_frames(), 20u);
  for (std::size_t i = 21; i <= 23; ++i) z.add_frame(i, frame(rng, 0.004, 30, 0.1));
  ASSERT_TRUE(z.onset_found());
  EXPECT_EQ(z.onset_frame(), 21u);
  EXPECT_NEAR(z.sigma(), 0.004, 0.004 * 0.05);
}

TEST(PreContactNoise, NoOnsetWithoutAContactThatForms) {
  // A recording that starts mid-contact: frame 0 holds the contact, so the later frames show
  // the noise alone and no onset.
  std::mt19937 rng(3);
  tt::PreContactNoise z;
  for (std::size_t i = 1; i <= 50; ++i) z.add_frame(i, frame(rng, 0.004, 0, 0.0));
  EXPECT_FALSE(z.onset_found());
  EXPECT_EQ(z.quiet_frames(), 50u);
}

// The motions of a set that only translates.
tt::MotionContent translations() {
  tt::MotionContent m;
  m.set(tt::Motion::kTx);
  m.set(tt::Motion::kTy);
  m.set(tt::Motion::kSlide);
  m.set(tt::Motion::kStick);
  m.set(tt::Motion::kPadsOpen);
  m.set(tt::Motion::kStickTranslation);
  return m;
}

TEST(Coverage, OnlyTranslationsLackTheThreeRotations) {
  const auto missing = tt::missing_motions({translations()}, true);
  ASSERT_EQ(missing.size(), 3u);
  EXPECT_EQ(missing[0]->motion, tt::Motion::kRx);
  EXPECT_EQ(missing[1]->motion, tt::Motion::kRy);
  EXPECT_EQ(missing[2]->motion, tt::Motion::kRz);
  const std::string msg = tt::coverage_message(missing);
  EXPECT_NE(msg.find("rotation_scale x"), std::string::npos) << msg;
  EXPECT_NE(msg.find("record a rotation about z"), std::string::npos) << msg;
}

TEST(Coverage, TheRegimeRulesWaitForTheFit) {
  tt::MotionContent m;
  for (auto k :
       {tt::Motion::kRx, tt::Motion::kRy, tt::Motion::kRz, tt::Motion::kTx, tt::Motion::kTy})
    m.set(k);
  // The pixel pitch's rule is decided by the truth too: waived when the pitch is given.
  const auto pitch = tt::missing_motions({m}, false);
  ASSERT_EQ(pitch.size(), 1u);
  EXPECT_EQ(pitch[0]->motion, tt::Motion::kStickTranslation);
  EXPECT_TRUE(tt::missing_motions({m}, false, true).empty());
  m.set(tt::Motion::kStickTranslation);
  EXPECT_TRUE(tt::missing_motions({m}, false).empty());
  const auto missing = tt::missing_motions({m}, true);
  ASSERT_EQ(missing.size(), 3u);  // slide, stick, pads open
  m.set(tt::Motion::kSlide);
  tt::MotionContent stick;
  stick.set(tt::Motion::kStick);
  stick.set(tt::Motion::kPadsOpen);
  EXPECT_TRUE(tt::missing_motions({m, stick}, true).empty());
  EXPECT_EQ(tt::coverage_message({}), "");
}

TEST(CheckTolerance, QuarterOfTheMotionAtThePadsWithAOnePixelFloor) {
  tt::SourceInfo info;
  info.pixel_pitch_mm = 0.1;
  info.finger_separation_mm = 38.0;
  const double deg = 180.0 / std::acos(-1.0);
  // 30 deg: 0.5236 rad · 19 mm = 9.95 mm at the pads.
  tt::CheckTolerance t = tt::check_tolerance(info, 30.0, 0.0);
  EXPECT_NEAR(t.rotation_deg, 7.5, 1e-9);
  EXPECT_NEAR(t.translation_mm, 0.25 * 30.0 / deg * 19.0, 1e-9);
  // 10 mm: 2.5 mm, and 2.5 mm / 19 mm in rotation.
  t = tt::check_tolerance(info, 0.0, 10.0);
  EXPECT_NEAR(t.translation_mm, 2.5, 1e-9);
  EXPECT_NEAR(t.rotation_deg, 2.5 / 19.0 * deg, 1e-9);
  // No motion: one pixel, and one pixel at 19 mm.
  t = tt::check_tolerance(info, 0.0, 0.0);
  EXPECT_NEAR(t.translation_mm, 0.1, 1e-12);
  EXPECT_NEAR(t.rotation_deg, 0.1 / 19.0 * deg, 1e-9);
}

TEST(RecordingCheck, FailsWithoutValidFramesAndOutsideTheTolerance) {
  tt::RecordingCheck c;
  c.tolerance = {1.0, 0.1};
  c.frames = 100;
  c.valid_frames = 0;
  EXPECT_FALSE(c.passed());
  EXPECT_NE(c.reason().find("no valid frame"), std::string::npos);
  c.valid_frames = 80;
  c.rotation_error_deg = 0.99;
  c.translation_error_mm = 0.1;
  EXPECT_TRUE(c.passed());
  c.rotation_error_deg = 1.01;
  EXPECT_EQ(c.reason(), "rotation off by 1.01 deg (tolerance 1.00 deg)");
  c.rotation_error_deg = std::nan("");
  EXPECT_FALSE(c.passed());
}

}  // namespace
