// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: the live `sim` camera backend: two simulated pads from one shared simulation.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "tacse3/hal/camera.hpp"
#include "tacse3/hal/camera/recorded_motion.hpp"
#include "tacse3/sim/types.hpp"

namespace tacse3::sim {
class Simulator;
class ArmLog;
struct SimConfig;
}  // namespace tacse3::sim

namespace tacse3::hal {

// The scene, as the board file's [sim] table declares it (docs/hal-camera.md, "sim camera
// backend").
struct SimSceneConfig {
  std::string object = "sphere";  // a tacse3::sim object preset (sim::object_preset_names())
  std::string motion = "rz";      // rx ry rz tx ty
  double magnitude = 30.0;        // degrees for rotations, millimetres for translations
  std::string regime = "stick";   // stick | slide
  std::uint64_t seed = 1;
  bool repeat = true;    // loop approach -> grasp -> motion -> hold -> release forever
  bool realtime = true;  // pace frames to CLOCK_MONOTONIC; false: as fast as they are consumed
  // > 0: rescale the object so the pads sit this far apart when grasped ([pipeline]
  // finger_separation_m in mm); 0: the preset's own size.
  double finger_separation_mm = 0.0;
  // A calibration plan CSV (tacse3-calibrate --plan --format csv). Given, the rig plays one of
  // its motions per recording (RecordedMotion) instead of the scene above, and rests between.
  std::string plan;
};

// The rig: the scene plus the frame geometry and rate shared by both pads.
struct SimRigConfig {
  SimSceneConfig scene;
  int width = 320;  // the simulator renders multiples of 4 pixels; the pipeline needs 320 x 240
  int height = 240;
  int fps = 120;  // 1..1000
  // With a plan: the pose of G in the robot's TCP frame (x, y, z in m, qw, qx, qy, qz), the
  // board file's [rig] tcp_to_grasp, for the simulated robot's log.
  std::array<double, 7> tcp_to_grasp{0, 0, 0, 1, 0, 0, 0};
};

// One simulated sensor. Everything a Camera needs, plus fault injection for tests and the
// daemon's control path.
struct SimCameraConfig {
  sim::Sensor sensor = sim::Sensor::kLeft;
  dsp::PixelFormat format = dsp::PixelFormat::kRgb888;  // kRgb888 or kGrey
  int buffer_count = 4;                                 // 2..16, all allocated in open()
};

class SimCamera;

// Owns the one Simulator both pads are rendered from, and the common time origin t0 (set by the
// first start() of either camera): frame k of the frame grid has the timestamp
// t0 + round(k * 1e9 / fps) and shows the scene at simulation time round(k * 1e9 / fps), so
// left and right frames with the same timestamp show the same instant of the same grasp.
// Each pad keeps its own physical state inside the Simulator, so the two capture threads
// render concurrently without a lock on the frame path.
//
// With a plan (SimSceneConfig::plan) the rig is also the RecordedMotion of the daemon's
// recordings: between recordings the pads rest open; each start_motion() plays the plan's next
// motion from rest (pads open for its pads_open_s, grasp, settle, motion, hold, then held), and
// stop_motion() opens the pads again and writes, in the recording's robot/ folder, the simulated
// robot's TCP log (gripper.csv, sim::ArmLog: the format tacse3-truth --gripper-log reads, on
// CLOCK_REALTIME, the clock a controller on this host stamps its CAN log with) and the
// simulator's exact truth of the same frames (sim-truth.csv, truth.csv's format), which a real
// rig does not have. A motion starts at a frame neither pad has rendered yet, so both pads
// switch on the same frame.
class SimRig : public std::enable_shared_from_this<SimRig>, public RecordedMotion {
 public:
  // Validates the configuration and builds the simulator (patterns, tables: ~0.1-0.3 s).
  // nullptr with *error naming the key ("[sim] object: ...") on a bad configuration.
  // With a plan, *error names the plan file and line on a bad plan.
  static std::shared_ptr<SimRig> create(const SimRigConfig& config, std::string* error);
  ~SimRig() override;
  SimRig(const SimRig&) = delete;
  SimRig& operator=(const SimRig&) = delete;

  // A camera for one pad (at most one per sensor is meaningful: both would share its state).
  std::unique_ptr<SimCamera> make_camera(const SimCameraConfig& config);

