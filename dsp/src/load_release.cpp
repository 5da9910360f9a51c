// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the release rule's load rate (see load_release.hpp).
#include "tacse3/dsp/load_release.hpp"

namespace tacse3::dsp {

void LoadRelease::configure(const Calibration& cal) noexcept {
  smoothing_s_ = cal.slip_smoothing_s;
  release_load_rate_ = cal.release_load_rate;
}

void LoadRelease::reset() noexcept {
  load_ = 0.0;
  load_change_ = 0.0;
}

double LoadRelease::update(double load, bool had_previous, double previous_load,
                           double dt_s) noexcept {
  const double alpha = smoothing_s_ > 0.0 ? dt_s / (smoothing_s_ + dt_s) : 1.0;
  load_change_ =
      had_previous ? load_change_ + alpha * ((load - previous_load) - load_change_) : 0.0;
  load_ = had_previous ? load_ + alpha * (load - load_) : load;
  return load_ > 0.0 ? -load_change_ / (load_ * dt_s) : 0.0;
}

}  // namespace tacse3::dsp
