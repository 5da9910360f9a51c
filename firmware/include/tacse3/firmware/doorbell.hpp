// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: a doorbell a thread rings when it has handed over work (a frame, a command) and
// the DSP thread waits on when it has none, so the work starts at once instead of after a sleep.
#pragma once

#include <atomic>
#include <cstdint>

namespace tacse3::firmware {

// A counter and a futex on it: ring() bumps the counter and wakes the waiter; wait(seen, ns)
// returns at once when the counter is no longer `seen` (a ring between reading it and waiting is
// not lost), else after a ring or timeout_ns. One waiting thread (the DSP thread), any number of
// ringing ones. No allocation, no lock; ring() is one atomic add
// and, when the waiter sleeps, one futex wake.
class Doorbell {
 public:
  std::uint32_t value() const noexcept { return count_.load(std::memory_order_acquire); }
  void ring() noexcept;
  void wait(std::uint32_t seen, std::int64_t timeout_ns) noexcept;

 private:
  std::atomic<std::uint32_t> count_{0};
  std::atomic<bool> sleeping_{false};
};

}  // namespace tacse3::firmware
