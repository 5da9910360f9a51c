// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the per-sensor and dual-sensor TacSE3 pipelines that chain every stage per frame.
#pragma once

#include <array>
#include <cstdint>

#include "tacse3/dsp/block_flow.hpp"
#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/confidence.hpp"
#include "tacse3/dsp/contact.hpp"
#include "tacse3/dsp/density.hpp"
#include "tacse3/dsp/force_map.hpp"
#include "tacse3/dsp/fusion.hpp"
#include "tacse3/dsp/motion.hpp"
#include "tacse3/dsp/moving_average.hpp"
#include "tacse3/dsp/nhhd.hpp"
#include "tacse3/dsp/se3.hpp"
#include "tacse3/dsp/slip_payback.hpp"
#include "tacse3/dsp/smoothing.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Tuning of the image and grid stages (not calibration: it does not depend on the sensor unit).
struct PipelineConfig {
  BlockFlowConfig flow{};
  SmoothingConfig smoothing{};
  DensityConfig density{};
  NhhdConfig nhhd{};
  // A frame whose tracked fraction of grid points falls below this is "degraded": its motion is
  // not used (empty, saturated, occluded or unrelated frame). (0, 1].
  double min_tracked_fraction = 0.25;
};

// kOk or kBadArgument for any out-of-range stage config.
Status validate(const PipelineConfig& config) noexcept;

// Every intermediate field of one sensor's last frame (for tests, tools and --dump-fields).
struct SensorFields {
  WorkImage work{};
  VectorField flow{};  // block flow w vs the undeformed reference, Q16 working px
  GridMask flow_valid{};
  VectorField smoothed{};  // Gaussian-smoothed w, Q16 working px
  GridMask smoothed_valid{};
  ScalarField density{};  // 𝒢, Q16 (0 = undeformed, < 0 = local expansion)
  VectorField d{};        // NHHD curl-free part
  VectorField r{};        // NHHD divergence-free part
  VectorField k{};        // NHHD harmonic part
  ScalarField fz{};       // normal response f^z, Q16
  VectorField shear{};    // calibrated shear (f^x, f^y), Q16 shear units
  ContactSet contact{};   // Ω and the 3D contact points
};

// Result of one sensor's frame.
struct SensorResult {
  Status status = Status::kOk;          // input error (the frame was rejected, state unchanged)
  bool processed = false;               // the frame went through the pipeline
  bool degraded = false;                // too few points tracked: motion not used this frame
  bool reference_taken = false;         // this frame became the (tare) reference
  int tracked_points = 0;               // valid block-flow points
  std::uint32_t keyframe_switches = 0;  // since the last tare
  bool keyframe_switched = false;       // this frame became the block flow's next keyframe
  SensorMotion motion{};                // per-sensor translation, moments and own-frame ω
  // kAuto: the stick/slip detector's decision this frame (velocity proxy used); false otherwise.
  bool slipping = false;
};

// What stages 7-8 of a frame need from its stages 1-6: their result so far and a copy of the
// two fields the motion reads, so the image work of the pad's next frame may run meanwhile.
struct PadStages {
  SensorResult result{};  // motion and slipping still empty
  ContactSet contact{};
  VectorField shear{};
};

// One sensor: frame → luma → block flow → smoothing → 𝒢 → NHHD → forces → Ω, q → motion.
// All state lives in the object (≈ 0.6 MB); construct it once (statically or with one allocation
// at start). process() never allocates, locks or calls the OS.
class SensorPipeline {
 public:
  SensorPipeline() noexcept;

  // Validates and applies both configs; on error nothing changes. Resets the tracking state.
  Status configure(const PipelineConfig& config, const Calibration& cal) noexcept;
  // Applies a new calibration without dropping the reference (e.g. a SIGHUP reload).
  Status set_calibration(const Calibration& cal) noexcept;
  // set_calibration() in the halves process_image and finish_motion read, for a caller that runs
  // them on different threads: the image half (force map, contact detector) and the motion half
  // (motion estimator, calibration()). Each validates; on error nothing changes.
  Status set_image_calibration(const Calibration& cal) noexcept;
  Status set_motion_calibration(const Calibration& cal) noexcept;

