// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: memory locking, SCHED_FIFO, affinity and the systemd notify protocol.
#include "tacse3/firmware/system.hpp"

#include <alloca.h>
#include <pthread.h>
#include <sched.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <cstring>

#include "tacse3/firmware/memory_lock.hpp"

#if TACSE3_HAVE_LIBSYSTEMD
#include <systemd/sd-daemon.h>
#endif

namespace tacse3::firmware {

namespace {

// Touch the stack once so the pages the DSP loop will use are mapped before the first frame
// (locked at their first touch, lock_memory(): no page fault in the loop).
__attribute__((noinline)) void prefault_stack(std::size_t bytes) noexcept {
  volatile unsigned char* buf = static_cast<volatile unsigned char*>(alloca(bytes));
  for (std::size_t i = 0; i < bytes; i += 4096) buf[i] = 0;
  buf[bytes - 1] = 0;
}

}  // namespace

std::string pin_current_thread(int cpu) {
  if (cpu < 0) return {};
  const long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
  if (cpu >= ncpu) {
    return "CPU " + std::to_string(cpu) + " does not exist (" + std::to_string(ncpu) +
           " online), not pinned";
  }
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  const int e = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
  if (e == 0) return {};
  return "pin to CPU " + std::to_string(cpu) + ": " + std::strerror(e);
}

RealtimeResult setup_realtime_thread(int priority, int cpu, std::size_t stack_bytes,
                                     bool lock) noexcept {
  RealtimeResult r;
  std::string missing;
  // The DSP path runs through the program, its libraries, its heap and its stack, and must take
  // no page fault after start: lock_memory() makes those libraries resident in full and locks
  // every other page at its first touch; the stack prefault below touches this thread's stack.
  if (lock) {
    const MemoryLock m = lock_memory();
    r.locked = m.locked;
    if (!m.message.empty()) missing += m.message;
  }
  if (stack_bytes > 0) prefault_stack(stack_bytes);
  if (priority > 0) {
    sched_param sp{};
    sp.sched_priority = priority;
    const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    if (e == 0) {
      r.scheduled = true;
    } else {
      missing += std::string(missing.empty() ? "" : "; ") + "SCHED_FIFO " +
                 std::to_string(priority) + ": " + std::strerror(e) + " (needs CAP_SYS_NICE)";
    }
  }
  if (cpu >= 0) {
    const std::string pin = pin_current_thread(cpu);
    r.pinned = pin.empty();
    if (!pin.empty()) missing += std::string(missing.empty() ? "" : "; ") + pin;
  }
  r.message = missing;
  return r;
}

bool notify_available() noexcept {
  const char* s = std::getenv("NOTIFY_SOCKET");
  return s != nullptr && *s != '\0';
}

bool notify(const char* state) noexcept {
#if TACSE3_HAVE_LIBSYSTEMD
  return sd_notify(0, state) > 0;
#else
  const char* path = std::getenv("NOTIFY_SOCKET");
  if (path == nullptr || *path == '\0') return false;
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const std::size_t n = std::strlen(path);
  if (n >= sizeof(addr.sun_path)) return false;
  std::memcpy(addr.sun_path, path, n);
  socklen_t len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + n);
  if (path[0] == '@') addr.sun_path[0] = '\0';  // abstract socket
  const int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  const ssize_t sent = sendto(fd, state, std::strlen(state), MSG_NOSIGNAL,
                              reinterpret_cast<const sockaddr*>(&addr), len);
  close(fd);
  return sent >= 0;
#endif
}

long long watchdog_usec() noexcept {
  const char* s = std::getenv("WATCHDOG_USEC");
  if (s == nullptr) return 0;
  const char* pid = std::getenv("WATCHDOG_PID");
  if (pid != nullptr && std::atoll(pid) != static_cast<long long>(getpid())) return 0;
  return std::atoll(s);
}

}  // namespace tacse3::firmware
