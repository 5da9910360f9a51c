// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: bounded exponential backoff schedule for reopening a lost device.
#pragma once

#include <cstdint>

#include "tacse3/hal/camera.hpp"

namespace tacse3::hal {

// Delays initial, 2*initial, 4*initial, ... capped at max; after max_attempts (if non-zero) the
// schedule is exhausted. Deterministic (no jitter): two sensors lost together retry together,
// which is what the daemon wants (it pairs them).
class Backoff {
 public:
  explicit Backoff(const ReconnectPolicy& policy) noexcept;

  // Delay to wait before the next attempt, in nanoseconds, and counts the attempt.
  // Returns -1 once max_attempts attempts have been handed out.
  std::int64_t next_delay_ns() noexcept;
  // Back to the first delay (call after a successful reconnect).
  void reset() noexcept { attempts_ = 0; }

  int attempts() const noexcept { return attempts_; }
  bool exhausted() const noexcept {
    return policy_.max_attempts > 0 && attempts_ >= policy_.max_attempts;
  }

  // Policy fields clamped to sane values: initial >= 1 ms, max >= initial.
  static ReconnectPolicy sanitize(const ReconnectPolicy& policy) noexcept;

 private:
  ReconnectPolicy policy_;
  int attempts_ = 0;
};

}  // namespace tacse3::hal
