// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the per-sensor and dual-sensor TacSE3 pipelines that chain every stage per frame.
#include "tacse3/dsp/pipeline.hpp"

#include <cmath>

#include "tacse3/dsp/luma.hpp"

namespace tacse3::dsp {
namespace {

bool finite_in(double v, double lo, double hi) noexcept {
  return std::isfinite(v) && v >= lo && v <= hi;
}

}  // namespace

Status validate(const PipelineConfig& config) noexcept {
  if (validate(config.flow) != Status::kOk) return Status::kBadArgument;
  // The smoother, density and NHHD validate in their configure(); probe them on scratch objects
  // would cost ~100 KB of stack, so their ranges are re-checked when SensorPipeline configures.
  if (!finite_in(config.min_tracked_fraction, 1e-6, 1.0)) return Status::kBadArgument;
  return Status::kOk;
}

SensorPipeline::SensorPipeline() noexcept {
  (void)configure(PipelineConfig{}, Calibration{});
}

Status SensorPipeline::configure(const PipelineConfig& config, const Calibration& cal) noexcept {
  if (validate(config) != Status::kOk) return Status::kBadArgument;
  if (validate(cal) != Status::kOk) return Status::kBadCalibration;
  // Stage configure() calls keep their previous state on error, so check them all on the live
  // objects in an order where a failure leaves everything as it was: the stages that can reject
  // a config are probed first with their current config restored on failure.
  const SmoothingConfig old_smoothing = smoother_.config();
  const DensityConfig old_density = density_.config();
  const NhhdConfig old_nhhd = nhhd_.config();
  if (smoother_.configure(config.smoothing) != Status::kOk) return Status::kBadArgument;
  if (density_.configure(config.density) != Status::kOk) {
    (void)smoother_.configure(old_smoothing);
    return Status::kBadArgument;
  }
  if (nhhd_.configure(config.nhhd) != Status::kOk) {
    (void)smoother_.configure(old_smoothing);
    (void)density_.configure(old_density);
    return Status::kBadArgument;
  }
  (void)old_nhhd;
  (void)flow_.configure(config.flow);  // validated above
  (void)forces_.configure(cal);        // validated above
  (void)contact_.configure(cal);
  (void)motion_.configure(cal);
  config_ = config;
  cal_ = cal;
  image_filter_ = work_image_filter(cal);
  min_tracked_points_ =
      static_cast<int>(std::ceil(config.min_tracked_fraction * static_cast<double>(kGridCount)));
  nhhd_.reset();
  contact_.reset();
  motion_.reset();
  return Status::kOk;
}

Status SensorPipeline::set_calibration(const Calibration& cal) noexcept {
  if (set_image_calibration(cal) != Status::kOk) return Status::kBadCalibration;
  return set_motion_calibration(cal);
}

Status SensorPipeline::set_image_calibration(const Calibration& cal) noexcept {
  if (validate(cal) != Status::kOk) return Status::kBadCalibration;
  (void)forces_.configure(cal);
  (void)contact_.configure(cal);
  if (work_image_filter(cal) != image_filter_) {
    // Another filter gives another image: the reference and the keyframes no longer match it,
    // so the next frame becomes the reference.
    image_filter_ = work_image_filter(cal);
    flow_.drop_reference();
    nhhd_.reset();
    contact_.reset();
  }
  return Status::kOk;
}

Status SensorPipeline::set_motion_calibration(const Calibration& cal) noexcept {
  if (validate(cal) != Status::kOk) return Status::kBadCalibration;
  (void)motion_.configure(cal);
  cal_ = cal;
  return Status::kOk;
}

void SensorPipeline::tare() noexcept {
  tare_image();
  reset_motion();
}

void SensorPipeline::tare_image() noexcept {
  // The last processed frame is still in fields_.work: it becomes the reference now, so the
  // very next frame already measures against it. Before any frame, the first frame becomes it.
  if (flow_.has_reference()) flow_.tare(fields_.work);
  nhhd_.reset();
  contact_.reset();
}

void SensorPipeline::reset_motion() noexcept {
  motion_.reset();
}

void SensorPipeline::restart_motion() noexcept {
  motion_.restart();
}

void SensorPipeline::process(const FrameView& frame, double dt_s, SensorResult& out) noexcept {
  PadStages& stages = scratch_;
  process_image(frame, stages);
  finish_motion(stages, dt_s, out);
  run_deferred();
}

void SensorPipeline::process_image(const FrameView& frame, PadStages& stages) noexcept {
  SensorResult& out = stages.result;
  out = SensorResult{};
  // Stage 1 (Sec. IV-B): luma and the calibrated filter's 2:1 downsample. A malformed frame is
  // rejected before any state is touched; check_frame and the conversion share the same rules.
  const Status input = check_frame(frame);
  if (input != Status::kOk) {
    out.status = input;
    return;
  }
  (void)frame_to_work_image(frame, fields_.work, image_filter_);

  // Stage 2: block flow against the adaptive reference, Eq. (dense_flow). Without one, this frame
  // becomes it (in the deferred work) and tracks nothing: that is not a degraded frame.
  out.reference_taken = !flow_.has_reference();
  flow_.track(fields_.work, fields_.flow, fields_.flow_valid);
  out.tracked_points = flow_.valid_count();
  out.keyframe_switches = flow_.keyframe_switches();
  out.keyframe_switched = flow_.last_frame_was_keyframe();

  // Stage 3: separable Gaussian smoothing, then the Gaussian density 𝒢.
  smoother_.apply(fields_.flow, fields_.flow_valid, fields_.smoothed, fields_.smoothed_valid);
  density_.compute(fields_.smoothed, fields_.smoothed_valid, fields_.density);

  // Stage 4: NHHD w = d + r + k, Eq. (nhhd), fixed work per frame, warm-started.
  nhhd_.decompose(fields_.smoothed, fields_.smoothed_valid, fields_.d, fields_.r, fields_.k);

  // Stage 5: calibrated linear maps to f^z and shear.
  forces_.compute(fields_.density, fields_.d, fields_.r, fields_.k, fields_.smoothed_valid,
                  fields_.fz, fields_.shear);

  // Stage 6: contact mask Ω and 3D contact points q at the points' current positions.
  contact_.detect(fields_.fz, fields_.smoothed, fields_.smoothed_valid, fields_.contact);

  out.processed = true;
  out.degraded = !out.reference_taken && out.tracked_points < min_tracked_points_;
  stages.contact = fields_.contact;
  stages.shear = fields_.shear;
}

void SensorPipeline::finish_motion(const PadStages& stages, double dt_s,
                                   SensorResult& out) noexcept {
  out = stages.result;
  if (!out.processed) return;
  if (out.degraded) {
    // Too little of the pad is trackable (dark, saturated, occluded or unrelated frame): its
    // shear would be stale, so the motion state restarts instead of differentiating across it.
    motion_.reset();
    return;
  }
  const double dt = (std::isfinite(dt_s) && dt_s > 0.0 && dt_s <= 1.0) ? dt_s : 1.0 / 120.0;
  // Stages 7-8: centroid translation, velocity proxy, moments and the own-frame ω solve.
  (void)motion_.update(stages.contact, stages.shear, dt, out.motion);
  out.slipping = out.motion.slipping;
}

Status validate(const DualConfig& config) noexcept {
  if (validate(config.pipeline) != Status::kOk) return Status::kBadArgument;
  if (validate(config.fusion) != Status::kOk) return Status::kBadArgument;
  if (!finite_in(config.finger_separation_m, 0.0, 0.5)) return Status::kBadArgument;
  if (!finite_in(config.nominal_frame_period_s, 1e-4, 1.0)) return Status::kBadArgument;
  if (!finite_in(config.max_frame_gap_s, 1e-4, 1.0)) return Status::kBadArgument;
  return Status::kOk;
}

ConfidenceConfig confidence_config(const PipelineConfig& config, const Calibration& cal) noexcept {
  ConfidenceConfig c;
  c.rest_speed_m_s = cal.stick_rest_speed_m_s;
  // The matching window's width in cells, uniform: variance w²/12; the smoothing's σ².
  const double window_cells = static_cast<double>(kFlowWindow) / kGridStride;
  const double sigma = config.smoothing.sigma_cells;
  c.footprint_cells = std::sqrt(sigma * sigma + window_cells * window_cells / 12.0);
  c.catchup_frames = cal.slip_catchup_frames;
  c.smoothing_s = cal.slip_smoothing_s;
  return c;
}

DualPipeline::DualPipeline() noexcept {
  (void)configure(DualConfig{}, std::array<Calibration, 2>{Calibration{}, Calibration{}});
}

Status DualPipeline::configure(const DualConfig& config,
                               const std::array<Calibration, 2>& cal) noexcept {
  if (validate(config) != Status::kOk) return Status::kBadArgument;
  for (const auto& c : cal) {
    if (validate(c) != Status::kOk) return Status::kBadCalibration;
  }
  for (std::size_t i = 0; i < sensors_.size(); ++i) {
    const Status s = sensors_[i].configure(config.pipeline, cal[i]);
    if (s != Status::kOk) return s;
  }
  (void)average_.set_length(cal[0].moving_average_length);
  payback_.configure(cal[0].slip_catchup_frames);
  payback_.reset();
  confidence_.configure(confidence_config(config.pipeline, cal[0]));
  config_ = config;
  cal_ = cal;
  integrator_.reset();
  have_last_t_ = false;
  return Status::kOk;
}

Status DualPipeline::set_calibration(const std::array<Calibration, 2>& cal) noexcept {
  for (const auto& c : cal) {
    if (validate(c) != Status::kOk) return Status::kBadCalibration;
  }
  for (std::size_t i = 0; i < sensors_.size(); ++i) (void)sensors_[i].set_calibration(cal[i]);
  return set_pair_calibration(cal);
}

Status DualPipeline::set_pair_calibration(const std::array<Calibration, 2>& cal) noexcept {
  for (const auto& c : cal) {
    if (validate(c) != Status::kOk) return Status::kBadCalibration;
  }
  if (cal[0].moving_average_length != average_.length()) {
    (void)average_.set_length(cal[0].moving_average_length);
  }
  payback_.configure(cal[0].slip_catchup_frames);
  confidence_.configure(confidence_config(config_.pipeline, cal[0]));
  // Entering or leaving kAuto on either sensor: the pending payback belongs to the old mode.
  for (std::size_t i = 0; i < cal.size(); ++i) {
    if ((cal[i].velocity_proxy == VelocityProxy::kAuto) !=
        (cal_[i].velocity_proxy == VelocityProxy::kAuto)) {
      payback_.reset();
    }
  }
  cal_ = cal;
  return Status::kOk;
}

void DualPipeline::process(const FrameView* left, const FrameView* right, std::int64_t t_ns,
                           DualResult& out) noexcept {
  if (left != nullptr) process_pad(SensorSlot::kLeft, *left, stages_[0]);
  if (right != nullptr) process_pad(SensorSlot::kRight, *right, stages_[1]);
  finish(left != nullptr ? &stages_[0] : nullptr, right != nullptr ? &stages_[1] : nullptr, t_ns,
         out);
  for (SensorPipeline& p : sensors_) p.run_deferred();
}

void DualPipeline::process_pad(SensorSlot s, const FrameView& frame, PadStages& out) noexcept {
  sensors_[static_cast<std::size_t>(s)].process_image(frame, out);
}

void DualPipeline::finish(const PadStages* left, const PadStages* right, std::int64_t t_ns,
                          DualResult& out) noexcept {
  out.t_ns = t_ns;
  out.present = {left != nullptr, right != nullptr};

  // Step: measured from the sample times; nominal for the first pair or a clock that did not
  // advance. A gap longer than max_frame_gap_s restarts the per-sensor motion differencing.
  double dt = config_.nominal_frame_period_s;
  bool gap = false;
  if (have_last_t_ && t_ns > last_t_ns_) {
    dt = static_cast<double>(t_ns - last_t_ns_) * 1e-9;
    if (dt > config_.max_frame_gap_s) {
      gap = true;
      dt = config_.nominal_frame_period_s;
    }
  }
  last_t_ns_ = t_ns;
  have_last_t_ = true;
  out.dt_s = dt;

  const PadStages* stages[2] = {left, right};
  const SensorMotion* motions[2] = {nullptr, nullptr};
  for (std::size_t i = 0; i < 2; ++i) {
    SensorResult& r = out.sensors[i];
    out.slipping[i] = false;
    if (stages[i] == nullptr) {
      r = SensorResult{};
      // A sensor that misses a cycle must not difference its next frame against a stale one.
      sensors_[i].restart_motion();
      continue;
    }
    if (gap) sensors_[i].restart_motion();
    sensors_[i].finish_motion(*stages[i], dt, r);
    if (r.processed && !r.degraded) motions[i] = &r.motion;
    out.slipping[i] = r.slipping;
  }

  // Fusion (Sec. V-B) in G; an absent sensor gives the flagged single-sensor mode.
  (void)fuse(motions[0], motions[1], config_.fusion, config_.finger_separation_m, out.fused);
  out.valid = out.fused.valid;
  out.single_sensor = out.fused.single_sensor;

  // kAuto: the same frame fused from the velocity readings, and the slip payback of their
  // difference (slip_payback.hpp). In the fixed modes the readings are equal and nothing is paid.
  SlipPayback::Frame pf;
  pf.confirmed = true;
  bool any_stuck = false;
  for (std::size_t i = 0; i < 2; ++i) {
    if (motions[i] == nullptr) continue;
    any_stuck = any_stuck || motions[i]->velocity_differs;
    if (!motions[i]->contact) continue;
    pf.contact = true;
    pf.onset = pf.onset || motions[i]->slip_onset;
    pf.confirmed = pf.confirmed && motions[i]->stick_confirmed;
  }
  pf.confirmed = pf.confirmed && pf.contact;
  if (any_stuck) {
    SensorMotion read[2];
    const SensorMotion* readings[2] = {nullptr, nullptr};
    for (std::size_t i = 0; i < 2; ++i) {
      if (motions[i] == nullptr) continue;
      read[i] = velocity_reading(*motions[i]);
      readings[i] = &read[i];
    }
    (void)fuse(readings[0], readings[1], config_.fusion, config_.finger_separation_m,
               out.fused_velocity);
    pf.differs = true;
  } else {
    out.fused_velocity = out.fused;
  }
  pf.chosen = out.fused.xi;
  pf.velocity = out.fused_velocity.xi;
  if (gap) payback_.reset();
  out.paid = payback_.update(pf, dt);

  // Confidence of this frame's twist: the fit's quality and the contributing pads' slip state.
  bool slipping = false;
  for (std::size_t i = 0; i < 2; ++i) {
    if ((out.fused.rotation_sensors & (1u << i)) == 0) continue;
    slipping = slipping || out.slipping[i];
  }
  out.confidence_terms = confidence_.update(out.fused.quality, slipping, pf.onset, dt);
  out.confidence = out.confidence_terms.value;

  // Moving average (Sec. IV-D). A frame without a valid estimate contributes a zero twist: with
  // no evidence of motion the object is held still rather than extrapolated.
  out.twist = average_.push(out.paid);

  // SE(3) integration, T ← T·exp(ξ̂_b Δt) with ξ_b = Ad_{T⁻¹} ξ̄_G (se3.hpp).
  (void)integrator_.step_spatial(out.twist, dt);
  out.pose = integrator_.pose();
}

void DualPipeline::tare() noexcept {
  for (auto& s : sensors_) s.tare_image();
  tare_motion();
}

void DualPipeline::tare_motion() noexcept {
  for (auto& s : sensors_) s.reset_motion();
  restart_filters();
}

void DualPipeline::restart_filters() noexcept {
  average_.reset();
  payback_.reset();
  confidence_.reset();
}

void DualPipeline::reset_pose() noexcept {
  integrator_.reset();
  payback_.reset();  // a pending payback belongs to the motion before the new origin
}

Status DualPipeline::set_finger_separation(double separation_m) noexcept {
  if (!finite_in(separation_m, 0.0, 0.5)) return Status::kBadArgument;
  config_.finger_separation_m = separation_m;
  return Status::kOk;
}

Status DualPipeline::set_fusion_method(FusionMethod method) noexcept {
  if (method != FusionMethod::kPaper && method != FusionMethod::kJoint) {
    return Status::kBadArgument;
  }
  config_.fusion.method = method;
  return Status::kOk;
}

Status DualPipeline::set_velocity_proxy(VelocityProxy mode) noexcept {
  if (mode != VelocityProxy::kVelocity && mode != VelocityProxy::kDisplacement &&
      mode != VelocityProxy::kAuto) {
    return Status::kBadArgument;
  }
  std::array<Calibration, 2> cal = cal_;
  for (auto& c : cal) c.velocity_proxy = mode;
  if (set_pair_calibration(cal) != Status::kOk) return Status::kBadCalibration;
  // Each sensor keeps its own calibration (it may be a reload behind the pair level).
  for (auto& s : sensors_) {
    Calibration c = s.calibration();
    c.velocity_proxy = mode;
    (void)s.set_motion_calibration(c);
  }
  return Status::kOk;
}

}  // namespace tacse3::dsp
