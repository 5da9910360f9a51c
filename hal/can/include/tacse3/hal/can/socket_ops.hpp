// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: the few syscalls SocketCanChannel makes, behind an interface tests can fake.
#pragma once

#include <poll.h>
#include <sys/socket.h>
#include <sys/types.h>

#include <cstddef>
#include <cstdint>

namespace tacse3::hal::can {

// Every call returns what the syscall returns on success and -errno on failure (never -1 with
// errno), so a fake can script failures without touching the thread's errno and the channel
// never reads errno after an intervening call.
//
// The real implementation is system_socket_ops(). A fake (tests/hal/can/fake_socket.hpp) plays
// the kernel: it returns ENOBUFS, EAGAIN, ENETDOWN, ENXIO, delivers error frames and records
// the socket options it was given. That is how the TX queue, error-frame and recovery policies
// are unit-tested on hosts without AF_CAN and beyond what vcan can simulate (vcan produces no
// error frames and never goes bus-off).
class SocketOps {
 public:
  virtual ~SocketOps() = default;
  virtual int socket(int domain, int type, int protocol) = 0;
  // ioctl(fd, SIOCGIFINDEX): the interface index of `name`.
  virtual int if_index(int fd, const char* name) = 0;
  // ioctl(fd, SIOCGIFFLAGS): the interface flags (IFF_UP, IFF_RUNNING...) of `name`.
  virtual int if_flags(int fd, const char* name) = 0;
  virtual int setsockopt(int fd, int level, int name, const void* value, socklen_t len) = 0;
  virtual int bind(int fd, const sockaddr* addr, socklen_t len) = 0;
  virtual ssize_t write(int fd, const void* buf, std::size_t len) = 0;
  virtual ssize_t read(int fd, void* buf, std::size_t len) = 0;
  virtual int poll(pollfd* fds, nfds_t n, int timeout_ms) = 0;
  virtual int close(int fd) = 0;
  // CLOCK_MONOTONIC in milliseconds: the retry backoff runs on it, so a fake can step time.
  virtual std::int64_t now_ms() = 0;
};

// The process-wide real implementation (stateless, thread-safe).
SocketOps& system_socket_ops() noexcept;

}  // namespace tacse3::hal::can
