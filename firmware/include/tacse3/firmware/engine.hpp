// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: the DSP thread's loop body: pair frames, run the pipeline, apply commands,
// emit cycles, status and acks on the CAN channel. No heap, no locks, no blocking per frame.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>

#include "tacse3/dsp/pipeline.hpp"
#include "tacse3/firmware/health.hpp"
#include "tacse3/firmware/latency.hpp"
#include "tacse3/firmware/pad_stager.hpp"
#include "tacse3/firmware/pairing.hpp"
#include "tacse3/firmware/recording_mailbox.hpp"
#include "tacse3/firmware/view_fill.hpp"
#include "tacse3/hal/camera.hpp"
#include "tacse3/hal/camera/clock.hpp"
#include "tacse3/hal/camera/spsc_ring.hpp"
#include "tacse3/hal/can/channel.hpp"
#include "tacse3/protocol/codec.hpp"
#include "tacse3/protocol/commands.hpp"
#include "tacse3/viewer/command_mailbox.hpp"

namespace tacse3::firmware {

class FrameRecorder;

// RX thread / housekeeping -> DSP thread: validated commands (or NACK reasons) to answer.
using CommandRing = hal::SpscRing<protocol::CommandResult, 16>;
using viewer::CommandMailbox;

// State shared between the threads: plain atomics, written by one side, read by the other.
struct SharedState {
  struct Sensor {
    std::atomic<bool> disconnected{false};       // capture thread: the camera reported a loss
    std::atomic<std::uint64_t> camera_drops{0};  // capture thread: sequence gaps + ring overflow
    std::atomic<std::uint64_t> frames{0};        // capture thread: frames handed to the ring
  };
  std::array<Sensor, 2> sensors{};
  std::atomic<std::uint64_t> heartbeat{0};      // DSP thread: +1 per loop iteration
  std::atomic<std::uint8_t> state{0};           // DSP thread: protocol::State
  std::atomic<std::uint64_t> cycles{0};         // DSP thread: processed samples
  std::atomic<std::uint64_t> emitted{0};        // DSP thread: cycles sent
  std::atomic<std::uint32_t> tare_requests{0};  // housekeeping: tare button presses (cumulative)
  std::atomic<std::uint32_t> rejected_commands{0};  // RX thread: CommandStats::rejected()
  std::atomic<std::uint64_t> can_tx_dropped{0};     // housekeeping: channel stats
  std::atomic<bool> can_error_passive{false};       // housekeeping: channel stats
  // Calibration reload (SIGHUP): housekeeping fills `calibration` while flag == kIdle and sets
  // kPending; the DSP thread applies it between cycles and answers kApplied / kRejected.
  enum : int { kIdle = 0, kPending = 1, kApplied = 2, kRejected = 3 };
  std::atomic<int> calibration_flag{kIdle};
  std::array<dsp::Calibration, 2> calibration{};
  std::atomic<bool> calibration_invalid{false};  // the last reload failed (status fault code)
  std::atomic<bool> calibrated{false};  // daemon: a fitted calibration runs (Status Calibrated)
  RecordingMailbox recording;           // START/STOP_RECORDING: DSP thread <-> housekeeping
};

struct EngineConfig {
  protocol::TxConfig tx{};
  PairingConfig pairing{};
  HealthConfig health{};
  std::array<bool, 2> configured{true, true};
  std::uint8_t rate_divider = 1;
  bool stream_enabled = true;
  protocol::VelocityMode velocity_mode = protocol::VelocityMode::kAuto;
  std::int64_t status_period_ns = 100'000'000;  // 10 Hz
  // The sensors' nominal frame period. A change-triggered Status goes out at most once per
  // processed cycle. When the stream has stopped (no cycle for two periods: both pads gone), a
  // change goes out once a period has passed since the last Status, instead of waiting for the
  // next 10 Hz group; it fills a cycle slot that stayed empty, so the budget of one Status per
  // frame period holds on average (docs/can-protocol.md). The configured rate: a camera that
  // grants less (60 of 120 fps) makes every gap between two cycles "stopped", which allows one
  // more Status per cycle, within the same budget in Status frames per second.
  std::int64_t frame_period_ns = 8'333'333;  // 120 Hz
  // The clock the DSP time and the send time are read from (tests inject their own).
  std::int64_t (*clock)() noexcept = &hal::monotonic_ns;
};

struct EngineStats {
  std::uint64_t samples = 0;         // processed frame pairs / single frames
  std::uint64_t pairs = 0;           // both sensors
  std::uint64_t singles = 0;         // one sensor alone
  std::uint64_t dropped_late = 0;    // heads older than the last sample
  std::uint64_t cycles_sent = 0;     // cycles encoded and handed to the channel
  std::uint64_t send_failures = 0;   // Channel::send returned false
  std::uint64_t status_groups = 0;   // periodic status emissions
  std::uint64_t status_changes = 0;  // change-triggered Status frames
  std::uint64_t commands = 0;        // commands answered
  // Sample time from the last frame pair to the sample at which the state last became
  // DEGRADED_SINGLE_SENSOR (-1: never): how many frame periods a lost sensor went unnoticed.
  std::int64_t degraded_after_pair_ns = -1;
};

// Each pad's image stages run on the thread that owns its PadStager: the pad's capture thread
// (the daemon: its frames come staged through set_staged_rings) or, for a pad whose frames come
// raw through `rings`, the DSP thread itself when it takes them (tests). The rest of a sample
// (motion, fusion, SE(3), CAN) is the DSP thread's.
class Engine {
 public:
  // The pipeline must be configured; cameras may be null (no such sensor / tests without one).
  Engine(const EngineConfig& config, dsp::DualPipeline& pipeline, hal::can::Channel& channel,
         std::array<hal::Camera*, 2> cameras, std::array<FrameRing*, 2> rings,
         std::array<CommandRing*, 2> command_rings, SharedState& shared);

