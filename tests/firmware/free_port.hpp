// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: a loopback TCP port nobody listens on now (the kernel's pick for port 0), for the
// tests that start the viewer's server.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

namespace tacse3::test {

inline int free_port() {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  if (s < 0) return -1;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t n = sizeof(a);
  const bool ok = bind(s, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0 &&
                  getsockname(s, reinterpret_cast<sockaddr*>(&a), &n) == 0;
  close(s);
  return ok ? ntohs(a.sin_port) : -1;
}

}  // namespace tacse3::test
