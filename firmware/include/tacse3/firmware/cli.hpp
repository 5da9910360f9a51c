// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: the tacse3d command line (contract A in docs/firmware.md).
#pragma once

#include <string>

namespace tacse3::firmware {

struct Options {
  std::string board = "sim";
  std::string calibration;  // empty: the simulator's on a simulated board, else built-in defaults
  std::string can_log;      // non-empty: log backend to this file, "-" = stdout
  std::string can_iface;    // non-empty: override [can].interface
  std::string can_socket;   // non-empty: candump -L both ways on a Unix socket at this path
  double seconds = 0.0;     // 0 = until SIGTERM/SIGINT
  std::string record_dir;
  std::string http;  // non-empty: serve the live viewer here (checked "PORT" or "ADDR:PORT")
  bool check = false;
  int verbosity = 1;  // 0 quiet, 1 normal, 2 verbose
  bool help = false;
  bool version = false;
};

// false with *error on a usage error (exit status 2).
bool parse_cli(int argc, const char* const* argv, Options* out, std::string* error);
const char* usage_text() noexcept;

}  // namespace tacse3::firmware
