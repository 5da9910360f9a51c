// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: per-sensor calibration of the back end (forces, contact, motion proxy, solve).
#pragma once

#include <array>
#include <cstdint>

#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// How the calibrated shear field becomes the per-point motion proxy ṽ of paper Sec. IV-C.
enum class VelocityProxy : std::uint8_t {
  // Paper model: the calibrated shear is proportional to the contact velocity,
  // ṽ = c_velocity · shear. Suits the sliding regime.
  kVelocity = 0,
  // The increment of the shear field between consecutive frames is the contact displacement,
  // ṽ = c_displacement · (shear_t − shear_{t−1}) / Δt, over the cells in both frames' Ω. Exact
  // kinematics while the contact sticks.
  kDisplacement = 1,
  // Per frame and per sensor: a stick/slip detector (motion.hpp, docs/dsp.md "Stick/slip
  // detector") picks kDisplacement while the contact sticks and kVelocity while it slips, with
  // the thresholds below. What the velocity proxy would have added while a slip still looked like
  // a stick is paid back in the fused twist over slip_catchup_frames once the slip is detected
  // (no pose jump; dsp::SlipPayback).
  kAuto = 2,
};

// Largest moving-average window (frames). Sizes the ring buffer at compile time.
inline constexpr int kMaxMovingAverage = 32;
// Calibration::release_load_rate at or above this turns the release rule off entirely
// (docs/dsp.md §4.2b).
inline constexpr double kReleaseRuleOff = 1e4;

// All fields are doubles in SI units (or dimensionless); they are validated by validate() and
// converted once to the fixed-point formats of the per-grid stages by each stage's configure().
// "shear unit" = one working-image pixel of calibrated shear (shear gains of 1 keep the NHHD
// parts' unit); "f^z unit" = the dimensionless normal response (relative local expansion when
// normal_gain_density = 1). Ranges are the ones validate() enforces.
struct Calibration {
  // --- contact-point geometry (paper Sec. IV-B, κx = 1/pixel_pitch_m, κy = κx/pixel_aspect_y)
  double pixel_pitch_m = 0.075e-3;  // sensor pixel → metres along x. [1e-6, 2e-4]
  double pixel_aspect_y = 1.0;      // pitch_y / pitch_x. [0.25, 4]

  // --- normal response f^z = a_G · (−𝒢) + a_div · div(d)   (dimensionless inputs)
  double normal_gain_density = 1.0;     // per unit of −𝒢. [0, 1e4]
  double normal_gain_divergence = 0.0;  // per unit of div d (working px / working px). [0, 1e4]

  // --- shear (f^x, f^y) = s_d · d + s_r · r + s_k · k  (Eq. nhhd parts, working px)
  // Default 1: for a compact contact the natural HHD splits a locally uniform shear about evenly
  // between d and r (measured in tests/dsp/test_pipeline.cpp: dropping d halves the in-plane
  // kinematics of a rotation about the finger axis), while the radial bulge of the indentation
  // that d also carries is symmetric about the patch and drops out of the rotation moments.
  // The calibration tool fits all three gains.
  double shear_gain_d = 1.0;  // [0, 1e4]
  double shear_gain_r = 1.0;  // [0, 1e4]
  double shear_gain_k = 1.0;  // [0, 1e4]

  // --- contact mask Ω = {filter(f^z) > τ} with hysteresis and a minimum area
  double contact_tau_on = 0.02;    // new cells need filter(f^z) > τ_on. (0, 1e4]
  double contact_tau_off = 0.01;   // cells of last frame's Ω stay while > τ_off. [0, τ_on]
  int contact_min_area_cells = 4;  // smaller 4-connected components are dropped. [1, kGridCount]

  // --- height map z = g(f^z) = min(height_gain_m · max(f^z, 0), height_max_m)
  double height_gain_m = 5.0e-3;  // metres per f^z unit. [0, 1]
  double height_max_m = 2.0e-3;   // clamp. [0, 0.01]