  // Tare: the current (last processed) frame becomes the undeformed reference; before any frame,
  // the next frame does. Clears the NHHD warm start, the contact hysteresis and motion history.
  void tare() noexcept;

  // Processes one frame taken dt_s after the previous one (dt_s in (0, 1]; the first frame after
  // configure/tare ignores it). A malformed frame returns its error in out.status and changes
  // nothing. Never NaN, never throws. Includes run_deferred().
  void process(const FrameView& frame, double dt_s, SensorResult& out) noexcept;

  // process() in two calls: stages 1-6 (the image work, no time step; they advance the block
  // flow's reference, the NHHD warm start and the contact hysteresis) and stages 7-8 (the
  // motion, which differences against the previous finished frame). finish_motion may run on
  // another thread than process_image, one frame behind it (PadStages holds what it reads).
  void process_image(const FrameView& frame, PadStages& out) noexcept;
  void finish_motion(const PadStages& stages, double dt_s, SensorResult& out) noexcept;
  // The image work process_image leaves for later, which only the next frame needs (a keyframe
  // switch, BlockFlow::run_deferred): for the thread that owns the image state, once the frame's
  // stages are handed on. The next process_image or tare_image runs it if this is not called.
  void run_deferred() noexcept { flow_.run_deferred(); }
  // tare() in the same two halves: the image half (reference, warm start, hysteresis) and the
  // motion half. tare() = both.
  void tare_image() noexcept;
  void reset_motion() noexcept;

  // Forget the previous frame's motion state (after a gap in the stream or a missed frame) but
  // keep the reference and the displacement proxy's patch anchor (MotionEstimator::restart()).
  void restart_motion() noexcept;

  const SensorFields& fields() const noexcept { return fields_; }
  const BlockFlow& flow() const noexcept { return flow_; }
  const PipelineConfig& config() const noexcept { return config_; }
  const Calibration& calibration() const noexcept { return cal_; }
  bool has_reference() const noexcept { return flow_.has_reference(); }

 private:
  PipelineConfig config_{};
  Calibration cal_{};
  int min_tracked_points_ = 0;
  // The working image's filter, from the image half of the calibration (antialias_filter).
  WorkImageFilter image_filter_ = WorkImageFilter::kBox;
  BlockFlow flow_{};
  FlowSmoother smoother_{};
  GaussianDensity density_{};
  Nhhd nhhd_{};
  ForceMap forces_{};
  ContactDetector contact_{};
  MotionEstimator motion_{};
  SensorFields fields_{};
  PadStages scratch_{};  // process()'s hand-over from stages 1-6 to 7-8
};

// Configuration of the dual-sensor estimator.
struct DualConfig {
  PipelineConfig pipeline{};
  FusionConfig fusion{};
  double finger_separation_m = 0.040;  // distance W between the gel surfaces, [0, 0.5]
  double nominal_frame_period_s = 1.0 / 120.0;
  // A gap longer than this between frames restarts the motion state instead of differentiating
  // across it (the sensor stalled or was lost). (0, 1].
  double max_frame_gap_s = 0.1;
};

Status validate(const DualConfig& config) noexcept;

// Which sensors a frame pair carries.
enum class SensorSlot : std::uint8_t { kLeft = 0, kRight = 1 };

// Output of one frame pair: the twist and the integrated pose of the object in G.
struct DualResult {
  std::int64_t t_ns = 0;
  std::array<SensorResult, 2> sensors{};  // [left, right]
  std::array<bool, 2> present{false, false};
  FusedMotion fused{};  // this frame's fused twist (before the payback and averaging)
  // kAuto: fused twist of the velocity readings (= fused unless some sensor stuck), and the twist
  // that entered the moving average (fused.xi plus this frame's slip payback).
  FusedMotion fused_velocity{};
  Vector6d paid = Vector6d::Zero();
  Vector6d twist = Vector6d::Zero();           // moving-averaged twist ξ̄ in G, [ω rad/s; v m/s]
  Pose pose{};                                 // integrated object pose in G since tare/reset
  bool valid = false;                          // fused.valid for this frame
  bool single_sensor = false;                  // only one sensor contributed
  double dt_s = 0.0;                           // integration step used
  std::array<bool, 2> slipping{false, false};  // per sensor, = sensors[k].slipping
  // Confidence of this frame's twist in [0, 1] (TwistConfidence on fused.quality and the pads'
  // slip state; trust it at ≥ kConfidenceThreshold), and its terms.
  double confidence = 0.0;
  TwistConfidence::Terms confidence_terms{};
};

