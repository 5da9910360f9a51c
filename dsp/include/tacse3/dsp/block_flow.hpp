// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: fixed-point pyramidal block flow with keyframe chaining (paper Eq. (dense_flow)).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "tacse3/dsp/coarse_region.hpp"
#include "tacse3/dsp/flow_grid.hpp"
#include "tacse3/dsp/pyramid.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Tuning of the block flow. Lengths are in pixels of the pyramid level they act on unless
// they say "working px" (level 0). Converted to integers once, in configure().
struct BlockFlowConfig {
  int pyramid_levels = 3;     // 1..kMaxPyramidLevels; 3 levels recover >= 10 working px jumps
  int fine_iterations = 4;    // max Gauss-Newton iterations at level 0 (1..16)
  int coarse_iterations = 8;  // max iterations at each coarse level (1..16)
  // The coarse levels run when at least this many trackable windows fail at level 0 from the
  // warm start (0 = every frame). 0..1200.
  int coarse_trigger = 3;
  // A new keyframe is taken when some tracked point has moved this far (working px) from the
  // current keyframe. 0 disables chaining (everything is tracked against the tare frame).
  double keyframe_switch_px = 2.0;
  // A keyframe switch needs at least this fraction of the keyframe's trackable points valid in
  // the frame (never switch onto a dark, saturated or occluded frame).
  double keyframe_min_valid_fraction = 0.5;
  // Texture: smallest eigenvalue of the zero-mean structure tensor per pixel, expressed as the
  // RMS luma gradient (luma levels per pixel) along the weakest direction.
  double min_texture = 1.0;
  // Conditioning: smallest / largest eigenvalue of the zero-mean structure tensor.
  double min_eigen_ratio = 0.02;
  // Match quality: zero-mean residual energy / zero-mean template energy after the last
  // iteration (0 = perfect match; an unrelated or blank frame gives ~1 or more). A correct match
  // on strained, shaded gel under contact (a fine, low-contrast pattern with sensor noise) leaves
  // a sizeable residual; a tighter bound leaves the grid around a pressed patch untracked
  // (docs/dsp/flow.md).
  double max_residual_ratio = 0.30;
  double max_step_px = 2.0;        // per-iteration step clamp
  double converged_step_px = 0.1;  // the last step must be below this for a valid point
  // At a keyframe switch, points whose direct match against the tare frame agrees with the
  // chained displacement within this tolerance (working px) take the direct value, which
  // resets the drift of the chain (see BlockFlow::re_anchor()). 0 disables re-anchoring. The
  // default, the largest allowed, lets every valid direct match replace the chain: a chain can
  // take a wrong match while the gel springs back after a slide, and a tight tolerance would
  // protect the wrong chain against the right direct match for good (docs/dsp/flow.md).
  // "Every" holds because with the default iterations a match moves at most about 6 px from its
  // warm start (4 steps of at most max_step_px per component); more or longer steps could
  // exceed the tolerance.
  double reanchor_tolerance_px = 8.0;
};

// Validates a config (ranges above, finite values). kBadArgument on failure.
Status validate(const BlockFlowConfig& config) noexcept;

// Template of one window, packed contiguously at keyframe time so that the per-iteration loop
// runs over 64 consecutive samples: T (U8.2) and its central-difference gradients
// gx = T(x+1) - T(x-1), gy = T(y+1) - T(y-1) (int16, |.| <= 1020), row-major 8x8.
struct FlowWindowTemplate {
  alignas(16) std::array<std::int16_t, kFlowWindowPixels> t{};
  alignas(16) std::array<std::int16_t, kFlowWindowPixels> gx{};
  alignas(16) std::array<std::int16_t, kFlowWindowPixels> gy{};
};

