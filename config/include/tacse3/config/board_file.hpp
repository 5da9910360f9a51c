// SPDX-License-Identifier: Apache-2.0
// tacse3 config: the board file (boards/<name>/board.toml, schema version 1): parse, validate.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "tacse3/config/gpio_lines.hpp"
#include "tacse3/dsp/fusion.hpp"
#include "tacse3/protocol/ids.hpp"
#include "tacse3/protocol/types.hpp"

namespace tacse3::config {

inline constexpr int kBoardVersion = 1;

enum class CameraBackend : std::uint8_t { kSim = 0, kReplay, kV4l2, kLibcamera };
const char* to_string(CameraBackend b) noexcept;

// One [sensors.left] / [sensors.right] table.
struct SensorBoardConfig {
  bool enabled = false;  // the table is present
  CameraBackend backend = CameraBackend::kSim;
  std::string device;
  int width = 320;
  int height = 240;
  int fps = 120;
  int buffer_count = 4;
  bool allow_mjpeg = true;
  // replay only: delay of this pad's frames after the start (the offset between two
  // free-running cameras), microseconds.
  int phase_us = 0;
  // Pad orientation in the gripper frame G (row-major R_GS).
  std::array<std::array<double, 3>, 3> rotation{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
};

// The [sim] object names: the simulator's presets (sim::object_preset_names(), in its order).
// config may not include sim, so the list is kept here and tests/config checks the two agree;
// --check can then refuse a name the run would fail on.
inline constexpr std::array<const char*, 11> kSimObjectNames{
    "sphere", "large-sphere", "ellipsoid",   "bumpy",         "irregular",  "cylinder",
    "cube",   "plastic-cube", "wooden-cube", "textured-cube", "screwdriver"};

// [sim]: the live simulator's scenario (only read when a sensor uses backend "sim").
struct SimBoardConfig {
  std::string object = "sphere";
  std::string motion = "rz";
  double magnitude = 30.0;
  std::string regime = "stick";
  std::uint64_t seed = 1;
  bool repeat = true;
  bool realtime = true;
  // A calibration plan (tacse3-calibrate --plan --format csv) the simulated rig plays, one motion
  // per START_RECORDING (docs/firmware.md, "Simulated rig"). A relative path is taken from the
  // board file's folder; empty: no plan, the scenario above plays.
  std::string plan;
};

// The finger separation range of board files, the same as SET_FINGER_SEPARATION's
// (docs/can-protocol.md); replay holds recordings to it too.
inline constexpr double kMinFingerSeparationM = 0.001;
inline constexpr double kMaxFingerSeparationM = 0.25;

// [pipeline]
struct PipelineBoardConfig {
  double finger_separation_m = 0.040;
  dsp::FusionMethod method = dsp::FusionMethod::kJoint;
  protocol::VelocityMode velocity_proxy = protocol::VelocityMode::kAuto;
  int pair_tolerance_us = 2000;
  int stale_ms = 50;
  int lost_ms = 500;
};

enum class CanBackend : std::uint8_t { kSocketCan = 0, kLog };

// [can]
struct CanBoardConfig {
  CanBackend backend = CanBackend::kSocketCan;
  std::string interface = "can0";
  std::string log = "-";
  protocol::FrameMode mode = protocol::FrameMode::kClassic;
  int bitrate = 500000;
  int data_bitrate = 2000000;
  int node_id = 1;
  bool extended_ids = false;
  int tx_queue = 64;
  int rate_divider = 1;
};

enum class GpioBackendKind : std::uint8_t { kNull = 0, kLibgpiod };

// [gpio]
struct GpioBoardConfig {
  GpioBackendKind backend = GpioBackendKind::kNull;
  GpioConfig lines;      // chip + the optional lines (enabled = table present)
  int debounce_ms = 20;  // [gpio.tare_button].debounce_ms (also used for gripper_closed)
};

// [realtime]
struct RealtimeConfig {
  int dsp_cpu = 3;        // -1 = do not pin
  int dsp_priority = 80;  // SCHED_FIFO priority, 0 = normal scheduling
  // The CPU each pad's capture thread is pinned to ([left, right]; -1 = do not pin).
  std::array<int, 2> pad_cpus{-1, -1};
};

// A quaternion in the board file is accepted as unit when its norm is within this of 1, as in
// truth.csv (docs/recording-format.md); it is then normalised.
inline constexpr double kBoardUnitQuaternionTolerance = 1e-3;

// [rig]: the robot the board is mounted on, read by the host tools (tacse3-truth), not the daemon.
struct RigBoardConfig {
  // The pose of the grasp frame G in the robot's TCP frame: x, y, z (m), qw, qx, qy, qz (unit).
  bool has_tcp_to_grasp = false;  // the key is present
  std::array<double, 7> tcp_to_grasp{0, 0, 0, 1, 0, 0, 0};
};

// [record]: where the START_RECORDING command writes (docs/can-protocol.md). Empty: the
// command is refused (NO_RECORD_DIR).
struct RecordBoardConfig {
  std::string dir;  // absolute path of an existing directory
};

// [viewer]: the live web view (docs/viewer.md). Empty listen: off.
struct ViewerBoardConfig {
  std::string listen;     // "PORT" or "ADDR:PORT", checked by parse_listen_address
  bool controls = false;  // POST /api/command (tare, reset pose, stream on/off) allowed
};

struct BoardConfig {
  int version = kBoardVersion;
  std::string name;
  std::string description;
  std::array<SensorBoardConfig, 2> sensors{};  // [left, right]
  SimBoardConfig sim;
  PipelineBoardConfig pipeline;
  CanBoardConfig can;
  GpioBoardConfig gpio;
  RealtimeConfig realtime;
  RecordBoardConfig record;
  RigBoardConfig rig;
  ViewerBoardConfig viewer;
  std::string origin;  // the file it came from