  // --- velocity proxy (issue item 12)
  VelocityProxy velocity_proxy = VelocityProxy::kVelocity;
  // m/s per shear unit. Default: one working pixel of shear read as one frame's contact
  // displacement at 120 Hz, 2 · 0.075 mm · 120 Hz. (0, 100]
  double c_velocity = 2.0 * 0.075e-3 * 120.0;
  // metres per shear unit. Default 2 · pixel_pitch_m: exact kinematics, since shear is in
  // working pixels (1 working px = 2 sensor px). Change it together with pixel_pitch_m. (0, 1]
  double c_displacement = 2.0 * 0.075e-3;

  // --- stick/slip detector of kAuto (docs/dsp.md "Stick/slip detector"). The detector looks at
  // the planar rigid-body content of the shear field over Ω read as a contact displacement
  // (c_displacement scaling): X = [L·θ, t_x, t_y], the rotation θ about the pad normal times the
  // contact's rms lever L and the mean shift t (motion.hpp planar_content), smoothed
  // exponentially with time constant slip_smoothing_s; dX is its change per frame, read from the
  // shear increments over the cells in both masks, Ω_t ∩ Ω_{t−1}, and smoothed alike.
  // Slip onset: the shear relaxes while loaded, ρ = −X·dX / (|X|² Δt) > slip_relax_rate_on for
  // slip_on_frames consecutive frames with |X| > slip_min_shift_m. Only relaxation beyond the
  // contact's relative loss of normal load counts (ρ − max(0, ρ_L)), and no frame whose load
  // falls faster than release_load_rate (a contact being released, below). A sticking contact's
  // shear is the accumulated contact displacement and only shrinks if the object moves back; a
  // sliding contact's shear follows the sliding speed with the gel's lag, so it relaxes as the
  // slide slows and when it ends. Ranges: (0, 1e3] 1/s, [1, 1000], [0, 0.01] m.
  double slip_relax_rate_on = 3.0;
  int slip_on_frames = 4;
  double slip_min_shift_m = 20e-6;
  // Slip end: |X| fell below slip_exit_fraction of its peak during the slip and the field is at
  // rest, |dX|/Δt < stick_rest_speed_m_s. [0, 1], (0, 1] m/s.
  double slip_exit_fraction = 0.25;
  double stick_rest_speed_m_s = 0.05e-3;
  // A sticking contact whose shear content stayed at rest (|dX|/Δt < stick_rest_speed_m_s) for
  // stick_confirm_s ([0, 10] s) is confirmed stuck; once every sensor in contact is, the pending
  // payback is dropped (unless a payback is under way): a slide relaxes within a few lag times of
  // the gel, a stuck contact holds its shear. An unloaded contact (|X| ≤ slip_min_shift_m, so
  // sliding, if at all, slower than slip_min_shift_m · c_velocity / c_displacement) at rest is
  // confirmed after slip_on_frames frames, so its grasp is not paid back as motion; the two onset
  // thresholds thus also set this confirmation.
  double stick_confirm_s = 1.0;
  // Frames over which the deficit (what the velocity proxy would have added while the slip still
  // looked like a stick) is paid back after a slip onset, so the pose catches up without a jump.
  // The dual pipeline uses the left sensor's value (one payback for the fused twist). [1, 1000].
  int slip_catchup_frames = 12;
  // Time constant of the smoothing of X (s): the per-frame noise of the shear field's rigid
  // content is ~10 µm, the gel's lag (which a slide's relaxation follows) ~50 ms. [0, 1].
  double slip_smoothing_s = 0.04;

