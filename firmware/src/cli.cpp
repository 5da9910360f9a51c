// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: tacse3d command-line parsing (no exceptions, explicit usage errors).
#include "tacse3/firmware/cli.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "tacse3/config/listen_address.hpp"

namespace tacse3::firmware {

const char* usage_text() noexcept {
  return "Usage: tacse3d --board NAME|PATH [--calibration FILE] [--can-log FILE|-]\n"
         "               [--can-socket PATH] [--can-iface IFACE] [--seconds S] [--record DIR]\n"
         "               [--http [ADDR:]PORT] [--check] [--quiet|--verbose] [--help] [--version]\n"
         "The tacse3 gripper firmware daemon: reads both tactile sensors, estimates the grasped\n"
         "object's motion and streams twist and pose over CAN.\n"
         "  --board NAME|PATH    board name (boards/NAME/board.toml) or a board.toml path\n"
         "                       (default: sim, the simulated board)\n"
         "  --calibration FILE   calibration from tacse3-calibrate (default: the simulator's\n"
         "                       sim-calibration.toml on a simulated board, else the built-in\n"
         "                       defaults, reported as UNCALIBRATED)\n"
         "  --can-log FILE|-     write CAN frames as a candump -L log (\"-\" = stdout)\n"
         "  --can-socket PATH    listen on a Unix socket: frames out and commands in as candump "
         "-L\n"
         "                       lines (tacse3-ctl --socket PATH); for hosts without CAN\n"
         "  --can-iface IFACE    override the board's SocketCAN interface\n"
         "  --seconds S          stop after S seconds of streaming (0 = until SIGTERM/SIGINT)\n"
         "  --record DIR         record both raw sensor streams to DIR\n"
         "  --http [ADDR:]PORT   serve the live web view (docs/viewer.md) on ADDR:PORT; a port\n"
         "                       alone listens on 127.0.0.1 (default: the board's [viewer],\n"
         "                       else off)\n"
         "  --check              validate board and calibration, print a summary, exit 0/1\n"
         "  --quiet | --verbose  fewer / more diagnostics on stderr\n"
         "  --help               print this help and exit\n"
         "  --version            print the version and exit\n";
}

bool parse_cli(int argc, const char* const* argv, Options* out, std::string* error) {
  Options o;
  bool have_board = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    std::string value;
    bool has_inline = false;
    std::string name = a;
    if (const auto eq = a.find('='); a.rfind("--", 0) == 0 && eq != std::string::npos) {
      name = a.substr(0, eq);
      value = a.substr(eq + 1);
      has_inline = true;
    }
    auto take = [&](std::string* dst) {
      if (has_inline) {
        *dst = value;
        return true;
      }
      if (i + 1 >= argc) {
        *error = "option " + name + " needs a value";
        return false;
      }
      *dst = argv[++i];
      return true;
    };
    if (name == "--board") {
      if (!take(&o.board)) return false;
      have_board = true;
      if (o.board.empty()) {
        *error = "--board needs a board name or a path";
        return false;
      }
    } else if (name == "--calibration") {
      // An empty value must not mean "none": it would run on the built-in calibration unnoticed.
      if (!take(&o.calibration)) return false;
      if (o.calibration.empty()) {
        *error = "--calibration needs a file; leave the option out for the default calibration";
        return false;
      }
    } else if (name == "--can-log") {
      if (!take(&o.can_log)) return false;
      if (o.can_log.empty()) {
        *error = "--can-log needs a file or -";
        return false;
      }
    } else if (name == "--can-socket") {
      if (!take(&o.can_socket)) return false;
      if (o.can_socket.empty()) {
        *error = "--can-socket needs a socket path, e.g. /tmp/tacse3-can.sock";
        return false;
      }
    } else if (name == "--can-iface") {
      if (!take(&o.can_iface)) return false;
      if (o.can_iface.empty()) {
        *error = "--can-iface needs an interface name; leave the option out for the board's";
        return false;
      }
    } else if (name == "--seconds") {
      std::string v;
      if (!take(&v)) return false;
      char* end = nullptr;
      errno = 0;
      const double s = std::strtod(v.c_str(), &end);
      if (v.empty() || end == nullptr || *end != '\0' || errno != 0 || !std::isfinite(s) ||
          s < 0.0 || s > 1e7) {
        *error = "--seconds must be a number >= 0, got \"" + v + "\"";
        return false;
      }
      o.seconds = s;
    } else if (name == "--record") {
      if (!take(&o.record_dir)) return false;
      if (o.record_dir.empty()) {
        *error = "--record needs a directory; leave the option out to record nothing";
        return false;
      }
    } else if (name == "--http") {
      if (!take(&o.http)) return false;
      config::ListenAddress addr;
      std::string e;
      if (!config::parse_listen_address(o.http, &addr, &e)) {
        *error = std::string("--http ").append(e);
        return false;
      }
    } else if (name == "--check" && !has_inline) {
      o.check = true;
    } else if (name == "--quiet" && !has_inline) {
      o.verbosity = 0;
    } else if (name == "--verbose" && !has_inline) {
      o.verbosity = 2;
    } else if ((name == "--help" || name == "-h") && !has_inline) {
      o.help = true;
    } else if (name == "--version" && !has_inline) {
      o.version = true;
    } else {
      *error = "unknown option \"" + a + "\"";
      return false;
    }
  }
  if (!o.can_log.empty() && !o.can_socket.empty()) {
    *error = "--can-log and --can-socket both choose the CAN backend; give one of them";
    return false;
  }
  (void)have_board;  // --board defaults to "sim", the board with no hardware
  *out = o;
  return true;
}

}  // namespace tacse3::firmware
