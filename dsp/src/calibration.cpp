// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: validation of the back-end calibration ranges.
#include "tacse3/dsp/calibration.hpp"

#include <cmath>

namespace tacse3::dsp {
namespace {

// Closed range check that also rejects NaN and infinities (NaN fails every comparison).
bool in_range(double v, double lo, double hi) noexcept {
  return std::isfinite(v) && v >= lo && v <= hi;
}
// Half-open (lo, hi]: strictly positive quantities.
bool in_range_open_lo(double v, double lo, double hi) noexcept {
  return std::isfinite(v) && v > lo && v <= hi;
}

}  // namespace

Status validate(const Calibration& c) noexcept {
  bool ok = true;
  ok = ok && in_range(c.pixel_pitch_m, 1e-6, 2e-4);
  ok = ok && in_range(c.pixel_aspect_y, 0.25, 4.0);
  ok = ok && in_range(c.normal_gain_density, 0.0, 1e4);
  ok = ok && in_range(c.normal_gain_divergence, 0.0, 1e4);
  ok = ok && in_range(c.shear_gain_d, 0.0, 1e4);
  ok = ok && in_range(c.shear_gain_r, 0.0, 1e4);
  ok = ok && in_range(c.shear_gain_k, 0.0, 1e4);
  ok = ok && in_range_open_lo(c.contact_tau_on, 0.0, 1e4);
  ok = ok && in_range(c.contact_tau_off, 0.0, 1e4) && c.contact_tau_off <= c.contact_tau_on;
  ok = ok && c.contact_min_area_cells >= 1 && c.contact_min_area_cells <= kGridCount;
  ok = ok && in_range(c.height_gain_m, 0.0, 1.0);
  ok = ok && in_range(c.height_max_m, 0.0, 1e-2);
  ok = ok && (c.velocity_proxy == VelocityProxy::kVelocity ||
              c.velocity_proxy == VelocityProxy::kDisplacement ||
              c.velocity_proxy == VelocityProxy::kAuto);
  ok = ok && in_range_open_lo(c.slip_relax_rate_on, 0.0, 1e3);
  ok = ok && c.slip_on_frames >= 1 && c.slip_on_frames <= 1000;
  ok = ok && in_range(c.slip_min_shift_m, 0.0, 0.01);
  ok = ok && in_range(c.slip_exit_fraction, 0.0, 1.0);
  ok = ok && in_range_open_lo(c.stick_rest_speed_m_s, 0.0, 1.0);
  ok = ok && in_range(c.stick_confirm_s, 0.0, 10.0);
  ok = ok && c.slip_catchup_frames >= 1 && c.slip_catchup_frames <= 1000;
  ok = ok && in_range(c.slip_smoothing_s, 0.0, 1.0);
  ok = ok && in_range_open_lo(c.release_load_rate, 0.0, kReleaseRuleOff);
  // The smoothed ρ_L cannot exceed 1/slip_smoothing_s: a rate at or above it would never act.
  ok = ok &&
       (c.release_load_rate >= kReleaseRuleOff || c.release_load_rate * c.slip_smoothing_s < 1.0);
  ok = ok && in_range_open_lo(c.c_velocity, 0.0, 100.0);
  ok = ok && in_range_open_lo(c.c_displacement, 0.0, 1.0);
  ok = ok && in_range(c.max_mask_change, 0.0, 1.0);
  ok = ok && in_range(c.max_mask_area_ratio, 1.0, 1e4);
  for (int a = 0; a < 3; ++a) {
    ok = ok && in_range(c.rotation_scale[static_cast<std::size_t>(a)], 0.0, 100.0);
    ok = ok && in_range(c.translation_scale[static_cast<std::size_t>(a)], 0.0, 100.0);
    ok = ok && in_range(c.displacement_rotation_ratio[static_cast<std::size_t>(a)], 0.0, 100.0);
  }
  ok = ok && c.moving_average_length >= 1 && c.moving_average_length <= kMaxMovingAverage;
  ok = ok && in_range(c.solve_lambda_rel, 0.0, 1.0);
  ok = ok && in_range(c.solve_lever_floor_m, 0.0, 1e-2);
  ok =
      ok && std::isfinite(c.solve_rcond_min) && c.solve_rcond_min >= 0.0 && c.solve_rcond_min < 1.0;
  return ok ? Status::kOk : Status::kBadCalibration;
}

}  // namespace tacse3::dsp