  void start(std::int64_t now_ns) noexcept;
  // --record: every processed instant also goes to the recorder (null: not recording). Set
  // before the DSP thread starts; START/STOP_RECORDING change it later (through
  // SharedState::recording).
  void set_recorder(FrameRecorder* recorder) noexcept { recorder_ = recorder; }
  // --http: the slot the live viewer reads (null: no viewer, nothing is published). Set before
  // the DSP thread starts; it allocates the viewer's per-pad copies, which a daemon without a
  // viewer never holds.
  void set_view(ViewSlot* slot);
  // [viewer] controls: the mailbox the viewer's POST /api/command writes (null: no controls).
  // Set before the DSP thread starts.
  void set_web_commands(CommandMailbox* box) noexcept { web_commands_ = box; }
  // Pads whose frames arrive staged by their own thread (stager(s).stage) instead of raw through
  // the constructor's rings (null: that pad's ring). Set before the DSP thread starts.
  void set_staged_rings(std::array<StagedRing*, 2> rings) noexcept { staged_rings_ = rings; }
  PadStager& stager(std::size_t s) noexcept { return stagers_[s]; }
  // One loop iteration at now_ns (CLOCK_MONOTONIC). Returns true when it did work (the caller
  // sleeps briefly when it did not).
  bool step(std::int64_t now_ns) noexcept;
  // Hands every frame still held back to its camera (before the cameras stop).
  void release_all() noexcept;

  const EngineStats& stats() const noexcept { return stats_; }
  const StateOutput& state() const noexcept { return state_; }
  const protocol::Cycle& last_cycle() const noexcept { return last_cycle_; }  // as sent
  const dsp::DualResult& last_result() const noexcept { return result_; }
  // SampleTime -> cycle handed to the channel (StatusTiming); the arrival latencies are in
  // latency().
  std::int64_t latency_percentile_us(double p) const noexcept {
    return latency_.sample().percentile(p);
  }
  const CycleLatency& latency() const noexcept { return latency_; }
  std::int64_t dsp_time_percentile_us(double p) const noexcept { return dsp_time_.percentile(p); }
  std::uint8_t rate_divider() const noexcept { return rate_divider_; }
  bool stream_enabled() const noexcept { return stream_enabled_; }
  protocol::VelocityMode velocity_mode() const noexcept { return velocity_mode_; }

 private:
  // A pad's oldest frame not yet in a cycle, its image stages (1-6) done (PadStager::stage):
  // the front of its staged ring, or the pad's inline slot.
  struct Head {
    PendingFrame pending;
    StagedFrame* f = nullptr;
  };
  void refill_heads(std::int64_t now_ns) noexcept;
  StagedFrame* take_frame(std::size_t s) noexcept;
  void release_head(std::size_t s) noexcept;
  void apply_pad_requests(std::size_t s, const StagedFrame& f) noexcept;
  bool post_calibration() noexcept;
  void process(bool use_left, bool use_right, std::int64_t now_ns) noexcept;
  void emit_cycle(bool use_left, bool use_right, std::int64_t t_ns) noexcept;
  void handle_command(const protocol::CommandResult& r) noexcept;
  bool handle_web_command() noexcept;
  protocol::Ack answer(const protocol::CommandResult& r) noexcept;
  bool recording_command(const protocol::Command& c, protocol::Ack& ack) noexcept;
  bool finish_recording_start() noexcept;
  void tare_and_reset_pose() noexcept;
  bool apply(const protocol::Command& c) noexcept;
  void apply_pending_calibration() noexcept;
  void update_state(std::int64_t now_ns) noexcept;
  protocol::StatusMsg status_message() const noexcept;
  void send_status_group() noexcept;
  void send_status_change() noexcept;
  void publish_view(std::int64_t now_ns) noexcept;
  bool send(const protocol::CanFrame& f) noexcept;

