// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: the DSP thread's doorbell on a Linux futex.
#include "tacse3/firmware/doorbell.hpp"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <climits>
#include <ctime>

namespace tacse3::firmware {

namespace {

// std::atomic<uint32_t> is a plain 32-bit word on Linux (the futex's own requirement).
static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t));

std::uint32_t* word(std::atomic<std::uint32_t>& a) noexcept {
  return reinterpret_cast<std::uint32_t*>(&a);
}

}  // namespace

void Doorbell::ring() noexcept {
  count_.fetch_add(1, std::memory_order_seq_cst);
  // Only a sleeping waiter costs a syscall; seq_cst pairs with the waiter's store of sleeping_.
  if (sleeping_.load(std::memory_order_seq_cst)) {
    syscall(SYS_futex, word(count_), FUTEX_WAKE_PRIVATE, INT_MAX, nullptr, nullptr, 0);
  }
}

void Doorbell::wait(std::uint32_t seen, std::int64_t timeout_ns) noexcept {
  sleeping_.store(true, std::memory_order_seq_cst);
  // The kernel compares the word with `seen` atomically with going to sleep: a ring after the
  // caller read `seen` makes this return at once.
  const timespec ts{static_cast<time_t>(timeout_ns / 1'000'000'000),
                    static_cast<long>(timeout_ns % 1'000'000'000)};
  syscall(SYS_futex, word(count_), FUTEX_WAIT_PRIVATE, seen, &ts, nullptr, 0);
  sleeping_.store(false, std::memory_order_relaxed);
}

}  // namespace tacse3::firmware
