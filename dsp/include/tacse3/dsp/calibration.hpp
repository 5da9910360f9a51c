// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: per-sensor calibration of the back end (forces, contact, motion proxy, solve).
#pragma once

#include <array>
#include <cstdint>

#include "tacse3/dsp/luma.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// How the calibrated shear field becomes the per-point motion proxy ṽ of paper Sec. IV-C.
enum class VelocityProxy : std::uint8_t {
  // Paper model: the calibrated shear is proportional to the contact velocity,
  // ṽ = c_velocity · shear. Suits the sliding regime.
  kVelocity = 0,
  // The shear's increment between frames is the contact displacement,
  // ṽ = c_displacement · (shear_t − shear_{t−1}) / Δt, over the cells in both frames' Ω: exact
  // kinematics while the contact sticks.
  kDisplacement = 1,
  // Per frame and sensor, a stick/slip detector picks kDisplacement while the contact sticks and
  // kVelocity while it slips (docs/dsp/motion.md). What the velocity proxy would have added while
  // a slip still looked like a stick is paid back once the slip is seen (dsp::SlipPayback).
  kAuto = 2,
};

// Largest moving-average window (frames). Sizes the ring buffer at compile time.
inline constexpr int kMaxMovingAverage = 32;
// Calibration::release_load_rate at or above this turns the release rule off.
inline constexpr double kReleaseRuleOff = 1e4;

// The per-sensor calibration of the back end. Doubles in SI units or dimensionless, converted
// once to each stage's fixed-point format by its configure(). Each field's meaning, unit and range
// are in kCalibrationFields (calibration_fields.hpp), the one schema that validate(), the file
// reader and docs/calibration.md use. The comments here say why a default is what it is.
// "shear unit" = one working-image pixel of calibrated shear; "f^z unit" = the dimensionless
// normal response (relative local expansion when normal_gain_density = 1).
struct Calibration {
  // Contact-point geometry (paper Sec. IV-B, κx = 1/pixel_pitch_m, κy = κx/pixel_aspect_y).
  double pixel_pitch_m = 0.075e-3;
  double pixel_aspect_y = 1.0;
  // The working image's filter (luma.hpp): 0 the 2x2 box, 1 the 4x4 binomial low-pass, for a
  // pattern finer than four sensor pixels per period. tacse3-calibrate sets it.
  int antialias_filter = 0;

  // Normal response f^z = a_G · (−𝒢) + a_div · div(d).
  double normal_gain_density = 1.0;
  double normal_gain_divergence = 0.0;

  // Shear (f^x, f^y) = s_d · d + s_r · r + s_k · k over the NHHD parts (Eq. nhhd). All 1: for a
  // compact contact the natural HHD splits a locally uniform shear about evenly between d and r,
  // and the radial bulge that d also carries is symmetric about the patch, so it drops out of the
  // rotation moments. Calibration fits all three.
  double shear_gain_d = 1.0;
  double shear_gain_r = 1.0;
  double shear_gain_k = 1.0;

  // Contact mask Ω = {filter(f^z) > τ} with hysteresis and a minimum area.
  double contact_tau_on = 0.02;
  double contact_tau_off = 0.01;
  int contact_min_area_cells = 4;

  // Height map z = min(height_gain_m · max(f^z, 0), height_max_m).
  double height_gain_m = 5.0e-3;
  double height_max_m = 2.0e-3;

  VelocityProxy velocity_proxy = VelocityProxy::kVelocity;
  // One working pixel of shear read as one frame's contact displacement at 120 Hz.
  double c_velocity = 2.0 * 0.075e-3 * 120.0;
  // 2 · pixel_pitch_m: exact kinematics, since 1 working px = 2 sensor px. Change it together
  // with pixel_pitch_m.
  double c_displacement = 2.0 * 0.075e-3;

  // Stick/slip detector of kAuto (docs/dsp/motion.md). It watches the planar rigid content of the
  // shear over Ω read as a contact displacement, X = [L·θ, t_x, t_y], smoothed with time constant
  // slip_smoothing_s. A sticking contact's shear is its accumulated displacement and only shrinks
  // if the object moves back; a sliding contact's shear follows the sliding speed with the gel's
  // lag, so it relaxes as the slide slows. An onset is relaxation beyond the contact's relative
  // loss of normal load, for slip_on_frames frames, on a loaded contact.
  double slip_relax_rate_on = 3.0;
  int slip_on_frames = 4;
  double slip_min_shift_m = 20e-6;
  double slip_exit_fraction = 0.25;
  double stick_rest_speed_m_s = 0.05e-3;
  // A slide relaxes within a few gel lag times; a stuck contact holds its shear. So a contact at
  // rest this long is stuck, and a pending payback is dropped.
  double stick_confirm_s = 1.0;
  // The dual pipeline takes the left sensor's value: one payback for the fused twist.
  int slip_catchup_frames = 12;
  // Between the shear content's per-frame noise and the gel's lag.
  double slip_smoothing_s = 0.04;
  // A contact losing normal load this fast is being released: the gel it lets go of springs back,
  // which the displacement proxy would read as the object moving back. Its frames' readings are
  // dropped. Needs a height estimate (height_gain_m > 0); at most 1/slip_smoothing_s, the largest
  // rate the smoothed load can show.
  double release_load_rate = 4.0;

  // Translation from the contact centroid (paper Sec. IV-D). In a slide Ω advances in bursts and
  // the centroid differences telescope, so the mask-change gate is off by default (1); the area
  // gate catches a forming contact, whose centroid jumps with nothing moving, while a sliding
  // patch keeps its area as cells enter at the leading edge and leave at the trailing one.
  double max_mask_change = 1.0;
  double max_mask_area_ratio = 1.5;

  // Per-axis scales of this sensor's estimates in its own frame. The two proxies read the axes
  // differently (exact sticking kinematics vs a drag law), hence a separate factor for the
  // displacement proxy.
  std::array<double, 3> rotation_scale{1.0, 1.0, 1.0};
  std::array<double, 3> translation_scale{1.0, 1.0, 1.0};
  std::array<double, 3> displacement_rotation_ratio{1.0, 1.0, 1.0};

  // Paper Sec. IV-D moving average.
  int moving_average_length = 4;

  // 3x3 solve (solve3.hpp): λ = solve_lambda_rel · tr(AᵀA)/3 + N · solve_lever_floor_m²; a solve
  // is valid when rcond ≥ solve_rcond_min.
  double solve_lambda_rel = 1e-6;
  double solve_lever_floor_m = 1e-5;
  double solve_rcond_min = 1e-4;
};

// kOk, or kBadCalibration if any field is NaN/inf, outside its range or breaks a rule of
// kCalibrationFields / kCalibrationRules (calibration_fields.hpp).
Status validate(const Calibration& cal) noexcept;

// The working image's filter that cal.antialias_filter names.
constexpr WorkImageFilter work_image_filter(const Calibration& cal) noexcept {
  return cal.antialias_filter != 0 ? WorkImageFilter::kBinomial : WorkImageFilter::kBox;
}

}  // namespace tacse3::dsp
