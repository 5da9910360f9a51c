// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: SocketCAN raw socket channel.
#include "tacse3/hal/can/socketcan.hpp"

#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace tacse3::hal::can {
namespace {

std::string errno_text(int e) {
  return std::strerror(e);
}

std::uint64_t realtime_us() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000u +
         static_cast<std::uint64_t>(ts.tv_nsec) / 1000u;
}

std::int64_t monotonic_ms() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000 + ts.tv_nsec / 1000000;
}

}  // namespace

std::unique_ptr<SocketCanChannel> SocketCanChannel::open(const std::string& iface,
                                                         const SocketCanOptions& options,
                                                         std::string& error) {
  const int s = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (s < 0) {
    const int e = errno;
    if (e == EAFNOSUPPORT || e == EPROTONOSUPPORT) {
      error =
          "SocketCAN is not available on this host: socket(PF_CAN, SOCK_RAW, CAN_RAW) failed (" +
          errno_text(e) +
          "). The kernel has no CAN support loaded (CONFIG_CAN / CONFIG_CAN_RAW; try "
          "'modprobe can_raw'). Without CAN hardware use a candump log instead.";
    } else {
      error = "socket(PF_CAN, SOCK_RAW, CAN_RAW) failed: " + errno_text(e);
    }
    return nullptr;
  }
  auto fail = [&](const std::string& what) {
    error = what;
    ::close(s);
    return nullptr;
  };
  if (iface.empty() || iface.size() >= IFNAMSIZ) {
    return fail("invalid CAN interface name '" + iface + "'");
  }
  ifreq ifr{};
  std::memcpy(ifr.ifr_name, iface.c_str(), iface.size() + 1);
  if (::ioctl(s, SIOCGIFINDEX, &ifr) < 0) {
    return fail("no CAN interface '" + iface + "': " + errno_text(errno) +
                " (is it up? 'ip link set " + iface + " up type can bitrate 500000')");
  }
  if (options.fd) {
    const int on = 1;
    if (::setsockopt(s, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) < 0) {
      return fail("CAN FD frames not supported on '" + iface + "': " + errno_text(errno));
    }
  }
  if (!options.filters.empty()) {
    std::vector<can_filter> f(options.filters.size());
    for (std::size_t i = 0; i < f.size(); ++i) {
      f[i].can_id = options.filters[i].id;
      f[i].can_mask = options.filters[i].mask;
    }
    if (::setsockopt(s, SOL_CAN_RAW, CAN_RAW_FILTER, f.data(),
                     static_cast<socklen_t>(f.size() * sizeof(can_filter))) < 0) {
      return fail("setting CAN filters on '" + iface + "' failed: " + errno_text(errno));
    }
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  if (::bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) {
    return fail("bind to '" + iface + "' failed: " + errno_text(errno));
  }
  return std::unique_ptr<SocketCanChannel>(new SocketCanChannel(s, iface, options.fd));
}

SocketCanChannel::~SocketCanChannel() {
  if (fd_ >= 0) ::close(fd_);
}

bool SocketCanChannel::send(const CanFrame& f) {
  if (!protocol::is_valid_length(f.fd, f.len)) {
    error_ = "invalid frame length";
    return false;
  }
  canid_t id = f.extended ? ((f.id & CAN_EFF_MASK) | CAN_EFF_FLAG) : (f.id & CAN_SFF_MASK);
  ssize_t n = 0;
  std::size_t want = 0;
  if (f.fd) {
    if (!fd_enabled_) {
      error_ = "CAN FD frame on a channel opened without FD support";
      return false;
    }
    canfd_frame cf{};
    cf.can_id = id;
    cf.len = f.len;
    cf.flags = f.brs ? CANFD_BRS : 0;
    std::memcpy(cf.data, f.data.data(), f.len);
    want = CANFD_MTU;
    n = ::write(fd_, &cf, want);
  } else {
    can_frame cf{};
    cf.can_id = id;
    cf.can_dlc = f.len;
    std::memcpy(cf.data, f.data.data(), f.len);
    want = CAN_MTU;
    n = ::write(fd_, &cf, want);
  }
  if (n != static_cast<ssize_t>(want)) {
    error_ = "write to '" + iface_ + "' failed: " + (n < 0 ? errno_text(errno) : "short write");
    return false;
  }
  return true;
}

RxResult SocketCanChannel::receive(RxFrame& out, int timeout_ms) {
  const std::int64_t deadline = timeout_ms < 0 ? -1 : monotonic_ms() + timeout_ms;
  for (;;) {
    int wait = -1;
    if (deadline >= 0) {
      const std::int64_t left = deadline - monotonic_ms();
      if (left < 0) return RxResult::kTimeout;
      wait = static_cast<int>(left);
    }
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, wait);
    if (r == 0) return RxResult::kTimeout;
    if (r < 0) {
      if (errno == EINTR) continue;
      error_ = "poll on '" + iface_ + "' failed: " + errno_text(errno);
      return RxResult::kError;
    }
    canfd_frame cf{};
    const ssize_t n = ::read(fd_, &cf, sizeof cf);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      error_ = "read from '" + iface_ + "' failed: " + errno_text(errno);
      return RxResult::kError;
    }
    if (n != CAN_MTU && n != CANFD_MTU) continue;
    if ((cf.can_id & (CAN_ERR_FLAG | CAN_RTR_FLAG)) != 0) {
      ++skipped_;
      continue;
    }
    CanFrame& f = out.frame;
    f = CanFrame{};
    f.extended = (cf.can_id & CAN_EFF_FLAG) != 0;
    f.id = f.extended ? (cf.can_id & CAN_EFF_MASK) : (cf.can_id & CAN_SFF_MASK);
    f.fd = n == CANFD_MTU;
    f.brs = f.fd && (cf.flags & CANFD_BRS) != 0;
    f.len = f.fd ? cf.len : std::min<std::uint8_t>(cf.len, CAN_MAX_DLEN);
    if (f.len > f.data.size()) f.len = static_cast<std::uint8_t>(f.data.size());
    std::memcpy(f.data.data(), cf.data, f.len);
    out.time_us = realtime_us();
    return RxResult::kFrame;
  }
}

}  // namespace tacse3::hal::can
