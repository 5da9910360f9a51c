// SPDX-License-Identifier: Apache-2.0
// seccomp_exec: run a program under a system-call allow list, as systemd's SystemCallFilter=
// does for the service. Calls outside the list kill the process with SIGSYS (systemd's default
// action), so a run that finishes proves every call it made is on the list.
//
//   seccomp_exec ALLOWLIST -- PROGRAM [ARG...]
//
// ALLOWLIST holds one system-call name a line (tests/packaging/unit_syscalls.sh writes it).
// Names this architecture does not have (the 32-bit variants) are skipped.
#include <seccomp.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

namespace {

int usage() {
  std::fprintf(stderr, "usage: seccomp_exec ALLOWLIST -- PROGRAM [ARG...]\n");
  return 2;
}

// Adds an allow rule per name; returns the number of names added, or -1 after a message.
int allow_listed(scmp_filter_ctx ctx, const char* path) {
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "seccomp_exec: cannot read the allow list %s\n", path);
    return -1;
  }
  int added = 0;
  for (std::string name; std::getline(in, name);) {
    if (name.empty()) continue;
    const int nr = seccomp_syscall_resolve_name(name.c_str());
    if (nr == __NR_SCMP_ERROR) continue;
    const int rc = seccomp_rule_add(ctx, SCMP_ACT_ALLOW, nr, 0);
    if (rc != 0) {
      std::fprintf(stderr, "seccomp_exec: allow %s: %s\n", name.c_str(), std::strerror(-rc));
      return -1;
    }
    ++added;
  }
  return added;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4 || std::strcmp(argv[2], "--") != 0) return usage();
  scmp_filter_ctx ctx = seccomp_init(SCMP_ACT_KILL_PROCESS);
  if (ctx == nullptr) {
    std::fprintf(stderr, "seccomp_exec: seccomp_init failed\n");
    return 1;
  }
  const int added = allow_listed(ctx, argv[1]);
  if (added <= 0) {
    if (added == 0) std::fprintf(stderr, "seccomp_exec: %s allows no system call\n", argv[1]);
    seccomp_release(ctx);
    return 1;
  }
  // libseccomp sets no_new_privs first, as NoNewPrivileges=yes in the unit does.
  const int rc = seccomp_load(ctx);
  seccomp_release(ctx);
  if (rc != 0) {
    std::fprintf(stderr, "seccomp_exec: seccomp_load: %s\n", std::strerror(-rc));
    return 1;
  }
  execvp(argv[3], argv + 3);
  std::fprintf(stderr, "seccomp_exec: cannot run %s: %s\n", argv[3], std::strerror(errno));
  return 127;
}
