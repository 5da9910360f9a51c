// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: the daemon: cameras, capture/DSP/RX threads, housekeeping, signals, shutdown.
#pragma once

#include <array>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "tacse3/config/board_file.hpp"
#include "tacse3/config/calibration_file.hpp"
#include "tacse3/firmware/cli.hpp"
#include "tacse3/firmware/doorbell.hpp"
#include "tacse3/firmware/engine.hpp"
#include "tacse3/hal/can/channel.hpp"
#include "tacse3/hal/can/unix_channel.hpp"

namespace tacse3::hal {
namespace can {
class LogChannel;
}
class SimRig;
class SimCamera;
class RecordedMotion;
class GpioBackend;
class GpioController;
}  // namespace tacse3::hal

namespace tacse3::viewer {
class ViewServer;
}  // namespace tacse3::viewer

namespace tacse3::firmware {

class FrameRecorder;
struct RecorderConfig;
using viewer::ViewServer;

// Where the calibration came from: built-in defaults or a file (reloaded on SIGHUP).
struct CalibrationSource {
  std::filesystem::path file;  // empty: built-in defaults
  config::CalibrationSet set;
  // False for the built-in defaults and a file with no sensor keys: the estimates are not to
  // scale, and the daemon says UNCALIBRATED at start and in its summary.
  bool fitted() const noexcept { return !file.empty() && set.fitted; }
};

// True when every enabled sensor of the board is simulated (the sim board).
bool simulated_board(const config::BoardConfig& board) noexcept;

// The calibration file tacse3d uses without --calibration: the simulator's
// (config::find_sim_calibration) on a simulated board, else none (empty: built-in defaults).
std::filesystem::path default_calibration(const config::BoardConfig& board,
                                          const std::filesystem::path& exe_dir,
                                          const std::filesystem::path& source_sim_calibration);

// Loads --calibration (or the defaults) and checks it against the board's pipeline settings.
bool load_calibration_source(const std::string& file, CalibrationSource* out, std::string* error);

// The pipeline configuration of a board + calibration (what --check validates).
bool make_pipeline_config(const config::BoardConfig& board, const CalibrationSource& cal,
                          dsp::DualConfig* dual, std::array<dsp::Calibration, 2>* sensors,
                          std::string* error);

struct DaemonSummary {
  EngineStats engine;
  protocol::Cycle last_cycle;  // the last cycle as sent (quantised)
  std::int64_t latency_p50_us = -1;
  std::int64_t latency_p99_us = -1;
  // Arrival of the sample's later / earlier frame at its capture thread -> cycle sent.
  std::int64_t later_arrival_p50_us = -1;
  std::int64_t later_arrival_p99_us = -1;
  std::int64_t earlier_arrival_p50_us = -1;
  std::int64_t earlier_arrival_p99_us = -1;
  std::int64_t dsp_p50_us = -1;
  double streaming_s = 0.0;
  bool have_truth = false;
  double truth_rotation_deg[3] = {0, 0, 0};  // sim board: truth rotation vector at the last cycle
  double estimated_rotation_deg[3] = {0, 0, 0};
  double rotation_error_deg = 0.0;
};

class Daemon {
 public:
  // Opens every device of the board (cameras, CAN channel, GPIO). Diagnostics go to `log`.
  static std::unique_ptr<Daemon> create(const config::BoardConfig& board, const Options& options,
                                        const CalibrationSource& calibration, std::FILE* log,
                                        std::string* error);
  ~Daemon();

  // Runs until request_stop(), a handled signal (SIGTERM/SIGINT stop, SIGHUP reloads the
  // calibration), options.seconds of streaming or a write error on the CAN log (exit code 1). The
  // caller blocks SIGTERM/SIGINT/SIGHUP in every thread first (handle_signals) so they are taken
  // here with sigtimedwait.
  int run(bool handle_signals);
  void request_stop() noexcept { stop_.store(true, std::memory_order_release); }
  // Reload the calibration file now (what SIGHUP does). false + message if the file is bad; the
  // running calibration is kept.
  bool reload_calibration(std::string* message);