// Per-window model, precomputed when a keyframe is taken (inverse-compositional LK: the
// template, its gradients and the inverse structure tensor stay fixed until the next keyframe).
// Formats are listed at the top of block_flow.cpp and in docs/dsp/flow.md.
struct FlowWindowModel {
  // Block-floating-point inverse of the zero-mean, gain-eliminated structure tensor H64:
  // H64^-1 = [inv_a inv_b; inv_b inv_c] * 2^-(shift + 12). Mantissas |.| < 2^22.
  std::int32_t inv_a = 0;
  std::int32_t inv_b = 0;
  std::int32_t inv_c = 0;
  std::int32_t gsum_x = 0;  // sum of gx over the window (|.| <= 64 * 1020)
  std::int32_t gsum_y = 0;
  std::int32_t tsum = 0;     // sum of T over the window (<= 64 * 1020)
  std::int32_t gain_qx = 0;  // gain coupling k / e (Q16, |.| <= 2^22)
  std::int32_t gain_qy = 0;
  std::int64_t template_energy = 0;  // 64 sum (2T)^2 - (sum 2T)^2 (U8.3 units): < 2^36
  // Bilinear-smoothing compensation: zero-mean projections of the template's second differences
  // onto gx, gy and T: {(gx, Txx), (gy, Txx), (T, Txx), (gx, Tyy), (gy, Tyy), (T, Tyy)} with
  // (a, Txx) = 64 sum a Txx - (sum a)(sum Txx); |.| < 2^35.
  std::array<std::int64_t, 6> curvature{};
  // Level 0 only: measurement-point moments P_x, P_y (row-major 2x2, Q16 px), see
  // BlockFlow::write_output(). |.| < 2^20.
  std::array<std::int32_t, 4> moment_x{};
  std::array<std::int32_t, 4> moment_y{};
  std::int16_t ox = 0;  // window origin (top-left pixel) in the keyframe plane of its level
  std::int16_t oy = 0;
  std::int8_t shift = 0;  // right shift turning M * b64 into a Q16 step
  std::uint8_t valid = 0;
};

// Dense block flow on the 40x30 grid by windowed least squares (Eq. (dense_flow)), solved by
// zero-mean inverse-compositional Lucas-Kanade with a local gain and offset per window, coarse
// to fine over a [1 3 3 1] pyramid, warm-started from the previous frame, against an adaptive
// keyframe chained back to the tare (undeformed) frame.
//
// The object is large (~1.7 MB, mostly the packed window templates) and allocation-free;
// construct it once (static storage or one allocation at start-up).
class BlockFlow {
 public:
  BlockFlow() noexcept;
  // An invalid config falls back to the defaults (check with validate() first).
  explicit BlockFlow(const BlockFlowConfig& config) noexcept;

  // Replaces the config. Drops the reference (the next track() is an implicit tare), because
  // the window models depend on the thresholds. On error nothing changes.
  Status configure(const BlockFlowConfig& config) noexcept;
  const BlockFlowConfig& config() const noexcept { return config_; }

  // Reference := frame; displacement := 0; keyframe := frame; switch count := 0.
  void tare(const WorkImage& frame) noexcept;

  // Tracks one frame. `displacement`: displacement of each grid material point relative to the
  // tare frame, Q16 working px. `valid`: 1 where the point was tracked in this frame (window
  // inside the image, well-conditioned, converged, small residual, consistent with its
  // neighbours). Invalid points hold their previous displacement. The first call without a
  // reference is an implicit tare (all zeros, no point valid): the frame becomes the reference
  // in run_deferred(), as a tare's would. A keyframe switch is decided here
  // (last_frame_was_keyframe()), but its work, which only the next frame needs, is left to
  // run_deferred() too; track() and tare() run it first if the caller has not, so no result
  // depends on when it runs.
  void track(const WorkImage& frame, VectorField& displacement, GridMask& valid) noexcept;
  // The last track()'s deferred work: the first frame's reference (its pyramid and level-0
  // models), a keyframe switch (neighbour fit, re-anchoring) and the new keyframe's level-0
  // models, or a pending coarse-level build. For a caller with spare
  // time once the frame's result is handed on; a no-op when nothing is pending.
  void run_deferred() noexcept;
  bool deferred_pending() const noexcept { return deferred_pending_; }

