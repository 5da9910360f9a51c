// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: one pad's image stages, run by the thread that owns the pad's image state,
// and the hand-off of tare, calibration and the viewer's fields between it and the DSP thread.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

#include "tacse3/dsp/pipeline.hpp"
#include "tacse3/firmware/slot_queue.hpp"
#include "tacse3/hal/camera.hpp"
#include "tacse3/hal/camera/spsc_ring.hpp"
#include "tacse3/viewer/view_snapshot.hpp"

namespace tacse3::firmware {

// A frame as the capture thread hands it on: with the moment it received it from the camera
// (CLOCK_MONOTONIC), where the arrival latencies start (CycleLatency).
struct ArrivedFrame {
  hal::Frame frame;
  std::int64_t arrival_ns = 0;
};
// Capture thread -> DSP thread when the DSP thread runs the stages itself (tests). 8 frames =
// 66 ms at 120 Hz, more than the camera has buffers, so the ring never holds the camera back.
using FrameRing = hal::SpscRing<ArrivedFrame, 8>;

// A frame with its image stages (dsp stages 1-6) done, or not run because it was already late.
// The epochs say which tare and which calibration its stages ran under (PadStager).
struct StagedFrame {
  ArrivedFrame arrived;
  dsp::PadStages stages;
  bool staged = false;
  std::int64_t stage_us = 0;  // time its image stages took
  std::uint32_t tare_epoch = 0;
  std::uint32_t calibration_epoch = 0;
};
// Pad thread -> DSP thread, written and read in place (back() and front()): a staged frame is
// 31 KB, and copying it in and out would cost more than the hand-off. A staged frame keeps its
// camera buffer until the DSP thread pops it, so the cameras' buffer_count (at most 16) bounds
// how many are in use; only those slots are ever built (SpscSlotQueue).
using StagedRing = SpscSlotQueue<StagedFrame, 16>;

// Owns one pad's image state (SensorPipeline::process_image, tare_image, set_image_calibration):
// stage() and run_deferred() are called by one thread only, the pad's; the other members by the
// DSP thread. The DSP thread asks; the pad thread takes a request when its next frame's stages
// start. It applies a calibration there, and a tare once that frame is handed on (run_deferred:
// the frame becomes the reference, and the model build is off the cycle's latency). It stamps
// every frame with the epochs it was staged under, so the DSP thread applies the motion half
// (reset_motion, set_motion_calibration) exactly at the first frame staged after the pad applied
// the request: the frames staged before it are the last of the old reference, as a tare between
// two frames of one thread. No lock, no allocation; each request is one atomic store.
class PadStager {
 public:
  PadStager(dsp::SensorPipeline& sensor, std::int64_t (*clock)() noexcept) noexcept
      : sensor_(sensor), clock_(clock) {}

  // Pad thread. Runs f's image stages into out unless f is not newer than the last sample
  // (set_last_sample: the DSP thread drops it). A frame that becomes late while its stages run
  // is dropped by the DSP thread with its stages done: the pad's image state has then seen a
  // frame that entered no cycle, as when the camera delivers one that pairing drops.
  void stage(const ArrivedFrame& f, StagedFrame& out) noexcept;
  // Pad thread, once the staged frame is handed on: the image work only the next frame needs (a
  // keyframe switch, dsp::SensorPipeline::run_deferred), then a requested tare, off the cycle's
  // latency.
  void run_deferred() noexcept;

  // DSP thread: the sample time of the last processed sample (frames not newer are late).
  void set_last_sample(std::int64_t t_ns) noexcept {
    last_t_ns_.store(t_ns, std::memory_order_release);
  }
  // DSP thread: the next frame whose stages start becomes the reference once handed on. Returns
  // the tare epoch the frames staged after it carry.
  std::uint32_t request_tare() noexcept {
    return tare_requested_.fetch_add(1, std::memory_order_release) + 1;
  }
  // DSP thread: the image half of cal before the next frame. Returns the calibration epoch the
  // next staged frame carries, or 0 when not posted (ask again later): the pad thread is taking
  // the previous request right now, or has taken it and `after_taken` is false (the DSP thread
  // has not seen a frame of that epoch yet: its motion half still waits). A request the pad has
  // not taken yet is replaced (a lost pad never takes one).
  std::uint32_t request_calibration(const dsp::Calibration& cal, bool after_taken) noexcept;
  // Before the pad's thread starts: where the pad thread copies the viewer's fields (null, the
  // default: no viewer, nothing is copied).
  void set_view_buffer(viewer::ViewPad* buffer) noexcept { view_ = buffer; }
  // DSP thread: asks for the viewer's fields of the next staged frame (a view is due soon).
  void want_view_fields() noexcept {
    int idle = kViewIdle;
    view_state_.compare_exchange_strong(idle, kViewWanted, std::memory_order_acq_rel);
  }
  // DSP thread: copies the fields asked for into *out (grid fields and image) and *contact_cells
  // (|Ω| of that frame). False (nothing touched) when they are not there yet.
  bool take_view_fields(viewer::ViewPad* out, int* contact_cells) noexcept;

 private:
  void apply_calibration() noexcept;

  enum : int { kIdle = 0, kPosted, kBusy };  // calibration mailbox: who holds calibration_
  // view_: the pad thread writes it while kViewWanted, the DSP thread reads it while kViewFilled.
  enum : int { kViewWanted = 0, kViewFilled, kViewIdle };

  dsp::SensorPipeline& sensor_;
  std::int64_t (*clock_)() noexcept;
  std::atomic<std::int64_t> last_t_ns_{INT64_MIN};
  std::atomic<std::uint32_t> tare_requested_{0};
  std::uint32_t tare_taken_ = 0;    // pad thread: the request its last frame's stages took
  std::uint32_t tare_applied_ = 0;  // pad thread
  std::atomic<int> calibration_state_{kIdle};
  dsp::Calibration calibration_{};  // held by whoever set calibration_state_ to kBusy
  std::uint32_t calibration_posted_ = 0;
  std::uint32_t calibration_applied_ = 0;  // pad thread
  std::atomic<int> view_state_{kViewWanted};
  viewer::ViewPad* view_ = nullptr;  // the grid fields and image only
  int view_contact_cells_ = 0;
};

}  // namespace tacse3::firmware
