// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: OS services for the daemon: real-time setup of the DSP and pad threads,
// sd_notify.
#pragma once

#include <string>

namespace tacse3::firmware {

struct RealtimeResult {
  bool locked = false;     // memory locked (lock_memory())
  bool scheduled = false;  // SCHED_FIFO at the priority
  bool pinned = false;     // CPU affinity set
  std::string message;     // one line naming what could not be done and why (empty if all ok)
};

// Locks memory (lock_memory(), process-wide; `lock` false: a thread started after one that did,
// which MCL_FUTURE covers), touches `stack_bytes` of the calling thread's stack so it is resident,
// and moves the calling thread to SCHED_FIFO `priority` (0: leave it) on `cpu` (-1: leave it; a CPU
// that does not exist is skipped with a note). Never fails hard: missing privileges
// (CAP_SYS_NICE, CAP_IPC_LOCK, RLIMIT_MEMLOCK) are reported in `message`.
RealtimeResult setup_realtime_thread(int priority, int cpu, std::size_t stack_bytes,
                                     bool lock = true) noexcept;

// Pins the calling thread to `cpu` (-1: leave it). Returns "" when done (or nothing to do), else
// one line saying why not (a CPU that does not exist is skipped).
std::string pin_current_thread(int cpu);

// systemd's notify protocol: libsystemd's sd_notify() when built with it, else the same
// datagram sent to $NOTIFY_SOCKET directly. Returns false when not under systemd (no socket).
bool notify(const char* state) noexcept;
bool notify_available() noexcept;
// The watchdog period systemd expects (WATCHDOG_USEC for this process), 0 when disabled.
long long watchdog_usec() noexcept;

}  // namespace tacse3::firmware