  // Test access.
  hal::SimCamera* sim_camera(std::size_t sensor) noexcept;
  const hal::SimRig* sim_rig() const noexcept { return rig_.get(); }
  const SharedState& shared() const noexcept { return shared_; }
  protocol::State state() const noexcept {
    return static_cast<protocol::State>(shared_.state.load(std::memory_order_relaxed));
  }
  const DaemonSummary& summary() const noexcept { return summary_; }

 private:
  Daemon() = default;
  void capture_loop(std::size_t s);
  void dsp_loop();
  void rx_loop();
  void housekeeping_tick(std::int64_t now_ns, bool handle_signals);
  void check_can_log();
  void report_can_socket();
  void finish_summary();
  RecorderConfig recorder_config(double finger_separation_m) const;
  void service_recording();
  void close_recording();
  bool start_viewer(std::string* error);
  void say(int level, const char* fmt, ...) __attribute__((format(printf, 3, 4)));

  config::BoardConfig board_;
  Options options_;
  CalibrationSource calibration_;
  std::FILE* log_ = stderr;

  std::shared_ptr<hal::SimRig> rig_;
  // The sim rig with a plan: it plays a motion per START_RECORDING (null: the cameras show what
  // is in front of them). motion_playing_: one was started for the current recording.
  hal::RecordedMotion* motion_ = nullptr;
  bool motion_playing_ = false;
  std::array<std::unique_ptr<hal::Camera>, 2> cameras_;
  std::array<hal::SimCamera*, 2> sim_cameras_{};
  // Sources that are not paced to the wall clock (sim or replay with [sim] realtime = false)
  // wait for ring space instead of dropping: nothing is lost when the loop is the slower side.
  std::array<bool, 2> backpressure_{};
  std::unique_ptr<hal::can::Channel> channel_;
  hal::can::LogChannel* log_channel_ = nullptr;          // channel_, when it is the log backend
  hal::can::UnixSocketChannel* unix_channel_ = nullptr;  // channel_, with --can-socket
  hal::can::UnixSocketChannel::Counters socket_seen_;    // as last reported
  int exit_code_ = 0;
  std::unique_ptr<hal::GpioBackend> gpio_;
  std::unique_ptr<hal::GpioController> gpio_controller_;
  std::unique_ptr<dsp::DualPipeline> pipeline_;
  std::unique_ptr<std::array<StagedRing, 2>> rings_;           // pad thread -> DSP thread
  std::unique_ptr<std::array<CommandRing, 2>> command_rings_;  // [0] CAN RX, [1] local
  Doorbell doorbell_;  // capture and RX threads -> the DSP thread: work was handed over
  std::unique_ptr<Engine> engine_;
  // The recording being written (--record or START_RECORDING; null: none), owned here and lent
  // to the DSP thread; housekeeping creates and closes it.
  std::unique_ptr<FrameRecorder> recorder_;
  std::string recording_path_;
  bool recording_failure_reported_ = false;
  SharedState shared_;
  // --http / [viewer] listen: the slot the DSP thread publishes into, the controls' mailbox
  // ([viewer] controls) and the server using both (declared in this order: the server goes first).
  std::unique_ptr<ViewSlot> view_slot_;
  std::unique_ptr<CommandMailbox> web_commands_;
  std::unique_ptr<ViewServer> view_server_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> dsp_ready_{false};
  std::int64_t streaming_since_ns_ = 0;
  bool ready_sent_ = false;
  std::uint64_t last_heartbeat_ = 0;
  std::int64_t next_watchdog_ns_ = 0;
  long long watchdog_usec_ = 0;
  std::uint32_t tare_count_ = 0;
  std::uint8_t last_state_ = 0xFF;
  std::int64_t next_verbose_ns_ = 0;
  DaemonSummary summary_;
};

}  // namespace tacse3::firmware
