// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: run a shell command and collect its stdout; read a whole file. Shared by the
// tests that drive the built tacse3d and tools.
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace tacse3::test {

struct RunResult {
  int status = -1;  // exit status; 128 + N if signal N ended it (as a shell says); -1 if no run
  std::string out;
};

inline RunResult run_cmd(const std::string& cmd) {
  RunResult r;
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return r;
  char buf[4096];
  std::size_t n;
  while ((n = fread(buf, 1, sizeof(buf), p)) > 0) r.out.append(buf, n);
  const int st = pclose(p);
  if (st != -1 && WIFEXITED(st)) r.status = WEXITSTATUS(st);
  if (st != -1 && WIFSIGNALED(st)) r.status = 128 + WTERMSIG(st);
  return r;
}

inline std::string read_all(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace tacse3::test
