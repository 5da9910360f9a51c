// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: one pad's image stages and their hand-off to the DSP thread.
#include "tacse3/firmware/pad_stager.hpp"

namespace tacse3::firmware {

void PadStager::stage(const ArrivedFrame& f, StagedFrame& out) noexcept {
  out.arrived = f;
  out.staged = false;
  out.stage_us = 0;
  if (f.frame.timestamp_ns > last_t_ns_.load(std::memory_order_acquire)) {
    apply_calibration();
    tare_taken_ = tare_requested_.load(std::memory_order_acquire);
    const std::int64_t t0 = clock_();
    sensor_.process_image(f.frame.view, out.stages);
    out.stage_us = (clock_() - t0) / 1000;
    out.staged = true;
    if (view_ != nullptr && view_state_.load(std::memory_order_acquire) == kViewWanted) {
      viewer::fill_view_pad_fields(sensor_.fields(), view_);
      view_contact_cells_ = sensor_.fields().contact.count;
      view_state_.store(kViewFilled, std::memory_order_release);
    }
  }
  out.tare_epoch = tare_applied_;
  out.calibration_epoch = calibration_applied_;
}

void PadStager::run_deferred() noexcept {
  sensor_.run_deferred();
  if (tare_taken_ != tare_applied_) {
    sensor_.tare_image();  // the frame just handed on becomes the reference
    tare_applied_ = tare_taken_;
  }
}

void PadStager::apply_calibration() noexcept {
  int posted = kPosted;
  if (calibration_state_.compare_exchange_strong(posted, kBusy, std::memory_order_acquire)) {
    (void)sensor_.set_image_calibration(calibration_);  // validated by the DSP thread
    calibration_applied_ = calibration_posted_;
    calibration_state_.store(kIdle, std::memory_order_release);
  }
}

std::uint32_t PadStager::request_calibration(const dsp::Calibration& cal,
                                             bool after_taken) noexcept {
  int state = kPosted;
  if (!calibration_state_.compare_exchange_strong(state, kBusy, std::memory_order_acquire)) {
    state = kIdle;
    if (!after_taken ||
        !calibration_state_.compare_exchange_strong(state, kBusy, std::memory_order_acquire)) {
      return 0;
    }
  }
  calibration_ = cal;
  ++calibration_posted_;
  const std::uint32_t epoch = calibration_posted_;
  calibration_state_.store(kPosted, std::memory_order_release);
  return epoch;
}

bool PadStager::take_view_fields(viewer::ViewPad* out, int* contact_cells) noexcept {
  if (view_state_.load(std::memory_order_acquire) != kViewFilled) return false;
  *contact_cells = view_contact_cells_;
  out->luma = view_->luma;
  out->mask = view_->mask;
  out->shear_x = view_->shear_x;
  out->shear_y = view_->shear_y;
  out->fz = view_->fz;
  view_state_.store(kViewIdle, std::memory_order_release);
  return true;
}

}  // namespace tacse3::firmware