  bool uses_backend(CameraBackend b) const noexcept {
    for (const auto& s : sensors) {
      if (s.enabled && s.backend == b) return true;
    }
    return false;
  }
  int sensor_count() const noexcept {
    return (sensors[0].enabled ? 1 : 0) + (sensors[1].enabled ? 1 : 0);
  }
};

// Parses and validates board TOML text. `origin` names the source in messages. On error returns
// false with *error = "FILE:LINE: key \"...\" ..." and leaves *out unchanged. Unknown keys,
// wrong types and out-of-range values are errors; missing optional tables take the defaults.
bool parse_board(std::string_view text, const std::string& origin, BoardConfig* out,
                 std::string* error) noexcept;
// Reads and parses a file (see parse_board). Only a regular file of at most kMaxBoardBytes is
// read: a directory, FIFO or device is an error at once, named as such.
inline constexpr std::size_t kMaxBoardBytes = std::size_t{1} << 20;
bool load_board(const std::filesystem::path& file, BoardConfig* out, std::string* error) noexcept;

// Resolves --board NAME|PATH (contract A): a path to an existing file (or anything containing a
// '/' or ending in ".toml") is used as is; a name is looked up as NAME/board.toml in, in order,
// $TACSE3_BOARD_DIR, /etc/tacse3/boards, <exe_dir>/../share/tacse3/boards, source_boards_dir.
// Returns the path, or an empty path with *error listing the places searched.
std::filesystem::path resolve_board(const std::string& name_or_path,
                                    const std::filesystem::path& exe_dir,
                                    const std::filesystem::path& source_boards_dir,
                                    std::string* error);

// The pad extrinsics of the board (rotations from the file; positions z = +-W/2).
dsp::FusionConfig fusion_config(const BoardConfig& board) noexcept;

// Multi-line human-readable summary for --check.
std::string describe(const BoardConfig& board);

}  // namespace tacse3::config
