// SPDX-License-Identifier: Apache-2.0
// tacse3 hal/can: the real SocketOps: thin wrappers that turn -1/errno into -errno.
#include "tacse3/hal/can/socket_ops.hpp"

#include <net/if.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace tacse3::hal::can {
namespace {

template <typename T>
T result(T r) noexcept {
  return r < 0 ? static_cast<T>(-errno) : r;
}

int ifreq_ioctl(int fd, unsigned long request, const char* name, ifreq& ifr) noexcept {
  const std::size_t n = std::strlen(name);
  if (n == 0 || n >= IFNAMSIZ) return -ENODEV;
  std::memcpy(ifr.ifr_name, name, n + 1);
  return result(::ioctl(fd, request, &ifr));
}

class SystemSocketOps final : public SocketOps {
 public:
  int socket(int domain, int type, int protocol) override {
    return result(::socket(domain, type, protocol));
  }
  int if_index(int fd, const char* name) override {
    ifreq ifr{};
    const int r = ifreq_ioctl(fd, SIOCGIFINDEX, name, ifr);
    return r < 0 ? r : ifr.ifr_ifindex;
  }
  int if_flags(int fd, const char* name) override {
    ifreq ifr{};
    const int r = ifreq_ioctl(fd, SIOCGIFFLAGS, name, ifr);
    return r < 0 ? r : (ifr.ifr_flags & 0xFFFF);
  }
  int setsockopt(int fd, int level, int name, const void* value, socklen_t len) override {
    return result(::setsockopt(fd, level, name, value, len));
  }
  int bind(int fd, const sockaddr* addr, socklen_t len) override {
    return result(::bind(fd, addr, len));
  }
  ssize_t write(int fd, const void* buf, std::size_t len) override {
    return result(::write(fd, buf, len));
  }
  ssize_t read(int fd, void* buf, std::size_t len) override { return result(::read(fd, buf, len)); }
  int poll(pollfd* fds, nfds_t n, int timeout_ms) override {
    return result(::poll(fds, n, timeout_ms));
  }
  int close(int fd) override { return result(::close(fd)); }
  std::int64_t now_ms() override {
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return static_cast<std::int64_t>(ts.tv_sec) * 1000 + ts.tv_nsec / 1000000;
  }
};

}  // namespace

SocketOps& system_socket_ops() noexcept {
  static SystemSocketOps ops;
  return ops;
}

}  // namespace tacse3::hal::can
