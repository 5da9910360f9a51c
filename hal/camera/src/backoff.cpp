// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: bounded exponential backoff schedule for reopening a lost device.
#include "tacse3/hal/camera/backoff.hpp"

#include <algorithm>

namespace tacse3::hal {

ReconnectPolicy Backoff::sanitize(const ReconnectPolicy& policy) noexcept {
  ReconnectPolicy p = policy;
  p.initial_ms = std::max(p.initial_ms, 1);
  p.max_ms = std::max(p.max_ms, p.initial_ms);
  p.max_attempts = std::max(p.max_attempts, 0);
  return p;
}

Backoff::Backoff(const ReconnectPolicy& policy) noexcept : policy_(sanitize(policy)) {}

std::int64_t Backoff::next_delay_ns() noexcept {
  if (exhausted()) return -1;
  // initial * 2^attempts, computed in 64 bits and capped before it can overflow.
  std::int64_t delay_ms = policy_.initial_ms;
  for (int i = 0; i < attempts_ && delay_ms < policy_.max_ms; ++i) delay_ms *= 2;
  delay_ms = std::min<std::int64_t>(delay_ms, policy_.max_ms);
  ++attempts_;
  return delay_ms * 1'000'000;
}

}  // namespace tacse3::hal
