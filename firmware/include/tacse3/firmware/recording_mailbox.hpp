// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: START/STOP_RECORDING between the DSP thread (which decides and answers) and
// the housekeeping thread (which creates and closes recordings: disk I/O the DSP thread never
// waits for).
#pragma once

#include <atomic>
#include <cstdint>

#include "tacse3/protocol/types.hpp"

namespace tacse3::firmware {

class FrameRecorder;

// One start and one close in flight at a time, handed over through atomics (no lock, no
// allocation). The recorder pointers are owned by the daemon (Daemon::recorder_); the DSP thread
// only borrows the one it records into.
class RecordingMailbox {
 public:
  struct StartRequest {
    std::uint16_t number = 0;
    double finger_separation_m = 0.0;  // the live separation, for recording.json's rig
  };

  // DSP thread. false: a start is already in flight (nothing posted).
  bool request_start(const StartRequest& r) noexcept {
    if (start_.load(std::memory_order_acquire) != kIdle) return false;
    request_ = r;
    start_.store(kRequested, std::memory_order_release);
    return true;
  }
  bool start_in_flight() const noexcept { return start_.load(std::memory_order_acquire) != kIdle; }
  // DSP thread: true once housekeeping answered; *recorder is null unless *result is kAck.
  bool poll_start(FrameRecorder** recorder, protocol::AckCode* result) noexcept {
    if (start_.load(std::memory_order_acquire) != kAnswered) return false;
    *recorder = started_;
    *result = result_;
    start_.store(kIdle, std::memory_order_release);
    return true;
  }
  // DSP thread, after it stopped recording into `recorder`. false: the previous close has not
  // been taken yet (nothing posted).
  bool request_close(FrameRecorder* recorder) noexcept {
    FrameRecorder* expected = nullptr;
    return close_.compare_exchange_strong(expected, recorder, std::memory_order_acq_rel);
  }

  // Housekeeping thread.
  bool pending_start(StartRequest* out) const noexcept {
    if (start_.load(std::memory_order_acquire) != kRequested) return false;
    *out = request_;
    return true;
  }
  void answer_start(FrameRecorder* recorder, protocol::AckCode result) noexcept {
    started_ = recorder;
    result_ = result;
    start_.store(kAnswered, std::memory_order_release);
  }
  FrameRecorder* take_close() noexcept {
    return close_.exchange(nullptr, std::memory_order_acq_rel);
  }

 private:
  enum : int { kIdle = 0, kRequested = 1, kAnswered = 2 };
  std::atomic<int> start_{kIdle};
  StartRequest request_{};
  FrameRecorder* started_ = nullptr;
  protocol::AckCode result_ = protocol::AckCode::kAck;
  std::atomic<FrameRecorder*> close_{nullptr};
};

}  // namespace tacse3::firmware