  EngineConfig config_;
  dsp::DualPipeline& pipeline_;
  hal::can::Channel& channel_;
  std::array<hal::Camera*, 2> cameras_;
  std::array<FrameRing*, 2> rings_;
  std::array<CommandRing*, 2> command_rings_;
  SharedState& shared_;

  std::array<StagedRing*, 2> staged_rings_{};
  std::array<PadStager, 2> stagers_;
  std::array<Head, 2> heads_{};
  // A pad staged here, from its raw ring: allocated only when the constructor is given one.
  std::unique_ptr<std::array<StagedFrame, 2>> inline_frames_;
  // Each pad's motion half follows its image half (PadStager): the tare and calibration epochs
  // its motion state is at, and the calibration whose image half was posted last.
  std::array<std::uint32_t, 2> motion_tare_epoch_{};
  std::array<std::uint32_t, 2> motion_calibration_epoch_{};
  std::array<std::uint32_t, 2> posted_calibration_epoch_{};
  std::array<dsp::Calibration, 2> posted_calibration_{};
  std::array<dsp::Calibration, 2> reload_calibration_{};  // the reload being posted
  std::array<bool, 2> reload_posted_{};                   // its image half posted to the pad
  bool reload_started_ = false;
  std::array<int, 2> contact_cells_{};  // |Ω| of each pad's last frame in a cycle
  // With a viewer (set_view): the viewer's grid fields and image of each pad, from a frame staged
  // at most a frame period before the view is due (PadStager::want_view_fields), and the copies
  // the pads' threads fill for them.
  struct ViewCopies {
    std::array<viewer::ViewPad, 2> pads{};
    std::array<viewer::ViewPad, 2> staged{};
  };
  std::unique_ptr<ViewCopies> view_copies_;
  std::array<int, 2> view_contact_cells_{};
  std::array<SensorObservation, 2> observed_{};
  std::array<std::uint64_t, 2> pairing_drops_{};
  StateMachine machine_;
  StateOutput state_{};
  dsp::DualResult result_{};
  protocol::CycleFrames cycle_frames_{};
  protocol::Cycle last_cycle_{};
  std::array<dsp::Calibration, 2> base_calibration_{};
  CycleLatency latency_;
  TimingWindow<> dsp_time_;
  std::int64_t last_t_ns_ = INT64_MIN;
  std::int64_t last_pair_t_ns_ = INT64_MIN;
  std::int64_t next_status_ns_ = 0;
  std::int64_t last_status_ns_ = 0;  // loop clock of the last Status, periodic or on change
  std::int64_t last_cycle_ns_ = 0;   // loop clock of the last processed cycle
  std::uint64_t sample_index_ = 0;
  std::uint8_t cycle_counter_ = 0;
  std::uint8_t status_counter_ = 0;
  std::uint8_t rate_divider_ = 1;
  bool stream_enabled_ = true;
  bool pose_reset_pending_ = false;
  bool status_sent_this_cycle_ = false;
  bool status_dirty_ = false;
  bool have_result_ = false;
  std::uint32_t tare_seen_ = 0;
  protocol::VelocityMode velocity_mode_ = protocol::VelocityMode::kAuto;
  std::array<bool, 2> contact_{};
  std::array<bool, 2> slip_{};
  EngineStats stats_{};
  FrameRecorder* recorder_ = nullptr;
  ViewSlot* view_ = nullptr;
  CommandMailbox* web_commands_ = nullptr;
  std::int64_t next_view_ns_ = INT64_MIN;
  std::int64_t last_dsp_us_ = -1;
  protocol::Ack recording_ack_{};  // the START_RECORDING answer waiting for housekeeping
};

// The dsp proxy a protocol mode maps to: AUTO is the pipeline's own kAuto when dsp has one,
// else the calibration's own proxy (`calibrated`).
dsp::VelocityProxy to_dsp_proxy(protocol::VelocityMode m, dsp::VelocityProxy calibrated) noexcept;
protocol::FusionMethod to_protocol(dsp::FusionMethod m) noexcept;
dsp::FusionMethod to_dsp(protocol::FusionMethod m) noexcept;

}  // namespace tacse3::firmware
