// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: the whole dual-sensor pipeline chained from the double-precision stages.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "tacse3/dsp/pipeline.hpp"
#include "tacse3/dsp_ref/block_flow_ref.hpp"
#include "tacse3/dsp_ref/contact_ref.hpp"
#include "tacse3/dsp_ref/motion_ref.hpp"
#include "tacse3/dsp_ref/nhhd_ref.hpp"
#include "tacse3/dsp_ref/smoothing_ref.hpp"

namespace tacse3::dsp_ref {

// How the reference chain is run (docs/dsp/reference.md).
struct ReferenceOptions {
  // Block flow on the fixed-point path's sampling grid (BlockFlowRef::set_fixed_point_sampling):
  // positions rounded to 1/32 px, the step added to the rounded position, stop when the rounded
  // position repeats. Off (default): exact positions, |step| < 1/64 px, i.e. the converged LK
  // solution of Eq. (dense_flow), which the fixed path approximates to second order. On is a
  // diagnostic: its discrete stopping rule makes the two chains take different iteration counts
  // where the double arithmetic rounds a position differently, so it does not agree better
  // everywhere.
  bool fixed_point_sampling = false;
};

// The fixed-point pipeline's discrete decisions for one sensor and frame, to report a
// "decision-locked" fixed−ref difference next to the free-running one (docs/dsp/reference.md).
// Each part is optional: null pointers leave that decision to the reference. Taken from
// dsp::SensorFields (flow_valid, contact.mask), dsp::SensorResult (keyframe_switched) and
// dsp::SensorMotion.
struct FixedDecisions {
  const SlipDecision* slip = nullptr;
  FlowDecision flow{};  // flow.valid null: the reference's own flow decisions
  const dsp::GridMask* contact = nullptr;
};

// One sensor's reference chain: luma → block flow → smoothing → 𝒢 → NHHD → forces → Ω → motion,
// each stage the double-precision twin of the fixed-point stage with the same configuration.
// Where a reference stage takes the firmware's Q16 field types as input (force map, contact),
// the double values are rounded to Q16 (LSB 2^-16 px), far below every tolerance that uses it.
class SensorPipelineRef {
 public:
  SensorPipelineRef(const dsp::PipelineConfig& config, const dsp::Calibration& cal,
                    const ReferenceOptions& options = {});
  void tare();
  // Returns false for a frame the firmware would reject (size/format) — then nothing changes.
  // follow (may be null): the fixed-point pipeline's decisions to take instead of the
  // reference's own (FixedDecisions).
  bool process(const dsp::FrameView& frame, double dt_s, SensorMotionRef& out, bool& degraded,
               const FixedDecisions* follow = nullptr);

  const GridVectorD& flow() const { return flow_; }
  const GridVectorD& smoothed() const { return smoothed_; }
  const GridScalarD& density() const { return density_; }
  const GridVectorD& d() const { return d_; }
  const GridVectorD& r() const { return r_; }
  const GridVectorD& k() const { return k_; }
  const std::vector<double>& fz() const { return fz_; }
  const std::vector<double>& shear_x() const { return shear_x_; }
  const std::vector<double>& shear_y() const { return shear_y_; }
  const ContactSetRef& contact() const { return contact_; }
  const BlockFlowRef& flow_stage() const { return flow_stage_; }
  const GridMaskD& flow_valid() const { return flow_valid_; }
  const GridMaskD& smoothed_valid() const { return smoothed_valid_; }
  const SensorMotionRef& motion() const { return motion_; }

 private:
  dsp::PipelineConfig config_;
  dsp::Calibration cal_;
  BlockFlowRef flow_stage_;
  NhhdRef nhhd_stage_;
  ContactDetectorRef contact_stage_;
  MotionRef motion_stage_;
  dsp::WorkImage last_work_{};
  GridVectorD flow_, smoothed_, d_, r_, k_;
  GridMaskD flow_valid_, smoothed_valid_;
  GridScalarD density_;
  std::vector<double> fz_, shear_x_, shear_y_;
  ContactSetRef contact_;
  SensorMotionRef motion_;
};

struct DualResultRef {
  dsp::Vector6d fused = dsp::Vector6d::Zero();  // this frame's fused twist (before the payback)
  dsp::Vector6d twist = dsp::Vector6d::Zero();  // moving average
  dsp::Pose pose{};
  bool rotation_valid = false;
  dsp::FitQuality quality{};  // of the chosen readings' joint fit (fit_quality_ref)
  double confidence = 0.0;    // dsp::TwistConfidence on `quality` and the pads' slip state
};

// dsp::fit_quality from the pads' points in G directly: the stacked rows' AᵀA and eigenvalues,
// the residual summed point by point, each pad's own 1-D fit about its normal. pads[i] null:
// pad i does not enter ω.
dsp::FitQuality fit_quality_ref(const std::array<const SensorMotionRef*, 2>& pads,
                                const dsp::FusionConfig& cfg, double separation_m);

// Both sensors, joint or paper fusion by brute-force stacked least squares in G, the moving
// average as an explicit window mean and the SE(3) integration of dsp/se3 (already double).
class DualPipelineRef {
 public:
  DualPipelineRef(const dsp::DualConfig& config, const std::array<dsp::Calibration, 2>& cal,
                  const ReferenceOptions& options = {});
  // follow (may be null): per-sensor decisions of the fixed-point pipeline for this frame pair,
  // to report a "decision-locked" fixed−ref difference next to the free-running one.
  void process(const dsp::FrameView* left, const dsp::FrameView* right, std::int64_t t_ns,
               DualResultRef& out, const std::array<FixedDecisions, 2>* follow = nullptr);
  const SensorPipelineRef& sensor(int i) const { return sensors_[static_cast<std::size_t>(i)]; }

 private:
  dsp::DualConfig config_;
  std::array<dsp::Calibration, 2> cal_;
  std::vector<SensorPipelineRef> sensors_;
  std::vector<dsp::Vector6d> window_;
  SlipPaybackRef payback_;
  dsp::TwistConfidence confidence_;
  dsp::Pose pose_{};
  std::int64_t last_t_ns_ = 0;
  bool have_last_t_ = false;
};

}  // namespace tacse3::dsp_ref