  // From the first frame on (its models may still be pending in run_deferred()).
  bool has_reference() const noexcept { return has_reference_; }
  // The next track() takes its frame as the reference (e.g. the working image changed).
  void drop_reference() noexcept {
    has_reference_ = false;
    reference_pending_ = false;
    deferred_pending_ = false;
  }
  // The last track()'s coarse fallback: whether the coarse levels ran, how many windows failed
  // at level 0 from their warm start (the trigger's count), how many of those the frame before
  // had tracked, and how many more windows the frame tracked after the retry than before it
  // (net: the retry's consensus may also drop some), and how many coarse windows it tracked
  // (CoarseRegion: those the retried windows draw on).
  struct CoarseFallback {
    bool ran = false;
    int failed = 0;
    int failed_fresh = 0;
    int recovered = 0;
    int coarse_windows = 0;
  };
  const CoarseFallback& last_coarse_fallback() const noexcept { return coarse_fallback_; }
  std::uint32_t keyframe_switches() const noexcept { return keyframe_switches_; }  // since tare
  std::uint32_t frames_since_keyframe() const noexcept { return frames_since_keyframe_; }
  bool last_frame_was_keyframe() const noexcept { return last_frame_was_keyframe_; }
  int valid_count() const noexcept { return valid_count_; }                    // last track()
  int keyframe_valid_count() const noexcept { return keyframe_valid_count_; }  // level 0
  // The last keyframe switch's per-point outcome (cleared at a tare): points whose keyframe
  // displacement was taken from the direct match against the tare frame (re_anchor()), and
  // points left lost (untracked and not recoverable from neighbours). The decision-locked
  // double reference follows both (dsp_ref::FlowDecision).
  const GridMask& reanchored() const noexcept { return reanchored_; }
  const GridMask& lost() const noexcept { return lost_; }
  // Displacement of each material point at the moment the current keyframe was taken (Q16).
  const VectorField& keyframe_displacement() const noexcept { return key_displacement_; }
  // Translation of each level-0 window since the keyframe (Q16 working px).
  const VectorField& flow_from_keyframe() const noexcept { return window_flow_; }
  // The level-0 windows' integer origins in the keyframe (working px), once its level 0 is built.
  using WindowOrigins = std::array<std::int16_t, kGridCount>;
  const WindowOrigins& window_origin_x() const noexcept { return window_origin_x_; }
  const WindowOrigins& window_origin_y() const noexcept { return window_origin_y_; }

  // A keyframe's window models are built in bounded pieces: at a tare level 0 at once and the
  // coarse levels within two frames; at a switch level 0 in the switch's deferred work and the
  // coarse levels in the next frame's (earlier when a coarse pass needs them). This runs the
  // deferred work and builds whatever is still pending now (the results are the same).
  void complete_keyframe() noexcept;

  // Stage access for tests and tools (call complete_keyframe() first).
  const ImagePyramid& keyframe_pyramid() const noexcept {
    return pyramid_[static_cast<std::size_t>(key_index_)];
  }
  const FlowWindowModel& window_model(int level, int index) const noexcept {
    return level_models(level)[index];
  }
  const FlowWindowTemplate& window_template(int level, int index) const noexcept {
    return level_templates(level)[index];
  }

 private:
  struct WindowResult {
    std::int32_t ux;  // Q16 level px
    std::int32_t uy;
    bool valid;
    bool outside;  // failed because the window left the image
  };
  struct JacobianStencil {  // see write_output()
    std::int16_t a;
    std::int16_t b;
    std::int32_t recip;
  };
  struct Thresholds {  // integer forms of the config, set in configure()
    std::int64_t min_eigen_h64 = 0;
    std::int64_t eigen_ratio_kappa_q16 = 0;
    std::int64_t residual_ratio_q8 = 0;
    std::int32_t max_step_q16 = 0;
    std::int32_t converged_q16 = 0;
    std::int64_t keyframe_switch_sq_q32 = 0;
    std::int64_t keyframe_min_valid_q16 = 0;
    std::int32_t reanchor_tolerance_q16 = 0;
  };

  void take_reference() noexcept;
  void build_level0() noexcept;
  void build_coarse() noexcept;  // when pending
  void build_models(int level) noexcept;
  // The keyframe's models of one level (level 0: the tare frame's own set while the keyframe
  // is the tare frame, and during re_anchor()).
  const FlowWindowModel* level_models(int level) const noexcept {
    return level == 0 && key_level0_is_tare_ ? tare_models_.data()
                                             : models_.data() + flow_grid_offset(level);
  }
  FlowWindowModel* level_models(int level) noexcept {
    return level == 0 && key_level0_is_tare_ ? tare_models_.data()
                                             : models_.data() + flow_grid_offset(level);
  }
  const FlowWindowTemplate* level_templates(int level) const noexcept {
    return level == 0 && key_level0_is_tare_ ? tare_templates_.data()
                                             : templates_.data() + flow_grid_offset(level);
  }
  FlowWindowTemplate* level_templates(int level) noexcept {
    return level == 0 && key_level0_is_tare_ ? tare_templates_.data()
                                             : templates_.data() + flow_grid_offset(level);
  }
  WindowResult track_window(int level, int index, std::int32_t ux, std::int32_t uy,
                            int iterations) const noexcept;
  void coarse_to_fine() noexcept;
  void write_output(VectorField& displacement, GridMask& valid) noexcept;
  void update_stencils() noexcept;
  bool keyframe_switch_due() const noexcept;
  void switch_keyframe() noexcept;
  void re_anchor() noexcept;
  void upsample_correction(int level) noexcept;
  int track_fine(bool retry, int* fresh = nullptr) noexcept;
  bool fit_from_neighbours(int gx, int gy, std::int32_t& ux, std::int32_t& uy) const noexcept;