  // A contact that sticks while its normal load Σ z over Ω falls faster than this relative rate
  // (1/s; ρ_L = −EMA(L_t − L_{t−1}) / (EMA(L) Δt), EMA with slip_smoothing_s) is being released:
  // the gel it lets go of springs back, which the displacement proxy read as the object moving
  // back (a 2° stick rotation of a sphere ended 1.43° off as the pads opened), and whose
  // relaxation started false slips. Its frames' chosen readings are dropped and count
  // towards no slip onset, and the onset counts only relaxation beyond ρ_L. A held grasp's load
  // stays: ≤ 2.7/s in the simulator's stick motions, ≤ 4.8/s in its slides whose contact stays
  // (5.7/s for two frames as a screwdriver handle's flute passes); releases over 0.3 s reach the
  // smoothing's ceiling (ρ_L ≤ 1/slip_smoothing_s, 25/s by default) (docs/dsp.md
  // §4.2b). (0, 1/slip_smoothing_s), or ≥ kReleaseRuleOff (1e4) for off; at most 1e4. Needs a
  // height estimate (height_gain_m > 0): without one L = 0 and the rule never acts.
  double release_load_rate = 4.0;

  // --- translation (contact-centroid displacement, paper Sec. IV-D)
  // If the mask changes by more than this fraction between frames (1 − Jaccard index), the
  // sliding rule's mask-centroid displacement is replaced by the mean displacement of the
  // material points in both masks, so area changes do not produce spikes. [0, 1]; 1 = off, the
  // default: in a slide Ω advances in bursts (a third of its cells in one frame) and the gate
  // dropped that motion (the material points stand still while the object slides), while the
  // centroid differences telescope (docs/dsp.md §4.1). A sticking contact (kDisplacement, kAuto
  // while sticking) reads the material points anyway. Worth setting (e.g. 0.3) only with
  // kVelocity on contacts dominated by pressing rather than sliding.
  double max_mask_change = 1.0;
  // If the mask's area changes by more than this factor between frames (the larger cell count
  // over the smaller), the sliding rule's centroid step is replaced by the mean displacement of
  // the material points in both masks, as for max_mask_change. A forming contact grows by up to
  // 13.5x in one frame (a flat face is first seen at a corner), and its centroid then jumps by
  // millimetres with nothing moving; a sliding patch keeps its area, cells entering at the
  // leading edge as others leave the trailing one (at most 1.25x in one frame on the
  // simulator's slides measured in docs/dsp.md §4.1, a margin of 1.2x). The rule is
  // symmetric, so a contact vanishing as fast is read the same way (not measured: the
  // recordings end in a hold). [1, 1e4], inclusive; 1e4 = off.
  double max_mask_area_ratio = 1.5;

  // --- per-axis scales applied to this sensor's estimates, in its own frame. [0, 100]
  std::array<double, 3> rotation_scale{1.0, 1.0, 1.0};
  std::array<double, 3> translation_scale{1.0, 1.0, 1.0};
  // Per-axis factor on rotation_scale for the frames that use the displacement proxy: the two
  // proxies read the axes differently (the displacement proxy follows the gel's exact sticking
  // kinematics, the velocity proxy a drag law), so one set of axis scales cannot serve both.
  // 1 = the same scales. [0, 100]
  std::array<double, 3> displacement_rotation_ratio{1.0, 1.0, 1.0};

  // --- temporal smoothing (paper Sec. IV-D moving average). [1, kMaxMovingAverage]
  int moving_average_length = 4;

  // --- 3x3 solve regularisation (solve3.hpp): λ = solve_lambda_rel · tr(AᵀA)/3
  //     + N · solve_lever_floor_m², validity needs rcond ≥ solve_rcond_min.
  double solve_lambda_rel = 1e-6;     // [0, 1]
  double solve_lever_floor_m = 1e-5;  // [0, 1e-2]
  double solve_rcond_min = 1e-4;      // [0, 1)
};

// kOk, or kBadCalibration if any field is NaN/inf or outside the range documented above
// (including τ_off > τ_on, an unknown velocity_proxy value and the detector ranges).
Status validate(const Calibration& cal) noexcept;

}  // namespace tacse3::dsp
