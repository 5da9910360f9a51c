// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: CLOCK_MONOTONIC helpers shared by the capture backends.
#pragma once

#include <time.h>

#include <cstdint>

namespace tacse3::hal {

inline std::int64_t monotonic_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// Sleeps until the absolute CLOCK_MONOTONIC time t_ns (returns early only on a signal).
inline void sleep_until_ns(std::int64_t t_ns) noexcept {
  if (t_ns <= 0) return;
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_ns / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(t_ns % 1'000'000'000);
  clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
}

// Deadline for a timeout in milliseconds (< 0: none).
inline std::int64_t deadline_after_ms(int timeout_ms) noexcept {
  if (timeout_ms < 0) return INT64_MAX;
  return monotonic_ns() + static_cast<std::int64_t>(timeout_ms) * 1'000'000;
}

// Milliseconds left until the deadline, rounded up, for poll(): -1 = forever, 0 = expired.
inline int poll_timeout_ms(std::int64_t deadline_ns) noexcept {
  if (deadline_ns == INT64_MAX) return -1;
  const std::int64_t left = deadline_ns - monotonic_ns();
  if (left <= 0) return 0;
  const std::int64_t ms = (left + 999'999) / 1'000'000;
  return ms > 1'000'000 ? 1'000'000 : static_cast<int>(ms);
}

}  // namespace tacse3::hal
