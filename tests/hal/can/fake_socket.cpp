// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: the scripted SocketCAN fake (see fake_socket.hpp).
#include "fake_socket.hpp"

#include <linux/can/error.h>
#include <net/if.h>

#include <cerrno>
#include <cstring>

namespace tacse3::test {

namespace {
constexpr int kFirstFd = 100;
constexpr std::size_t kMaxSockets = 64;
constexpr std::size_t kMaxWritten = 65536;
constexpr std::size_t kMaxRx = 1024;
}  // namespace

FakeSocketOps::FakeSocketOps() {
  sockets.reserve(kMaxSockets);
  written.reserve(kMaxWritten);
}

FakeSocketOps::Sock* FakeSocketOps::find(int fd) {
  const int i = fd - kFirstFd;
  if (i < 0 || static_cast<std::size_t>(i) >= sockets.size() || !sockets[i].open) return nullptr;
  return &sockets[i];
}

int FakeSocketOps::socket(int domain, int type, int protocol) {
  const std::lock_guard<std::mutex> lock(mu_);
  if (socket_errno != 0) return -socket_errno;
  if (domain != PF_CAN || protocol != CAN_RAW || sockets.size() == kMaxSockets) return -EINVAL;
  Sock s;
  s.fd = kFirstFd + static_cast<int>(sockets.size());
  s.open = true;
  s.type = type;
  s.filters.reserve(8);
  s.rx.reserve(kMaxRx);
  s.rx_size.reserve(kMaxRx);
  sockets.push_back(std::move(s));
  return sockets.back().fd;
}

int FakeSocketOps::if_index(int fd, const char* name) {
  const std::lock_guard<std::mutex> lock(mu_);
  if (find(fd) == nullptr) return -EBADF;
  if (!exists || std::strcmp(name, iface) != 0) return -ENODEV;
  return ifindex;
}

int FakeSocketOps::if_flags(int fd, const char* name) {
  const std::lock_guard<std::mutex> lock(mu_);
  if (find(fd) == nullptr) return -EBADF;
  if (!exists || std::strcmp(name, iface) != 0) return -ENODEV;
  return up ? (IFF_UP | IFF_RUNNING) : 0;
}

int FakeSocketOps::setsockopt(int fd, int level, int name, const void* value, socklen_t len) {
  const std::lock_guard<std::mutex> lock(mu_);
  Sock* s = find(fd);
  if (s == nullptr) return -EBADF;
  if (level != SOL_CAN_RAW) return -ENOPROTOOPT;
  switch (name) {
    case CAN_RAW_FD_FRAMES:
      if (len != sizeof(int)) return -EINVAL;
      s->fd_frames = *static_cast<const int*>(value) != 0;
      return 0;
    case CAN_RAW_FILTER: {
      if (len % sizeof(can_filter) != 0) return -EINVAL;
      const auto* f = static_cast<const can_filter*>(value);
      s->filters.assign(f, f + len / sizeof(can_filter));
      s->filter_set = true;
      return 0;
    }
    case CAN_RAW_ERR_FILTER:
      if (len != sizeof(can_err_mask_t)) return -EINVAL;
      s->err_mask = *static_cast<const can_err_mask_t*>(value);
      return 0;
    default:
      return -ENOPROTOOPT;
  }
}

int FakeSocketOps::bind(int fd, const sockaddr* addr, socklen_t len) {
  const std::lock_guard<std::mutex> lock(mu_);
  Sock* s = find(fd);
  if (s == nullptr) return -EBADF;
  if (bind_errno != 0) return -bind_errno;
  if (len != sizeof(sockaddr_can)) return -EINVAL;
  sockaddr_can a{};
  std::memcpy(&a, addr, sizeof a);  // copied: sockaddr is less aligned than sockaddr_can on arm
  if (a.can_family != AF_CAN) return -EINVAL;
  if (!exists || a.can_ifindex != ifindex) return -ENODEV;
  s->bound_ifindex = a.can_ifindex;
  return 0;
}

ssize_t FakeSocketOps::write(int fd, const void* buf, std::size_t len) {
  const std::lock_guard<std::mutex> lock(mu_);
  ++write_calls;
  Sock* s = find(fd);
  if (s == nullptr) return -EBADF;
  if (s->bound_ifindex != ifindex || !exists) return -ENXIO;
  if (!up) return -ENETDOWN;
  if (len != CAN_MTU && !(len == CANFD_MTU && s->fd_frames && iface_fd)) return -EINVAL;
  if (write_errno != 0) return -write_errno;
  if (accept_budget == 0) return -ENOBUFS;
  if (accept_budget > 0) --accept_budget;
  Written w{};
  std::memcpy(&w.frame, buf, len);
  w.size = len;
  w.fd = fd;
  written.push_back(w);
  return static_cast<ssize_t>(len);
}

ssize_t FakeSocketOps::read(int fd, void* buf, std::size_t len) {
  const std::lock_guard<std::mutex> lock(mu_);
  Sock* s = find(fd);
  if (s == nullptr) return -EBADF;
  if (s->pending_error != 0) {
    const int e = s->pending_error;
    s->pending_error = 0;
    return -e;
  }
  if (s->rx_next == s->rx.size()) return -EAGAIN;
  const std::size_t size = s->rx_size[s->rx_next];
  if (len < size) return -EINVAL;
  std::memcpy(buf, &s->rx[s->rx_next], size);
  if (++s->rx_next == s->rx.size()) {
    // Drained: start over (clear() keeps the capacity, so nothing is allocated).
    s->rx.clear();
    s->rx_size.clear();
    s->rx_next = 0;
  }
  return static_cast<ssize_t>(size);
}

int FakeSocketOps::poll(pollfd* fds, nfds_t n, int timeout_ms) {
  const std::lock_guard<std::mutex> lock(mu_);
  int ready = 0;
  for (nfds_t i = 0; i < n; ++i) {
    fds[i].revents = 0;
    Sock* s = find(fds[i].fd);
    if (s == nullptr) {
      fds[i].revents = POLLNVAL;
    } else if (s->pending_error != 0) {
      fds[i].revents = POLLERR;
    } else if (s->rx_next < s->rx.size()) {
      fds[i].revents = POLLIN;
    }
    if (fds[i].revents != 0) ++ready;
  }
  if (ready == 0 && timeout_ms > 0) {
    // Nothing will arrive while the caller waits (single-threaded): the wait just passes.
    now += timeout_ms;
    if (n == 0) sleeps_ms += static_cast<std::uint64_t>(timeout_ms);
  }
  return ready;
}

std::int64_t FakeSocketOps::now_ms() {
  const std::lock_guard<std::mutex> lock(mu_);
  return now;
}

int FakeSocketOps::close(int fd) {
  const std::lock_guard<std::mutex> lock(mu_);
  Sock* s = find(fd);
  if (s == nullptr) return -EBADF;
  s->open = false;
  return 0;
}

void FakeSocketOps::set_up(bool is_up) {
  const std::lock_guard<std::mutex> lock(mu_);
  if (up && !is_up) {
    for (Sock& s : sockets) {
      if (s.open && s.bound_ifindex == ifindex) s.pending_error = ENETDOWN;
    }
  }
  up = is_up;
}

void FakeSocketOps::set_exists(bool present, int new_index) {
  const std::lock_guard<std::mutex> lock(mu_);
  if (exists && !present) {
    for (Sock& s : sockets) {
      if (s.open && s.bound_ifindex == ifindex) {
        s.pending_error = ENODEV;
        s.bound_ifindex = 0;  // the kernel unbinds sockets of an unregistered device
      }
    }
  }
  exists = present;
  if (present) ifindex = new_index;
}

// The kernel's raw filter: a frame passes a socket if any filter has
// (id & mask) == (filter.id & mask); without CAN_RAW_FILTER the default filter passes all.
bool FakeSocketOps::passes(const Sock& s, canid_t id) {
  if (!s.filter_set) return true;
  for (const can_filter& f : s.filters) {
    if (((id ^ f.can_id) & f.can_mask) == 0) return true;
  }
  return false;
}

void FakeSocketOps::deliver(Sock& s, const canfd_frame& f, std::size_t size) {
  if (s.rx.size() == kMaxRx) return;  // socket receive buffer full: the kernel drops
  s.rx.push_back(f);
  s.rx_size.push_back(static_cast<std::uint8_t>(size));
}

void FakeSocketOps::push_error_frame(canid_t err_class, std::uint8_t d1, std::uint8_t d6,
                                     std::uint8_t d7) {
  const std::lock_guard<std::mutex> lock(mu_);
  canfd_frame f{};
  f.can_id = CAN_ERR_FLAG | err_class;
  f.len = CAN_ERR_DLC;
  f.data[1] = d1;
  f.data[6] = d6;
  f.data[7] = d7;
  for (Sock& s : sockets) {
    // Error frames go only to sockets that subscribed the class (raw.c: can_id & err_mask).
    if (s.open && s.bound_ifindex == ifindex && (err_class & s.err_mask) != 0) {
      deliver(s, f, CAN_MTU);
    }
  }
}

void FakeSocketOps::push_frame(const canfd_frame& f, std::size_t size) {
  const std::lock_guard<std::mutex> lock(mu_);
  for (Sock& s : sockets) {
    if (!s.open || s.bound_ifindex != ifindex || !passes(s, f.can_id)) continue;
    if (size == CANFD_MTU && !s.fd_frames) continue;  // FD frames only to FD sockets
    deliver(s, f, size);
  }
}

int FakeSocketOps::open_count() const {
  const std::lock_guard<std::mutex> lock(mu_);
  int n = 0;
  for (const Sock& s : sockets) n += s.open ? 1 : 0;
  return n;
}

const FakeSocketOps::Sock* FakeSocketOps::last_bound() const {
  const std::lock_guard<std::mutex> lock(mu_);
  for (auto it = sockets.rbegin(); it != sockets.rend(); ++it) {
    if (it->open && it->bound_ifindex != 0) return &*it;
  }
  return nullptr;
}

const FakeSocketOps::Sock* FakeSocketOps::tx_socket() const {
  const std::lock_guard<std::mutex> lock(mu_);
  for (auto it = sockets.rbegin(); it != sockets.rend(); ++it) {
    if (it->open && it->err_mask != 0) return &*it;
  }
  return nullptr;
}

const FakeSocketOps::Sock* FakeSocketOps::rx_socket() const {
  const std::lock_guard<std::mutex> lock(mu_);
  for (auto it = sockets.rbegin(); it != sockets.rend(); ++it) {
    if (it->open && it->err_mask == 0) return &*it;
  }
  return nullptr;
}

}  // namespace tacse3::test
