// SPDX-License-Identifier: Apache-2.0
// tacse3d: the gripper firmware daemon (docs/firmware.md).
#include <signal.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

#include "tacse3/config/board_file.hpp"
#include "tacse3/firmware/cli.hpp"
#include "tacse3/firmware/daemon.hpp"
#include "tacse3/version.hpp"

namespace {

using namespace tacse3;

// Where the calibration came from, for the start-up lines and --check.
std::string calibration_text(const firmware::CalibrationSource& cal, bool is_default) {
  if (cal.file.empty()) return "built-in defaults";
  std::string t = cal.file.string();
  if (is_default) t += " (the simulator's, the default for a simulated board)";
  if (!cal.set.fitted) t += " (sets no sensor keys)";
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  firmware::Options opt;
  std::string error;
  if (!firmware::parse_cli(argc, argv, &opt, &error)) {
    std::fprintf(stderr, "tacse3d: %s\n%s", error.c_str(), firmware::usage_text());
    return 2;
  }
  if (opt.help) {
    std::fputs(firmware::usage_text(), stdout);
    return 0;
  }
  if (opt.version) {
    std::printf("tacse3d %s\n", kVersion);
    return 0;
  }
  const std::filesystem::path exe_dir = config::executable_dir();

  const std::filesystem::path board_file =
      config::resolve_board(opt.board, exe_dir, TACSE3_SOURCE_BOARDS_DIR, &error);
  if (board_file.empty()) {
    std::fprintf(stderr, "tacse3d: %s\n", error.c_str());
    return 1;
  }
  config::BoardConfig board;
  if (!config::load_board(board_file, &board, &error)) {
    std::fprintf(stderr, "tacse3d: %s\n", error.c_str());
    return 1;
  }
  if (!opt.can_log.empty()) {
    board.can.backend = config::CanBackend::kLog;
    board.can.log = opt.can_log;
  }
  if (!opt.can_iface.empty()) board.can.interface = opt.can_iface;

  std::string cal_file = opt.calibration;
  const bool cal_default = cal_file.empty();
  if (cal_default) {
    cal_file =
        firmware::default_calibration(board, exe_dir, TACSE3_SOURCE_SIM_CALIBRATION).string();
  }
  firmware::CalibrationSource cal;
  if (!firmware::load_calibration_source(cal_file, &cal, &error)) {
    std::fprintf(stderr, "tacse3d: %s\n", error.c_str());
    return 1;
  }
  dsp::DualConfig dual;
  std::array<dsp::Calibration, 2> sensors;
  if (!firmware::make_pipeline_config(board, cal, &dual, &sensors, &error)) {
    std::fprintf(stderr, "tacse3d: %s\n", error.c_str());
    return 1;
  }
  if (opt.check) {
    std::fputs(config::describe(board).c_str(), stdout);
    std::printf("  calibration: %s%s\n", calibration_text(cal, cal_default).c_str(),
                cal.fitted() ? "" : ": UNCALIBRATED");
    std::printf("ok\n");
    return 0;
  }

  // Signals are taken synchronously by the housekeeping loop (sigtimedwait), so they are blocked
  // in every thread, which inherit this mask. A closed stdout (the reader of --can-log - went
  // away) must not kill the daemon: the write fails, and the daemon stops with a message, exit 1.
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  signal(SIGPIPE, SIG_IGN);

  auto daemon = firmware::Daemon::create(board, opt, cal, stderr, &error);
  if (!daemon) {
    std::fprintf(stderr, "tacse3d: %s\n", error.c_str());
    return 1;
  }
  if (!cal.fitted()) {
    std::fprintf(stderr,
                 "tacse3d: UNCALIBRATED: calibration %s; the estimates are not to scale. Give "
                 "--calibration FILE from tacse3-calibrate (docs/calibration.md)\n",
                 calibration_text(cal, cal_default).c_str());
  }
  if (opt.verbosity > 0) {
    const std::string can = !opt.can_socket.empty() ? std::string("socket ") + opt.can_socket
                            : board.can.backend == config::CanBackend::kLog
                                ? std::string("log ") + board.can.log
                                : std::string("socketcan ") + board.can.interface;
    std::fprintf(stderr, "tacse3d: board %s (%s), calibration %s, CAN %s\n", board.name.c_str(),
                 board_file.c_str(), calibration_text(cal, cal_default).c_str(), can.c_str());
  }
  return daemon->run(true);
}