  const SimRigConfig& config() const noexcept { return config_; }
  const sim::Simulator& simulator() const noexcept { return *sim_; }
  // Distance between the pad surfaces when grasped (the simulator's nominal value), in mm.
  double finger_separation_mm() const;
  std::int64_t period_ns() const noexcept { return 1'000'000'000 / config_.fps; }

  // CLOCK_MONOTONIC time of simulation time 0, or 0 before the first start().
  std::int64_t t0_ns() const noexcept { return t0_.load(std::memory_order_acquire); }
  // Simulation time (ns since the scenario's first frame) of a frame timestamp.
  std::int64_t sim_time_ns(std::int64_t timestamp_ns) const noexcept {
    return timestamp_ns - t0_ns();
  }
  // Simulation time of grid frame k.
  std::int64_t grid_time_ns(std::int64_t k) const noexcept;
  // Ground truth of the frame with this timestamp: the object's pose in G (mm) relative to the
  // first frame of the current scenario cycle (with repeat, it starts over every cycle).
  sim::Pose truth(std::int64_t timestamp_ns) const noexcept;
  sim::Twist truth_twist(std::int64_t timestamp_ns) const noexcept;

  // RecordedMotion (a plan only; without one, next_motion_problem() says so).
  bool has_plan() const noexcept { return !plan_sims_.empty(); }
  std::size_t plan_size() const noexcept { return plan_sims_.size(); }
  std::string next_motion_problem() const override;
  void start_motion(const std::filesystem::path& dir) override;
  std::string stop_motion() override;

 private:
  friend class SimCamera;
  SimRig() = default;
  // Sets t0 on the first call (now + one period); later calls return the same t0.
  std::int64_t start_clock() noexcept;
  // Renders pad s at grid frame k: the scene, or with a plan the motion (or rest) of frame k.
  sim::SimStatus render(sim::Sensor s, std::int64_t k, std::span<std::uint8_t> out,
                        int channels) noexcept;
  void restart_pad(sim::Sensor s) noexcept;
  bool load_plan(const sim::SimConfig& base, std::string* error);

  // With a plan: from grid frame start_grid on the rig plays plan motion `motion`, or rests
  // (-1) with the pads open as in the approach of motion `scene`.
  struct Segment {
    int motion = -1;
    int scene = 0;
    std::int64_t start_grid = 0;
  };
  std::size_t segment_at(std::int64_t k) const noexcept;
  bool append_segment(int motion);
  sim::Pose motion_truth(int motion, std::int64_t start_grid, std::int64_t t_sim) const noexcept;

  SimRigConfig config_;
  std::unique_ptr<sim::Simulator> sim_;
  std::atomic<std::int64_t> t0_{0};
  // Grid instant both pads resume at after a late pad skipped frames (realtime only). The pads
  // of a rig behave as if triggered together: when one falls behind, both skip to the same
  // future instant, so their frames keep pairing instead of drifting apart on a loaded machine.
  std::atomic<std::int64_t> resume_grid_{0};

  // Plan mode. The segments are appended by the RecordedMotion thread (entries first, then the
  // count with release) and read by the capture threads: no lock on the frame path.
  std::string plan_file_;
  std::vector<std::unique_ptr<sim::Simulator>> plan_sims_;
  std::unique_ptr<Segment[]> segments_;
  std::size_t segment_capacity_ = 0;
  std::atomic<std::size_t> segment_count_{0};
  std::array<std::atomic<std::int64_t>, 2> rendered_{};  // last grid frame each pad rendered
  struct PadPlay {  // each touched by its own pad's capture thread only
    std::size_t segment = SIZE_MAX;
    std::int64_t t_ns = -1;
  };
  std::array<PadPlay, 2> play_{};
  std::size_t next_motion_ = 0;  // RecordedMotion thread only
  std::filesystem::path motion_dir_;
  std::unique_ptr<sim::ArmLog> arm_;
};

// The Camera of one simulated pad. open() allocates buffer_count frame buffers, start() joins
// the rig's frame grid, next_frame() renders the pad (on the calling capture thread) and, when
// realtime, sleeps with clock_nanosleep(TIMER_ABSTIME) until the frame's timestamp. A realtime
// camera more than one period behind the wall clock (rendering slower than the frame rate, or a
// consumer calling late) skips to the current frame and counts the skipped ones as drops
// (dropped_before, stats.drops), as a sensor with an overflowing queue would.
//
// Fault injection (any thread, lock-free; takes effect at the next next_frame()):
//  - unplug(): next_frame() returns kDisconnected once (stats.disconnects + 1, link state
//    kDisconnected), then kTimeout after waiting out its timeout, until replug();
//  - replug(): the next next_frame() reconnects (stats.reconnects and reconnect_attempts + 1)
//    and delivers frames again from the current grid time; sequence numbers continue;
//  - drop_frames(n): the next n grid frames are never delivered: the next frame has
//    dropped_before == n and its sequence number jumps by n + 1; stats.drops += n;
//  - stall_for_ms(t): no frames for t ms (next_frame() times out meanwhile), then frames resume
//    at the current grid time with consecutive sequence numbers (a stalled, not a dropping,
//    sensor: its timestamps show the gap).
class SimCamera final : public Camera {
 public:
  ~SimCamera() override;

  CameraStatus open() override;
  CameraStatus start() override;
  CameraStatus next_frame(Frame& frame, int timeout_ms) override;
  void release(const Frame& frame) override;
  void stop() override;
  const CameraInfo& info() const override { return info_; }
  CameraStats stats() const override;
  LinkState link_state() const override { return state_.load(std::memory_order_acquire); }

  void unplug() noexcept { plugged_.store(false, std::memory_order_release); }
  void replug() noexcept { plugged_.store(true, std::memory_order_release); }
  void drop_frames(std::uint32_t n) noexcept { drop_.fetch_add(n, std::memory_order_acq_rel); }
  void stall_for_ms(int ms) noexcept;

  sim::Sensor sensor() const noexcept { return cfg_.sensor; }
  const SimRig& rig() const noexcept { return *rig_; }

 private:
  friend class SimRig;
  SimCamera(std::shared_ptr<SimRig> rig, const SimCameraConfig& config);

  struct Impl;
  std::shared_ptr<SimRig> rig_;
  SimCameraConfig cfg_;
  CameraInfo info_;
  std::unique_ptr<Impl> impl_;
  std::atomic<LinkState> state_{LinkState::kClosed};
  std::atomic<bool> plugged_{true};
  std::atomic<std::uint32_t> drop_{0};
  std::atomic<std::int64_t> stall_until_ns_{0};
};

}  // namespace tacse3::hal
