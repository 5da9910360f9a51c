// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: back-end calibration defaults, range validation and Q-format conversion.
#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/contact.hpp"
#include "tacse3/dsp/force_map.hpp"
#include "tacse3/dsp/motion.hpp"

namespace tacse3::dsp {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(Calibration, DefaultsAreValidAndDocumented) {
  const Calibration c;
  EXPECT_EQ(validate(c), Status::kOk);
  EXPECT_DOUBLE_EQ(c.pixel_pitch_m, 0.075e-3);
  // Displacement-mode default is exact kinematics: shear is in working px = 2 sensor px.
  EXPECT_DOUBLE_EQ(c.c_displacement, 2.0 * c.pixel_pitch_m);
  EXPECT_DOUBLE_EQ(c.c_velocity, 2.0 * c.pixel_pitch_m * 120.0);
  EXPECT_LE(c.contact_tau_off, c.contact_tau_on);
  EXPECT_EQ(c.velocity_proxy, VelocityProxy::kVelocity);
  EXPECT_GE(c.moving_average_length, 1);
  EXPECT_LE(c.moving_average_length, kMaxMovingAverage);
}

struct BadCase {
  std::string name;
  std::function<void(Calibration&)> mutate;
};

std::vector<BadCase> bad_cases() {
  std::vector<BadCase> v;
  auto add = [&](std::string n, std::function<void(Calibration&)> f) {
    v.push_back({std::move(n), std::move(f)});
  };
  // NaN / inf in every double field family.
  add("pitch NaN", [](Calibration& c) { c.pixel_pitch_m = kNan; });
  add("pitch inf", [](Calibration& c) { c.pixel_pitch_m = kInf; });
  add("aspect NaN", [](Calibration& c) { c.pixel_aspect_y = kNan; });
  add("normal gain NaN", [](Calibration& c) { c.normal_gain_density = kNan; });
  add("div gain inf", [](Calibration& c) { c.normal_gain_divergence = kInf; });
  add("shear d NaN", [](Calibration& c) { c.shear_gain_d = kNan; });
  add("shear r NaN", [](Calibration& c) { c.shear_gain_r = kNan; });
  add("shear k -inf", [](Calibration& c) { c.shear_gain_k = -kInf; });
  add("tau_on NaN", [](Calibration& c) { c.contact_tau_on = kNan; });
  add("tau_off NaN", [](Calibration& c) { c.contact_tau_off = kNan; });
  add("height NaN", [](Calibration& c) { c.height_gain_m = kNan; });
  add("height max NaN", [](Calibration& c) { c.height_max_m = kNan; });
  add("c_velocity NaN", [](Calibration& c) { c.c_velocity = kNan; });
  add("c_displacement inf", [](Calibration& c) { c.c_displacement = kInf; });
  add("mask change NaN", [](Calibration& c) { c.max_mask_change = kNan; });
  add("area ratio NaN", [](Calibration& c) { c.max_mask_area_ratio = kNan; });
  add("release rate NaN", [](Calibration& c) { c.release_load_rate = kNan; });
  add("rot scale NaN", [](Calibration& c) { c.rotation_scale[1] = kNan; });
  add("trans scale inf", [](Calibration& c) { c.translation_scale[2] = kInf; });
  add("lambda NaN", [](Calibration& c) { c.solve_lambda_rel = kNan; });
  add("lever NaN", [](Calibration& c) { c.solve_lever_floor_m = kNan; });
  add("rcond NaN", [](Calibration& c) { c.solve_rcond_min = kNan; });
  // Negative values.
  add("pitch negative", [](Calibration& c) { c.pixel_pitch_m = -0.075e-3; });
  add("pitch zero", [](Calibration& c) { c.pixel_pitch_m = 0.0; });
  add("normal gain negative", [](Calibration& c) { c.normal_gain_density = -1.0; });
  add("shear gain negative", [](Calibration& c) { c.shear_gain_k = -1.0; });
  add("tau_on negative", [](Calibration& c) { c.contact_tau_on = -0.01; });
  add("tau_off negative", [](Calibration& c) { c.contact_tau_off = -0.01; });
  add("height negative", [](Calibration& c) { c.height_gain_m = -1e-3; });
  add("c_velocity negative", [](Calibration& c) { c.c_velocity = -0.01; });
  add("c_displacement zero", [](Calibration& c) { c.c_displacement = 0.0; });
  add("scale negative", [](Calibration& c) { c.rotation_scale[0] = -1.0; });
  add("min area zero", [](Calibration& c) { c.contact_min_area_cells = 0; });
  add("lambda negative", [](Calibration& c) { c.solve_lambda_rel = -1e-6; });
  // Out of range.
  add("pitch 1 mm", [](Calibration& c) { c.pixel_pitch_m = 1e-3; });
  add("aspect 10", [](Calibration& c) { c.pixel_aspect_y = 10.0; });
  add("gain 1e5", [](Calibration& c) { c.shear_gain_r = 1e5; });
  add("tau_off > tau_on", [](Calibration& c) { c.contact_tau_off = 2.0 * c.contact_tau_on; });
  add("min area > grid", [](Calibration& c) { c.contact_min_area_cells = kGridCount + 1; });
  add("height max 2 cm", [](Calibration& c) { c.height_max_m = 0.02; });
  add("mask change 1.5", [](Calibration& c) { c.max_mask_change = 1.5; });
  add("area ratio below 1", [](Calibration& c) { c.max_mask_area_ratio = 0.99; });
  add("area ratio 1e5", [](Calibration& c) { c.max_mask_area_ratio = 1e5; });
  add("release rate zero", [](Calibration& c) { c.release_load_rate = 0.0; });
  add("release rate 1e5", [](Calibration& c) { c.release_load_rate = 1e5; });
  add("release rate at the smoothing's ceiling", [](Calibration& c) {
    c.slip_smoothing_s = 0.25;
    c.release_load_rate = 4.0;  // ρ_L < 1/0.25 = 4/s: it could never act
  });
  add("scale 1000", [](Calibration& c) { c.translation_scale[0] = 1000.0; });
  add("L = 0", [](Calibration& c) { c.moving_average_length = 0; });
  add("L > max", [](Calibration& c) { c.moving_average_length = kMaxMovingAverage + 1; });
  add("rcond 1", [](Calibration& c) { c.solve_rcond_min = 1.0; });
  add("proxy enum", [](Calibration& c) { c.velocity_proxy = static_cast<VelocityProxy>(7); });
  return v;
}

TEST(Calibration, RejectsNanNegativeAndOutOfRange) {
  for (const BadCase& bc : bad_cases()) {
    Calibration c;
    bc.mutate(c);
    EXPECT_EQ(validate(c), Status::kBadCalibration) << bc.name;
  }
}

TEST(Calibration, RangeBoundsAreInclusiveWhereDocumented) {
  Calibration c;
  c.contact_tau_off = c.contact_tau_on;  // τ_off == τ_on: plain threshold, allowed
  c.contact_min_area_cells = kGridCount;
  c.moving_average_length = kMaxMovingAverage;
  c.height_gain_m = 0.0;  // flat contact points, allowed
  c.max_mask_change = 1.0;
  c.max_mask_area_ratio = 1.0;  // every area change reads the material points, allowed
  EXPECT_EQ(validate(c), Status::kOk);
  c.max_mask_area_ratio = 1e4;  // off
  EXPECT_EQ(validate(c), Status::kOk);
  c.release_load_rate = kReleaseRuleOff;  // off, whatever the smoothing
  c.slip_smoothing_s = 1.0;
  EXPECT_EQ(validate(c), Status::kOk);
  c.release_load_rate = 0.999;  // below 1/slip_smoothing_s
  EXPECT_EQ(validate(c), Status::kOk);
  c.release_load_rate = 1e-3;
  EXPECT_EQ(validate(c), Status::kOk);
  c.slip_smoothing_s = 0.0;  // no smoothing, no ceiling: any rate up to 1e4
  c.release_load_rate = 9999.0;
  EXPECT_EQ(validate(c), Status::kOk);
}

TEST(Calibration, StagesRejectBadCalibrationAndKeepTheirGains) {
  Calibration good;
  good.normal_gain_density = 1.5;
  ForceMap fm;
  ASSERT_EQ(fm.configure(good), Status::kOk);
  // Converted once to Q16 at configure time: 1.5 · 2^16.
  EXPECT_EQ(fm.normal_gain_density_q16(), 98304);
  EXPECT_EQ(fm.normal_gain_divergence_q16(), 0);
  for (const BadCase& bc : bad_cases()) {
    Calibration bad = good;
    bc.mutate(bad);
    EXPECT_EQ(fm.configure(bad), Status::kBadCalibration) << bc.name;
    EXPECT_EQ(fm.normal_gain_density_q16(), 98304) << bc.name;
  }
  ContactDetector cd;
  MotionEstimator me;
  Calibration nan_cal;
  nan_cal.contact_tau_on = kNan;
  EXPECT_EQ(cd.configure(nan_cal), Status::kBadCalibration);
  EXPECT_EQ(me.configure(nan_cal), Status::kBadCalibration);
  EXPECT_EQ(cd.configure(good), Status::kOk);
  EXPECT_EQ(me.configure(good), Status::kOk);
}

}  // namespace
}  // namespace tacse3::dsp
