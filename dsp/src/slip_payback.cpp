// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: slip payback of the fused velocity-proxy deficit (see slip_payback.hpp).
#include "tacse3/dsp/slip_payback.hpp"

namespace tacse3::dsp {

void SlipPayback::configure(int catchup_frames) noexcept {
  catchup_frames_ = catchup_frames < 1 ? 1 : catchup_frames;
  if (left_ > catchup_frames_) left_ = catchup_frames_;
}

void SlipPayback::reset() noexcept {
  left_ = 0;
  deficit_.setZero();
}

Vector6d SlipPayback::update(const Frame& f, double dt_s) noexcept {
  if (!f.contact || !(dt_s > 0.0)) {
    reset();
    return f.chosen;
  }
  // This frame still used the proxies decided before it: book what the velocity proxy adds.
  if (f.differs) deficit_ += (f.velocity - f.chosen) * dt_s;
  if (f.confirmed && left_ == 0) {
    // A confirmed stick: what the velocity proxy read was the grasp's residual shear. A payback
    // under way is a slide already detected, so a stick confirmed after it does not cut it.
    reset();
    return f.chosen;
  }
  if (f.onset) left_ = catchup_frames_;  // a second sensor's onset restarts the spread
  if (left_ == 0) return f.chosen;
  const Vector6d pay = deficit_ / static_cast<double>(left_);
  deficit_ -= pay;
  --left_;
  return f.chosen + pay / dt_s;
}

}  // namespace tacse3::dsp