// The confidence's scales for a pipeline configuration and the left pad's calibration (the one
// whose payback the dual pipeline runs).
ConfidenceConfig confidence_config(const PipelineConfig& config, const Calibration& cal) noexcept;

// Two sensors, fusion (paper sign matrix or joint solve), moving average and SE(3) integration.
class DualPipeline {
 public:
  DualPipeline() noexcept;

  // cal[0] is the left sensor's, cal[1] the right sensor's calibration. The moving-average
  // length is the left calibration's. On error nothing changes.
  Status configure(const DualConfig& config, const std::array<Calibration, 2>& cal) noexcept;
  Status set_calibration(const std::array<Calibration, 2>& cal) noexcept;
  // The pair-level part of set_calibration (average length, payback, confidence), for a caller
  // that applies each sensor's halves itself (SensorPipeline::set_image_calibration and
  // set_motion_calibration, on the threads that own them).
  Status set_pair_calibration(const std::array<Calibration, 2>& cal) noexcept;

  // Processes one frame pair. A null frame pointer means that sensor has no frame this cycle
  // (lost, stale or absent): the other sensor carries on alone and the result says so.
  // t_ns: sample time of the pair (monotonic); the step is t_ns − previous t_ns, or the nominal
  // period for the first pair or a non-increasing time.
  void process(const FrameView* left, const FrameView* right, std::int64_t t_ns,
               DualResult& out) noexcept;

  // process() in parts: process_pad runs one sensor's stages 1-6 as soon as its frame is there
  // (possibly on its own thread: it touches only that sensor's image state); finish runs
  // stages 7-8 of the pads present (null: no frame this cycle), fusion and SE(3) at the pair's
  // sample time t_ns. process() is exactly these calls, then each sensor's run_deferred().
  void process_pad(SensorSlot s, const FrameView& frame, PadStages& out) noexcept;
  void finish(const PadStages* left, const PadStages* right, std::int64_t t_ns,
              DualResult& out) noexcept;
  // The image state of one sensor for a thread that owns it (process_pad, tare_image,
  // set_calibration).
  SensorPipeline& sensor_mut(SensorSlot s) noexcept {
    return sensors_[static_cast<std::size_t>(s)];
  }
  // tare() in parts: each sensor's tare_image (by the thread that owns it), then this: the
  // motion state, the average, the payback and the confidence restart.
  void tare_motion() noexcept;
  // The pair-level half of tare_motion (average, payback, confidence), for a caller that restarts
  // a sensor's motion later, after a frame whose image stages ran before the tare.
  void restart_filters() noexcept;

  void tare() noexcept;        // both sensors re-take the reference; averaging restarts
  void reset_pose() noexcept;  // pose := identity
  Status set_finger_separation(double separation_m) noexcept;
  Status set_fusion_method(FusionMethod method) noexcept;
  // Touches the motion half and the pair level only (the image stages do not read the proxy).
  Status set_velocity_proxy(VelocityProxy mode) noexcept;

  const SensorPipeline& sensor(SensorSlot s) const noexcept {
    return sensors_[static_cast<std::size_t>(s)];
  }
  const DualConfig& config() const noexcept { return config_; }
  const Pose& pose() const noexcept { return integrator_.pose(); }

 private:
  DualConfig config_{};
  std::array<Calibration, 2> cal_{};
  std::array<SensorPipeline, 2> sensors_{};
  MovingAverage<> average_{};
  SlipPayback payback_{};
  TwistConfidence confidence_{};
  PoseIntegrator integrator_{};
  std::array<PadStages, 2> stages_{};  // process()'s own stage outputs
  std::int64_t last_t_ns_ = 0;
  bool have_last_t_ = false;
};

}  // namespace tacse3::dsp