  BlockFlowConfig config_{};
  Thresholds th_{};
  bool has_reference_ = false;
  int key_index_ = 2;  // pyramid_ slot of the keyframe (2 = the tare frame itself)
  int cur_index_ = 0;  // pyramid_ slot that receives new frames (0 or 1, never the keyframe)
  std::uint32_t keyframe_switches_ = 0;
  CoarseFallback coarse_fallback_{};
  std::uint32_t frames_since_keyframe_ = 0;
  bool last_frame_was_keyframe_ = false;
  bool deferred_pending_ = false;    // the last track()'s run_deferred() has not run yet
  bool reference_pending_ = false;   // the tare slot's level 0 is to become the reference
  bool coarse_built_ = false;        // coarse pyramid levels of the current frame exist
  bool key_coarse_pyramid_ = false;  // coarse pyramid levels of the keyframe exist
  bool key_level0_is_tare_ = false;  // level_models(0) is the tare frame's set
  bool coarse_pending_ = false;      // its coarse-level models are still to be built
  int valid_count_ = 0;
  int keyframe_valid_count_ = 0;

  std::array<ImagePyramid, 3> pyramid_{};  // two alternating slots + the tare frame
  std::array<FlowWindowModel, kFlowModelCount> models_{};
  std::array<FlowWindowTemplate, kFlowModelCount> templates_{};
  // The tare frame's level-0 models and window placement (re_anchor() matches against them).
  std::array<FlowWindowModel, kGridCount> tare_models_{};
  std::array<FlowWindowTemplate, kGridCount> tare_templates_{};
  std::array<std::int16_t, kGridCount> tare_origin_x_{};
  std::array<std::int16_t, kGridCount> tare_origin_y_{};
  VectorField tare_offset_{};

  VectorField key_displacement_{};  // D_key: material displacement at the keyframe (Q16)
  VectorField window_offset_{};     // delta = material position - window centre, keyframe (Q16)
  VectorField window_flow_{};       // t_w: window translation since the keyframe (Q16)
  VectorField output_{};            // last output (held for invalid points)
  GridMask frame_valid_{};
  GridMask lost_{};  // untracked at the last keyframe switch and not recoverable from neighbours
  GridMask reanchored_{};  // keyframe displacement taken from the direct match at the last switch
  std::array<std::int16_t, kGridCount> window_origin_x_{};  // level-0 window origins
  std::array<std::int16_t, kGridCount> window_origin_y_{};
  // write_output() scratch: window-centre flows, flow gradients {dfx/dx, dfy/dx, dfx/dy,
  // dfy/dy} (Q16) and the difference stencils of the frame.
  VectorField centre_{};
  std::array<std::array<std::int32_t, 4>, kGridCount> jacobian_{};
  std::array<std::array<JacobianStencil, 2>, kGridCount> stencil_{};
  // The inputs the stencils were built from: they are rebuilt only when the valid mask or the
  // window origins changed, which in a steady grasp is rare.
  bool stencil_built_ = false;
  GridMask stencil_mask_{};
  std::array<std::int16_t, kGridCount> stencil_origin_x_{};
  std::array<std::int16_t, kGridCount> stencil_origin_y_{};
  // re_anchor() scratch.
  VectorField reanchor_reported_{};
  VectorField reanchor_chained_{};
  VectorField reanchor_direct_{};
  GridMask reanchor_reported_valid_{};
  GridMask reanchor_chained_lost_{};
  GridMask reanchor_direct_valid_{};
  // Coarse-level warm starts and corrections (Q16 working px), per level's own grid.
  std::array<std::int32_t, kFlowModelCount> warm_x_{};
  std::array<std::int32_t, kFlowModelCount> warm_y_{};
  std::array<std::int32_t, kFlowModelCount> corr_x_{};
  std::array<std::int32_t, kFlowModelCount> corr_y_{};
  std::array<std::int32_t, kFlowModelCount> up_x_{};  // corrections upsampled from the level above
  std::array<std::int32_t, kFlowModelCount> up_y_{};
  // Per-level estimates of the current frame (Q16 working px) and their usable flags.
  std::array<std::int32_t, kFlowModelCount> flow_x_{};
  std::array<std::int32_t, kFlowModelCount> flow_y_{};
  std::array<std::uint8_t, kFlowModelCount> ok_{};
  std::array<std::uint8_t, kFlowModelCount> scratch_{};
  // The coarse fallback's level-0 windows to retry and the coarse windows they draw on.
  std::array<std::uint8_t, kGridCount> retry_{};
  CoarseRegion coarse_region_{};
};

}  // namespace tacse3::dsp
