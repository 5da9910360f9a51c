// SPDX-License-Identifier: Apache-2.0
// tacse3 firmware: the DSP loop body (pairing, pipeline, commands, cycle/status/ack frames).
#include "tacse3/firmware/engine.hpp"
#if TACSE3_HAVE_RECORDER
#include "tacse3/firmware/recorder.hpp"
#endif

#include <algorithm>
#include <cmath>
#include <limits>

namespace tacse3::firmware {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Compile-time adapters for dsp API added at the same time (VelocityProxy::kAuto and the
// per-frame slip flag): the firmware uses them as soon as they exist and builds without them.
template <typename R>
bool slipping(const R& r) noexcept {
  if constexpr (requires { r.slipping; }) {
    return static_cast<bool>(r.slipping);
  } else {
    return false;
  }
}

template <typename E>
E auto_proxy(E fallback) noexcept {
  if constexpr (requires { E::kAuto; }) {
    return E::kAuto;
  } else {
    return fallback;
  }
}

double clamp01_or_nan(double v) noexcept {
  return std::isfinite(v) ? std::clamp(v, 0.0, 1.0) : kNaN;
}

double us_to_s(std::int64_t us) noexcept {
  return us < 0 ? kNaN : static_cast<double>(us) * 1e-6;
}

}  // namespace

dsp::VelocityProxy to_dsp_proxy(protocol::VelocityMode m, dsp::VelocityProxy calibrated) noexcept {
  switch (m) {
    case protocol::VelocityMode::kVelocity:
      return dsp::VelocityProxy::kVelocity;
    case protocol::VelocityMode::kDisplacement:
      return dsp::VelocityProxy::kDisplacement;
    case protocol::VelocityMode::kAuto:
      break;
  }
  return auto_proxy<dsp::VelocityProxy>(calibrated);
}

protocol::FusionMethod to_protocol(dsp::FusionMethod m) noexcept {
  return m == dsp::FusionMethod::kPaper ? protocol::FusionMethod::kPaper
                                        : protocol::FusionMethod::kJoint;
}

dsp::FusionMethod to_dsp(protocol::FusionMethod m) noexcept {
  return m == protocol::FusionMethod::kPaper ? dsp::FusionMethod::kPaper
                                             : dsp::FusionMethod::kJoint;
}

Engine::Engine(const EngineConfig& config, dsp::DualPipeline& pipeline, hal::can::Channel& channel,
               std::array<hal::Camera*, 2> cameras, std::array<FrameRing*, 2> rings,
               std::array<CommandRing*, 2> command_rings, SharedState& shared)
    : config_(config),
      pipeline_(pipeline),
      channel_(channel),
      cameras_(cameras),
      rings_(rings),
      command_rings_(command_rings),
      shared_(shared),
      stagers_{{{pipeline.sensor_mut(dsp::SensorSlot::kLeft), config.clock},
                {pipeline.sensor_mut(dsp::SensorSlot::kRight), config.clock}}},
      machine_(config.health),
      rate_divider_(config.rate_divider),
      stream_enabled_(config.stream_enabled),
      velocity_mode_(config.velocity_mode) {
  for (std::size_t s = 0; s < 2; ++s) observed_[s].configured = config.configured[s];
  if (rings[0] != nullptr || rings[1] != nullptr)
    inline_frames_ = std::make_unique<std::array<StagedFrame, 2>>();
  base_calibration_ = {pipeline.sensor(dsp::SensorSlot::kLeft).calibration(),
                       pipeline.sensor(dsp::SensorSlot::kRight).calibration()};
}

void Engine::set_view(ViewSlot* slot) {
  if (slot != nullptr) {
    view_copies_ = std::make_unique<ViewCopies>();
    for (std::size_t s = 0; s < 2; ++s) stagers_[s].set_view_buffer(&view_copies_->staged[s]);
  }
  view_ = slot;
}

void Engine::start(std::int64_t now_ns) noexcept {
  machine_.start(now_ns);
  next_status_ns_ = now_ns;
  state_ = machine_.update({observed_, false}, now_ns);
  shared_.state.store(static_cast<std::uint8_t>(state_.state), std::memory_order_relaxed);
  tare_seen_ = shared_.tare_requests.load(std::memory_order_acquire);
}

bool Engine::send(const protocol::CanFrame& f) noexcept {
  if (channel_.send(f)) return true;
  ++stats_.send_failures;
  return false;
}

// The pad's next frame, staged by its own thread or, from a raw ring, here (null: none).
StagedFrame* Engine::take_frame(std::size_t s) noexcept {
  if (staged_rings_[s] != nullptr) return staged_rings_[s]->front();
  ArrivedFrame a;
  if (rings_[s] == nullptr || !rings_[s]->pop(a)) return nullptr;
  StagedFrame& f = (*inline_frames_)[s];
  stagers_[s].stage(a, f);
  stagers_[s].run_deferred();  // as a pad's thread does once the frame is handed on
  return &f;
}

void Engine::refill_heads(std::int64_t now_ns) noexcept {
  for (std::size_t s = 0; s < 2; ++s) {
    Head& h = heads_[s];
    if (h.pending.present) continue;
    h.f = take_frame(s);
    if (h.f == nullptr) continue;
    h.pending.present = true;
    h.pending.t_ns = h.f->arrived.frame.timestamp_ns;
    h.pending.arrival_ns = now_ns;
    observed_[s].seen = true;
    observed_[s].last_frame_ns = now_ns;
  }
}

void Engine::release_head(std::size_t s) noexcept {
  Head& h = heads_[s];
  if (!h.pending.present) return;
  // The slot first, then the camera buffer: the camera's next frame, staged into a slot, then
  // always finds one free, so a pad never has more staged frames than camera buffers.
  const hal::Frame frame = h.f->arrived.frame;
  if (staged_rings_[s] != nullptr) staged_rings_[s]->pop();
  if (cameras_[s] != nullptr) cameras_[s]->release(frame);
  h.pending.present = false;
  h.f = nullptr;
}

void Engine::release_all() noexcept {
  for (std::size_t s = 0; s < 2; ++s) {
    release_head(s);
    while ((heads_[s].f = take_frame(s)) != nullptr) {
      heads_[s].pending.present = true;
      release_head(s);
    }
  }
}

// The motion half of what the pad's thread applied before staging f (PadStager): a frame staged
// after a tare restarts the pad's motion, one staged under a new calibration switches its motion
// to it. The frames staged before keep the old ones.
void Engine::apply_pad_requests(std::size_t s, const StagedFrame& f) noexcept {
  dsp::SensorPipeline& p = pipeline_.sensor_mut(static_cast<dsp::SensorSlot>(s));
  if (f.tare_epoch != motion_tare_epoch_[s]) {
    p.reset_motion();
    motion_tare_epoch_[s] = f.tare_epoch;
  }
  if (f.calibration_epoch != motion_calibration_epoch_[s]) {
    dsp::Calibration c = posted_calibration_[s];
    // The running proxy mode survives a reload (AUTO keeps meaning "the file's proxy").
    if (velocity_mode_ != protocol::VelocityMode::kAuto) {
      c.velocity_proxy = to_dsp_proxy(velocity_mode_, c.velocity_proxy);
    }
    (void)p.set_motion_calibration(c);  // validated when posted
    motion_calibration_epoch_[s] = f.calibration_epoch;
  }
}

// Posts the pending reload's image half to each pad not posted yet; true once both are.
bool Engine::post_calibration() noexcept {
  for (std::size_t s = 0; s < 2; ++s) {
    if (reload_posted_[s]) continue;
    // A pad with a frame of its last calibration still ahead of its motion half waits for it.
    const bool after_taken = motion_calibration_epoch_[s] == posted_calibration_epoch_[s];
    const std::uint32_t e = stagers_[s].request_calibration(reload_calibration_[s], after_taken);
    if (e == 0) continue;
    posted_calibration_epoch_[s] = e;
    posted_calibration_[s] = reload_calibration_[s];
    reload_posted_[s] = true;
  }
  return reload_posted_[0] && reload_posted_[1];
}

// Each frame runs on one calibration: the pads take the image half before their next frame's
// stages, the motion half follows at that frame (apply_pad_requests), the pair level now.
void Engine::apply_pending_calibration() noexcept {
  if (shared_.calibration_flag.load(std::memory_order_acquire) != SharedState::kPending) return;
  if (!reload_started_) {
    reload_calibration_ = shared_.calibration;
    const bool valid = dsp::validate(reload_calibration_[0]) == dsp::Status::kOk &&
                       dsp::validate(reload_calibration_[1]) == dsp::Status::kOk;
    if (!valid) {
      shared_.calibration_invalid.store(true, std::memory_order_relaxed);
      shared_.calibration_flag.store(SharedState::kRejected, std::memory_order_release);
      return;
    }
    reload_started_ = true;
    reload_posted_ = {false, false};
  }
  if (!post_calibration()) return;
  reload_started_ = false;
  std::array<dsp::Calibration, 2> cal = reload_calibration_;
  // The running proxy mode survives a reload (AUTO keeps meaning "the file's proxy").
  if (velocity_mode_ != protocol::VelocityMode::kAuto) {
    for (std::size_t s = 0; s < 2; ++s) {
      cal[s].velocity_proxy = to_dsp_proxy(velocity_mode_, cal[s].velocity_proxy);
    }
  }
  (void)pipeline_.set_pair_calibration(cal);  // validated above
  base_calibration_ = reload_calibration_;
  shared_.calibration_invalid.store(false, std::memory_order_relaxed);
  shared_.calibration_flag.store(SharedState::kApplied, std::memory_order_release);
}

// A tare re-takes both references, which also restarts the pose: docs/can-protocol.md defines the
// pose as relative to the last pose reset or tare, and the next cycle carries PoseReset = 1 so a
// controller knows the pose jumped (from the CAN command and from the tare button alike).
void Engine::tare_and_reset_pose() noexcept {
  // DualPipeline::tare() in parts: each pad's next frame to be staged becomes its reference
  // once handed on, and the cycle of the frame after restarts the pad's motion
  // (apply_pad_requests).
  for (PadStager& p : stagers_) (void)p.request_tare();
  pipeline_.restart_filters();
  pipeline_.reset_pose();
  pose_reset_pending_ = true;
}

bool Engine::apply(const protocol::Command& c) noexcept {
  using protocol::CommandCode;
  switch (c.code) {
    case CommandCode::kTare:
      tare_and_reset_pose();
      return true;
    case CommandCode::kResetPose:
      pipeline_.reset_pose();
      pose_reset_pending_ = true;
      return true;
    case CommandCode::kSetFingerSeparation:
      return pipeline_.set_finger_separation(c.finger_separation_m) == dsp::Status::kOk;
    case CommandCode::kSetFusion: {
      // Both parts or neither: the proxy is the one that can fail, so it goes first and the
      // method (which cannot fail for a validated value) second.
      const dsp::VelocityProxy proxy =
          to_dsp_proxy(c.velocity_mode, base_calibration_[0].velocity_proxy);
      if (pipeline_.set_velocity_proxy(proxy) != dsp::Status::kOk) return false;
      if (pipeline_.set_fusion_method(to_dsp(c.fusion)) != dsp::Status::kOk) return false;
      velocity_mode_ = c.velocity_mode;
      return true;
    }
    case CommandCode::kSetRateDivider:
      rate_divider_ = c.rate_divider;
      return true;
    case CommandCode::kSetStream:
      stream_enabled_ = c.stream_enabled;
      return true;
    case CommandCode::kQuery:
      return true;
    case CommandCode::kStartRecording:  // recording_command()
    case CommandCode::kStopRecording:
      return false;
  }
  return false;
}

// START/STOP_RECORDING: decided here, between two cycles; the disk work is the housekeeping
// thread's (RecordingMailbox), so the DSP thread never waits for it. Returns false when the
// answer is deferred: a start is answered by finish_recording_start() once the recording exists.
bool Engine::recording_command(const protocol::Command& c, protocol::Ack& ack) noexcept {
  using protocol::AckCode;
  RecordingMailbox& box = shared_.recording;
  if (c.code == protocol::CommandCode::kStartRecording) {
    if (recorder_ != nullptr || box.start_in_flight()) {
      ack.result = AckCode::kAlreadyRecording;
      return true;
    }
    // The live separation (as last set by SET_FINGER_SEPARATION) goes into the rig block.
    box.request_start({c.recording_number, pipeline_.config().finger_separation_m});
    recording_ack_ = ack;
    return false;
  }
  if (recorder_ == nullptr) {
    ack.result = box.start_in_flight() ? AckCode::kBusy : AckCode::kNotRecording;
    return true;
  }
  bool failed = false;
#if TACSE3_HAVE_RECORDER
  failed = recorder_->failed();
#endif
  if (!box.request_close(recorder_)) {
    ack.result = AckCode::kBusy;  // the previous recording is still being closed
    return true;
  }
  recorder_ = nullptr;
  // A write error had already stopped it: stopped now, but the controller hears of the loss.
  if (failed) ack.result = AckCode::kDiskError;
  return true;
}

bool Engine::finish_recording_start() noexcept {
  FrameRecorder* r = nullptr;
  protocol::AckCode result = protocol::AckCode::kAck;
  if (!shared_.recording.poll_start(&r, &result)) return false;
  recording_ack_.result = result;
  if (result == protocol::AckCode::kAck) recorder_ = r;
  protocol::CanFrame f;
  if (protocol::encode(recording_ack_, config_.tx, f) == protocol::Status::kOk) send(f);
  ++stats_.commands;
  return true;
}

void Engine::handle_command(const protocol::CommandResult& r) noexcept {
  if (!r.addressed) return;
  protocol::Ack ack = protocol::make_ack(r);
  const bool recording = r.command.code == protocol::CommandCode::kStartRecording ||
                         r.command.code == protocol::CommandCode::kStopRecording;
  if (r.code == protocol::AckCode::kAck && recording) {
    if (!recording_command(r.command, ack)) return;  // answered by finish_recording_start()
  } else {
    ack = answer(r);
  }
  protocol::CanFrame f;
  if (protocol::encode(ack, config_.tx, f) == protocol::Status::kOk) send(f);
  ++stats_.commands;
}

// The viewer's controls: the same validation (done by the web side with validate_command) and
// the same application as a CAN command; the answer goes back to the mailbox. Recording is
// started and stopped over CAN or with the button only: its answer may be deferred.
bool Engine::handle_web_command() noexcept {
  protocol::CommandResult r;
  if (web_commands_ == nullptr || !web_commands_->take(&r)) return false;
  const bool recording = r.command.code == protocol::CommandCode::kStartRecording ||
                         r.command.code == protocol::CommandCode::kStopRecording;
  protocol::Ack ack = protocol::make_ack(r);
  if (recording && r.code == protocol::AckCode::kAck) {
    ack.result = protocol::AckCode::kBusy;
  } else {
    ack = answer(r);
  }
  web_commands_->answer(ack);
  ++stats_.commands;
  return true;
}

// Applies a validated, non-recording command (all or nothing) and builds its ACK/NACK.
protocol::Ack Engine::answer(const protocol::CommandResult& r) noexcept {
  protocol::Ack ack = protocol::make_ack(r);
  if (r.code == protocol::AckCode::kAck) {
    if (!apply(r.command)) {
      ack.result = protocol::AckCode::kInternalError;
    } else if (r.command.code == protocol::CommandCode::kQuery) {
      protocol::QueryReply q;
      q.item = r.command.query;
      switch (q.item) {
        case protocol::QueryItem::kProtocolVersion:
          q.version = {protocol::kProtocolVersionMajor, protocol::kProtocolVersionMinor,
                       protocol::kProtocolVersionPatch};
          break;
        case protocol::QueryItem::kFirmwareVersion:
          q.version = {TACSE3_VERSION_MAJOR, TACSE3_VERSION_MINOR, TACSE3_VERSION_PATCH};
          break;
        default:
          break;
      }
      q.finger_separation_m = pipeline_.config().finger_separation_m;
      q.fusion = to_protocol(pipeline_.config().fusion.method);
      q.velocity_mode = velocity_mode_;
      q.stream_enabled = stream_enabled_;
      q.rate_divider = rate_divider_;
      q.fd_mode = config_.tx.frame_mode == protocol::FrameMode::kFd;
      q.extended_ids = config_.tx.endpoint.layout.mode == protocol::IdMode::kExtended;
      ack = protocol::make_query_reply(r.command, q);
    }
  }
  return ack;
}

void Engine::process(bool use_left, bool use_right, std::int64_t now_ns) noexcept {
  const dsp::FrameView* l = use_left ? &heads_[0].f->arrived.frame.view : nullptr;
  const dsp::FrameView* r = use_right ? &heads_[1].f->arrived.frame.view : nullptr;
  // The sample time of a pair is the later timestamp (docs/firmware.md, Pairing).
  std::int64_t t_ns = INT64_MIN;
  for (std::size_t s = 0; s < 2; ++s) {
    if (s == 0 ? use_left : use_right) t_ns = std::max(t_ns, heads_[s].pending.t_ns);
  }
  const dsp::PadStages* stages[2] = {use_left ? &heads_[0].f->stages : nullptr,
                                     use_right ? &heads_[1].f->stages : nullptr};
  for (std::size_t s = 0; s < 2; ++s) {
    if (stages[s] == nullptr) continue;
    apply_pad_requests(s, *heads_[s].f);
    contact_cells_[s] = stages[s]->contact.count;
  }
  const std::int64_t t0 = config_.clock();
  pipeline_.finish(stages[0], stages[1], t_ns, result_);
  // The pipeline time of the sample: its frames' image stages and the finish.
  std::int64_t dsp_ns = config_.clock() - t0;
  for (std::size_t s = 0; s < 2; ++s) {
    if (stages[s] != nullptr) dsp_ns += heads_[s].f->stage_us * 1000;
  }
  last_dsp_us_ = std::clamp<std::int64_t>(dsp_ns / 1000, 0, UINT32_MAX);
  dsp_time_.add(static_cast<std::uint32_t>(last_dsp_us_));
#if TACSE3_HAVE_RECORDER
  if (recorder_ != nullptr) recorder_->record(t_ns, l, r);
#endif
  have_result_ = true;
  last_t_ns_ = t_ns;
  for (PadStager& p : stagers_) p.set_last_sample(t_ns);
  if (use_left && use_right) last_pair_t_ns_ = t_ns;
  ++stats_.samples;
  (use_left && use_right ? stats_.pairs : stats_.singles) += 1;
  shared_.cycles.store(stats_.samples, std::memory_order_relaxed);
  status_sent_this_cycle_ = false;
  last_cycle_ns_ = now_ns;

  for (std::size_t s = 0; s < 2; ++s) {
    const bool present = result_.present[s];
    const bool c = present && result_.fused.contact[s];
    const bool sl = present && slipping(result_.sensors[s]);
    if (c != contact_[s] || sl != slip_[s]) status_dirty_ = true;
    contact_[s] = c;
    slip_[s] = sl;
  }

  const bool emit = stream_enabled_ && (sample_index_ % rate_divider_) == 0;
  ++sample_index_;
  if (emit) emit_cycle(use_left, use_right, t_ns);
  if (use_left) release_head(0);
  if (use_right) release_head(1);
}

// Encodes and sends the cycle of the sample just processed (heads still held: their arrival
// times start the latencies).
void Engine::emit_cycle(bool use_left, bool use_right, std::int64_t t_ns) noexcept {
  protocol::Cycle c;
  c.timestamp_us = static_cast<std::uint64_t>(std::max<std::int64_t>(t_ns, 0) / 1000);
  c.estimate_valid = result_.valid;
  c.single_sensor = result_.single_sensor || !(use_left && use_right);
  c.pose_reset = pose_reset_pending_;
  c.angular = {result_.twist[0], result_.twist[1], result_.twist[2]};
  c.linear = {result_.twist[3], result_.twist[4], result_.twist[5]};
  c.orientation = {result_.pose.q.w(), result_.pose.q.x(), result_.pose.q.y(), result_.pose.q.z()};
  c.position = {result_.pose.p.x(), result_.pose.p.y(), result_.pose.p.z()};
  if (protocol::encode_cycle(c, cycle_counter_, config_.tx, cycle_frames_) !=
      protocol::Status::kOk) {
    return;
  }
  bool all_sent = true;
  for (std::size_t i = 0; i < cycle_frames_.count; ++i)
    all_sent = send(cycle_frames_.frames[i]) && all_sent;
  CycleLatency::Times lt;
  lt.sent_ns = config_.clock();
  lt.sample_ns = t_ns;
  lt.later_arrival_ns = INT64_MIN;
  lt.earlier_arrival_ns = INT64_MAX;
  for (std::size_t s = 0; s < 2; ++s) {
    if (!(s == 0 ? use_left : use_right)) continue;
    lt.later_arrival_ns = std::max(lt.later_arrival_ns, heads_[s].f->arrived.arrival_ns);
    lt.earlier_arrival_ns = std::min(lt.earlier_arrival_ns, heads_[s].f->arrived.arrival_ns);
  }
  latency_.add(lt);
  pose_reset_pending_ = false;
  cycle_counter_ = static_cast<std::uint8_t>((cycle_counter_ + 1) & 0x0F);
  last_cycle_ = cycle_frames_.sent;
  if (all_sent) ++stats_.cycles_sent;
  shared_.emitted.store(stats_.cycles_sent, std::memory_order_relaxed);
}

protocol::StatusMsg Engine::status_message() const noexcept {
  protocol::StatusMsg m;
  m.state = state_.state;
  m.health_left = state_.health[0];
  m.health_right = state_.health[1];
  m.contact_left = contact_[0];
  m.contact_right = contact_[1];
  m.slip_left = slip_[0];
  m.slip_right = slip_[1];
  m.stream_enabled = stream_enabled_;
  m.fusion = to_protocol(pipeline_.config().fusion.method);
  m.velocity_mode = velocity_mode_;
  m.confidence = have_result_ && result_.valid ? clamp01_or_nan(result_.confidence) : kNaN;
  m.rate_divider = rate_divider_;
  m.fault = state_.fault;
  if (m.fault == FaultCode::kNone && shared_.calibration_invalid.load(std::memory_order_relaxed)) {
    m.fault = FaultCode::kCalibrationInvalid;
  }
  if (m.fault == FaultCode::kNone && shared_.can_error_passive.load(std::memory_order_relaxed)) {
    m.fault = FaultCode::kCanErrorPassive;
  }
  m.rejected_commands =
      static_cast<std::uint8_t>(shared_.rejected_commands.load(std::memory_order_relaxed));
  m.calibrated = shared_.calibrated.load(std::memory_order_relaxed);
  return m;
}

void Engine::send_status_group() noexcept {
  protocol::StatusGroup g;
  g.status = status_message();
  for (std::size_t s = 0; s < 2; ++s) {
    const auto& p = pipeline_.sensor(static_cast<dsp::SensorSlot>(s));
    const bool present = have_result_ && state_.health[s] == SensorHealth::kOk;
    const double area =
        present ? viewer::contact_area_m2(p.calibration(), contact_cells_[s]) : kNaN;
    const double conf =
        present ? static_cast<double>(result_.sensors[s].tracked_points) / dsp::kGridCount : kNaN;
    (s == 0 ? g.contact.area_left_m2 : g.contact.area_right_m2) = area;
    (s == 0 ? g.contact.confidence_left : g.contact.confidence_right) = conf;
  }
  g.timing.dsp_time_s = us_to_s(dsp_time_.percentile(50));
  g.timing.latency_p50_s = us_to_s(latency_.sample().percentile(50));
  g.timing.latency_p99_s = us_to_s(latency_.sample().percentile(99));
  for (std::size_t s = 0; s < 2; ++s) {
    const std::uint64_t d =
        shared_.sensors[s].camera_drops.load(std::memory_order_relaxed) + pairing_drops_[s];
    (s == 0 ? g.counters.dropped_left : g.counters.dropped_right) = static_cast<std::uint16_t>(d);
  }
  g.counters.can_tx_dropped =
      static_cast<std::uint16_t>(shared_.can_tx_dropped.load(std::memory_order_relaxed));
  std::array<protocol::CanFrame, 4> frames;
  if (protocol::encode_status_group(g, status_counter_, config_.tx, frames) ==
      protocol::Status::kOk) {
    for (const auto& f : frames) send(f);
  }
  status_counter_ = static_cast<std::uint8_t>((status_counter_ + 1) & 0x0F);
  status_sent_this_cycle_ = true;
  status_dirty_ = false;
  ++stats_.status_groups;
}

void Engine::send_status_change() noexcept {
  // A change-triggered Status is the Status frame alone with the next status counter value
  // (docs/can-protocol.md); the group encoder is what stamps that counter.
  protocol::StatusGroup g;
  g.status = status_message();
  std::array<protocol::CanFrame, 4> frames;
  if (protocol::encode_status_group(g, status_counter_, config_.tx, frames) ==
      protocol::Status::kOk) {
    send(frames[0]);
  }
  status_counter_ = static_cast<std::uint8_t>((status_counter_ + 1) & 0x0F);
  status_sent_this_cycle_ = true;
  status_dirty_ = false;
  ++stats_.status_changes;
}

void Engine::update_state(std::int64_t now_ns) noexcept {
  for (std::size_t s = 0; s < 2; ++s) {
    observed_[s].disconnected = shared_.sensors[s].disconnected.load(std::memory_order_acquire);
  }
  const StateOutput next = machine_.update({observed_, contact_[0] || contact_[1]}, now_ns);
  if (next.state != state_.state || next.health != state_.health) status_dirty_ = true;
  if (next.state == State::kDegradedSingleSensor && state_.state != next.state &&
      last_pair_t_ns_ != INT64_MIN) {
    stats_.degraded_after_pair_ns = last_t_ns_ - last_pair_t_ns_;
  }
  state_ = next;
  shared_.state.store(static_cast<std::uint8_t>(state_.state), std::memory_order_relaxed);
}

bool Engine::step(std::int64_t now_ns) noexcept {
  bool worked = false;
  shared_.heartbeat.fetch_add(1, std::memory_order_relaxed);
  apply_pending_calibration();
  if (finish_recording_start()) worked = true;

  // Commands first: they apply between two cycles, all or nothing.
  for (CommandRing* ring : command_rings_) {
    protocol::CommandResult r;
    while (ring != nullptr && ring->pop(r)) {
      handle_command(r);
      worked = true;
    }
  }
  if (handle_web_command()) worked = true;
  const std::uint32_t taps = shared_.tare_requests.load(std::memory_order_acquire);
  if (taps != tare_seen_) {
    tare_seen_ = taps;
    tare_and_reset_pose();
    worked = true;
  }

  // At most one processed cycle per step: the caller comes straight back with a fresh clock, so
  // the 10 Hz Status below is never starved by a backlog of frames (a slow core working through
  // 16 queued cycles at 60 ms each would otherwise hold it back for a second). Late-frame drops
  // are cheap and keep looping.
  // The pads copy the viewer's fields from their next frame once a view is due within a period.
  if (view_ != nullptr && now_ns + config_.frame_period_ns >= next_view_ns_) {
    for (PadStager& p : stagers_) p.want_view_fields();
  }
  bool processed = false;
  for (int guard = 0; guard < 16 && !processed; ++guard) {
    refill_heads(now_ns);
    update_state(now_ns);
    // While booting, a configured sensor that has not delivered yet (and is not known lost) is
    // waited for (up to the pairing's max wait), so the first instant is processed as a pair
    // rather than as one pad alone because its partner's first frame came a moment later.
    const bool booting = state_.state == protocol::State::kBooting;
    const auto alive = [&](std::size_t s) {
      return state_.health[s] == SensorHealth::kOk ||
             (booting && observed_[s].configured && !observed_[s].disconnected);
    };
    const bool left_alive = alive(0);
    const bool right_alive = alive(1);
    const PairAction a = decide_pairing(heads_[0].pending, heads_[1].pending, left_alive,
                                        right_alive, last_t_ns_, now_ns, config_.pairing);
    if (a == PairAction::kWait) break;
    worked = true;
    switch (a) {
      case PairAction::kPair:
        process(true, true, now_ns);
        processed = true;
        break;
      case PairAction::kLeftAlone:
        process(true, false, now_ns);
        processed = true;
        break;
      case PairAction::kRightAlone:
        process(false, true, now_ns);
        processed = true;
        break;
      case PairAction::kDropLeft:
      case PairAction::kDropRight: {
        const std::size_t s = a == PairAction::kDropLeft ? 0 : 1;
        release_head(s);
        ++pairing_drops_[s];
        ++stats_.dropped_late;
        break;
      }
      case PairAction::kWait:
        break;
    }
  }
  update_state(now_ns);

  // Status: the periodic group at 10 Hz; a change-triggered Status at most once per cycle, or,
  // once the stream has stopped (no cycle for two frame periods: the second pad of a board going
  // a few ms after the first, with no cycle left to count), once per frame period.
  const bool stream_stopped = now_ns - last_cycle_ns_ >= 2 * config_.frame_period_ns &&
                              now_ns - last_status_ns_ >= config_.frame_period_ns;
  if (now_ns >= next_status_ns_) {
    send_status_group();
    last_status_ns_ = now_ns;
    next_status_ns_ += config_.status_period_ns;
    if (next_status_ns_ <= now_ns) next_status_ns_ = now_ns + config_.status_period_ns;
    worked = true;
  } else if (status_dirty_ && (!status_sent_this_cycle_ || stream_stopped)) {
    send_status_change();
    last_status_ns_ = now_ns;
    worked = true;
  }
  channel_.service();
  if (view_ != nullptr && now_ns >= next_view_ns_) publish_view(now_ns);
  return worked;
}

// The live viewer's copy: at most every kViewPeriodNs, a bounded copy into the slot's back
// buffer (no allocation, no lock); the viewer thread encodes and serves it.
void Engine::publish_view(std::int64_t now_ns) noexcept {
  ViewSnapshot& v = view_->back();
  v.cycle = stats_.samples;
  v.t_us = have_result_ ? last_t_ns_ / 1000 : 0;
  v.state = static_cast<std::uint8_t>(state_.state);
  v.have_result = have_result_;
  v.valid = have_result_ && result_.valid;
  v.single_sensor = result_.single_sensor;
  v.calibrated = shared_.calibrated.load(std::memory_order_relaxed);
  for (int i = 0; i < 3; ++i) {
    v.w[static_cast<std::size_t>(i)] = result_.twist[i];
    v.v[static_cast<std::size_t>(i)] = result_.twist[i + 3];
  }
  v.q = {result_.pose.q.w(), result_.pose.q.x(), result_.pose.q.y(), result_.pose.q.z()};
  v.p = {result_.pose.p.x(), result_.pose.p.y(), result_.pose.p.z()};
  v.confidence = have_result_ && result_.valid ? clamp01_or_nan(result_.confidence) : 0.0;
  v.dsp_us = have_result_ ? last_dsp_us_ : -1;
  v.latency_us = latency_.last_sample_us();
  for (std::size_t s = 0; s < 2; ++s) {
    (void)stagers_[s].take_view_fields(&view_copies_->pads[s], &view_contact_cells_[s]);
    v.pads[s] = view_copies_->pads[s];
  }
  fill_view_pads(pipeline_, result_, state_, config_.configured, view_contact_cells_, &v);
  v.counters.cycles_sent = stats_.cycles_sent;
  v.counters.can_send_failures = stats_.send_failures;
  v.counters.can_tx_dropped = shared_.can_tx_dropped.load(std::memory_order_relaxed);
  v.counters.commands = stats_.commands;
  v.counters.rejected_commands = shared_.rejected_commands.load(std::memory_order_relaxed);
  for (std::size_t s = 0; s < 2; ++s) {
    v.pads[s].frames = shared_.sensors[s].frames.load(std::memory_order_relaxed);
    v.pads[s].dropped =
        shared_.sensors[s].camera_drops.load(std::memory_order_relaxed) + pairing_drops_[s];
  }
  view_->publish();
  next_view_ns_ = now_ns + viewer::kViewPeriodNs;
}

}  // namespace tacse3::firmware
