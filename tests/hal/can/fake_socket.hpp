// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: a scripted in-memory SocketCAN "kernel" behind SocketOps, for the policy tests.
#pragma once

#include <linux/can.h>
#include <linux/can/raw.h>

#include <cstdint>
#include <mutex>
#include <vector>

#include "tacse3/hal/can/socket_ops.hpp"

namespace tacse3::test {

// Plays the kernel for SocketCanChannel: one CAN interface that can exist or not, be up or down,
// refuse writes (ENOBUFS, EAGAIN, any errno), deliver error frames to sockets whose
// CAN_RAW_ERR_FILTER subscribes their class, and data frames through each socket's
// CAN_RAW_FILTER list with the kernel's matching rule. Every buffer is reserved up front so
// the fake itself never allocates during a measured loop. Every call takes one mutex, so a
// sending thread, a receiving thread and the test's thread may use it at once; the public
// fields are set by the test while no other thread runs.
class FakeSocketOps final : public hal::can::SocketOps {
 public:
  struct Sock {
    int fd = -1;
    bool open = false;
    int type = 0;
    bool fd_frames = false;
    bool filter_set = false;          // CAN_RAW_FILTER given (else the kernel's match-all)
    std::vector<can_filter> filters;  // as given
    can_err_mask_t err_mask = 0;      // CAN_RAW_ERR_FILTER
    int bound_ifindex = 0;
    int pending_error = 0;              // like sk_err: returned once by the next read
    std::vector<canfd_frame> rx;        // delivered, not yet read
    std::vector<std::uint8_t> rx_size;  // CAN_MTU or CANFD_MTU per delivered frame
    std::size_t rx_next = 0;
  };
  struct Written {
    canfd_frame frame;
    std::size_t size;
    int fd;
  };

  FakeSocketOps();

  // Interface and kernel behaviour.
  const char* iface = "vcan0";
  int ifindex = 7;
  bool exists = true;
  bool up = true;
  bool iface_fd = true;     // interface MTU 72; false: classic-only, 72-byte writes get EINVAL
  int socket_errno = 0;     // socket() fails with this when non-zero
  int bind_errno = 0;       // bind() fails with this when non-zero
  int write_errno = 0;      // every write fails with this when non-zero...
  long accept_budget = -1;  // ...else at most this many more writes succeed, then ENOBUFS (-1: any)
  std::int64_t now = 1000;  // the monotonic clock, ms

  // Take the link down (every bound socket gets ENETDOWN once, writes fail with ENETDOWN) or up.
  void set_up(bool is_up);
  // Remove the interface (sockets get ENODEV, writes ENXIO) or bring it back with a new index.
  void set_exists(bool present, int new_index);
  // Deliver an error frame / a data frame to every bound socket that the kernel would give it.
  void push_error_frame(canid_t err_class, std::uint8_t d1 = 0, std::uint8_t d6 = 0,
                        std::uint8_t d7 = 0);
  void push_frame(const canfd_frame& f, std::size_t size);

  // Observations.
  std::vector<Sock> sockets;     // every socket ever created, by creation order
  std::vector<Written> written;  // every accepted write, in order
  std::uint64_t write_calls = 0;
  std::uint64_t sleeps_ms = 0;  // total of poll(nullptr, 0, t)
  int open_count() const;
  const Sock* last_bound() const;  // the newest open, bound socket (nullptr if none)
  const Sock* tx_socket() const;   // the newest open socket with an error mask
  const Sock* rx_socket() const;   // the newest open socket without one

  // SocketOps
  int socket(int domain, int type, int protocol) override;
  int if_index(int fd, const char* name) override;
  int if_flags(int fd, const char* name) override;
  int setsockopt(int fd, int level, int name, const void* value, socklen_t len) override;
  int bind(int fd, const sockaddr* addr, socklen_t len) override;
  ssize_t write(int fd, const void* buf, std::size_t len) override;
  ssize_t read(int fd, void* buf, std::size_t len) override;
  int poll(pollfd* fds, nfds_t n, int timeout_ms) override;
  int close(int fd) override;
  std::int64_t now_ms() override;

 private:
  Sock* find(int fd);
  static bool passes(const Sock& s, canid_t id);
  void deliver(Sock& s, const canfd_frame& f, std::size_t size);
  mutable std::mutex mu_;
};

}  // namespace tacse3::test
