// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: double-precision pyramid, window models and block flow (Eq. (dense_flow)).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "tacse3/dsp/block_flow.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp_ref {

// One image plane in double (U8.2 scale for images, 2 * U8.2 / px for gradients).
struct PlaneRef {
  int width = 0;
  int height = 0;
  std::vector<double> px;
  double at(int x, int y) const { return px[static_cast<std::size_t>(y * width + x)]; }
  double& at(int x, int y) { return px[static_cast<std::size_t>(y * width + x)]; }
};

// Same kernel as dsp::build_pyramid ([1 3 3 1] / 8, clamped, cell-centred), without rounding.
std::vector<PlaneRef> build_pyramid_ref(const dsp::WorkImage& in, int levels);
// Central differences with clamped indices (the fixed-point path packs the same differences
// per window; windows never touch the border, so the clamping never matters there).
void gradients_ref(const PlaneRef& img, PlaneRef& gx, PlaneRef& gy);

// A window model in double: origin, zero-mean structure tensor with the local gain eliminated
// (h64 = 64 sum g g^T - G G^T - k k^T / e), its inverse, and validity by the same tests as the
// fixed-point path.
struct WindowRef {
  int ox = 0;
  int oy = 0;
  bool valid = false;
  bool solvable = false;  // inverse and moments computed (valid, or failed only a texture test)
  double offset_x = 0.0;  // material point minus window centre (level px)
  double offset_y = 0.0;
  double gsum_x = 0.0;
  double gsum_y = 0.0;
  double template_energy = 0.0;  // 64 sum T^2 - (sum T)^2, U8.2 units
  double tsum = 0.0;
  // Rows gx, gy, T; columns Txx, Tyy: 64 sum a Txx - (sum a)(sum Txx) (bilinear compensation).
  Eigen::Matrix<double, 3, 2> curvature = Eigen::Matrix<double, 3, 2>::Zero();
  Eigen::Vector2d gain_k = Eigen::Vector2d::Zero();  // 64 sum g T - G sum T
  double gain_e = 0.0;                               // 64 sum T^2 - (sum T)^2
  Eigen::Matrix2d h64 = Eigen::Matrix2d::Zero();
  Eigen::Matrix2d h64_inv = Eigen::Matrix2d::Zero();
  // Measurement-point moments: for an affine flow u(s) = u(c) + J (s - c) the window's LK
  // translation is u(c) + P_x J(:, 0) + P_y J(:, 1).
  Eigen::Matrix2d p_x = Eigen::Matrix2d::Zero();
  Eigen::Matrix2d p_y = Eigen::Matrix2d::Zero();
};

// The fixed-point path's discrete decisions of one frame, for the "decision-locked" comparison
// only (docs/dsp/reference.md): which points dsp::BlockFlow reported
// tracked (dsp::SensorFields::flow_valid) and whether it took this frame as its next keyframe.
// Near a threshold (convergence, residual ratio, neighbour consensus, the keyframe gates) the two
// arithmetics can decide differently; following these takes those crossings out of the numeric
// difference. The reference still computes its own estimate at every point.
struct FlowDecision {
  const dsp::GridMask* valid = nullptr;  // null: nothing is followed (the rest included)
  bool keyframe_switch = false;
  // At a switch (each may be null: the reference decides itself): the points whose keyframe
  // displacement the fixed path took from the direct match against the tare frame
  // (dsp::BlockFlow::reanchored()), and the points it left lost (dsp::BlockFlow::lost()). A
  // re-anchored point takes the reference's own direct estimate, even where the reference's
  // own tolerance or validity test failed.
  const dsp::GridMask* reanchored = nullptr;
  const dsp::GridMask* lost = nullptr;
  // The fixed path's level-0 window origins in its current keyframe (null: the reference
  // places its own). Each origin rounds a keyframe displacement, so the two paths can place a
  // window one pixel apart, and the flow-gradient stencils that need 3 px between windows then
  // differ. Followed from the frame after a switch (the fixed path builds the new keyframe's
  // level 0 in the switch's deferred work): the reference re-places its level-0 windows there.
  const dsp::BlockFlow::WindowOrigins* origin_x = nullptr;
  const dsp::BlockFlow::WindowOrigins* origin_y = nullptr;
};

// The block flow of dsp::BlockFlow in double: exact bilinear sampling at the real-valued
// position, exact inverse, exact divisions, unrounded pyramid. The same config, windows,
// iteration and validity rules, on-demand coarse-to-fine, output corrections, keyframe policy,
// neighbour fit and re-anchoring. The only intended differences are the fixed-point roundings
// (1/32 px sampling, U8.7 samples, Q16 results), and the stopping rule (|step| < 1/64 px instead
// of a repeated rounded position).
class BlockFlowRef {
 public:
  explicit BlockFlowRef(const dsp::BlockFlowConfig& config = {});
  void tare(const dsp::WorkImage& frame);
  // Displacement relative to the tare frame, working px, row-major 40x30.
  // follow (may be null): take the validity and keyframe decisions from the fixed-point path.
  void track(const dsp::WorkImage& frame, std::vector<double>& dx, std::vector<double>& dy,
             std::vector<std::uint8_t>& valid, const FlowDecision* follow = nullptr);
  int keyframe_switches() const { return switches_; }
  // The last switch's outcome, as dsp::BlockFlow::reanchored() and lost(): 1 per grid point.
  const std::vector<std::uint8_t>& reanchored() const { return reanchored_; }
  const std::vector<std::uint8_t>& lost() const { return lost_; }
  // Sample on the fixed-point path's grid: positions rounded to 1/32 px, the Gauss-Newton step
  // added to the rounded position, stop when the rounded position repeats. Off (default), the
  // reference samples at the exact position and stops when |step| < 1/64 px, so it also checks
  // that the 1/32 px rounding only matters at second order. On, only the arithmetic differs
  // (bilinear weights and Q16 roundings): for end-to-end comparisons downstream of the flow.
  void set_fixed_point_sampling(bool on) { fixed_point_sampling_ = on; }
  bool has_reference() const { return has_reference_; }
  const WindowRef& window(int level, int index) const {
    return models_[static_cast<std::size_t>(level)][static_cast<std::size_t>(index)];
  }
  const std::vector<PlaneRef>& keyframe_pyramid() const { return key_; }
  const std::vector<double>& flow_from_keyframe_x() const { return tx_; }
  const std::vector<double>& flow_from_keyframe_y() const { return ty_; }

 private:
  struct Result {
    double ux, uy;
    bool valid;
    bool outside;
  };
  void take_keyframe();
  void build_level(int level);
  void follow_origins(const FlowDecision& follow);
  void coarse_levels(const dsp::GridMask* follow_valid);
  void coarse_correction(int level, int jx, int jy, double& ox, double& oy) const;
  // follow_valid (decision-locked track() only): also track the windows the fixed-point path
  // tracked whose model failed only a texture test here.
  int track_fine(bool retry, const dsp::GridMask* follow_valid = nullptr);
  void write_output();
  void re_anchor(const FlowDecision* follow);
  void follow_validity(const dsp::GridMask& valid, const std::vector<double>& held_x,
                       const std::vector<double>& held_y);
  // inside: a window the fixed path tracked, so its sampling position is held in the image
  // instead of reporting `outside` (the two paths' positions differ by their rounding).
  Result track_window(int level, const WindowRef& m, double ux, double uy, int iterations,
                      bool inside = false) const;
  bool fit_from_neighbours(int gx, int gy, double& ux, double& uy) const;

  dsp::BlockFlowConfig cfg_;
  bool has_reference_ = false;
  int switches_ = 0;
  std::vector<PlaneRef> tare_, key_, cur_, gx_, gy_;
  std::vector<std::vector<double>> cx_, cy_;  // coarse-level corrections
  std::vector<double> fx_, fy_;               // level-0 estimates of the current frame
  std::vector<std::uint8_t> ok_;
  // This frame's own level-0 estimate of every window tracked without leaving the image, valid
  // or not (for follow_validity()).
  std::vector<double> est_x_, est_y_;
  std::vector<std::uint8_t> est_ok_;
  std::vector<std::vector<WindowRef>> models_;
  // Level-0 origins given by follow_origins() for build_level() (null: its own rounding).
  const FlowDecision* given_origins_ = nullptr;
  std::vector<double> dkx_, dky_;  // keyframe displacement
  std::vector<double> tx_, ty_;    // window flow since keyframe
  std::vector<double> outx_, outy_;
  std::vector<std::uint8_t> valid_;
  std::vector<std::uint8_t> lost_;
  std::vector<std::uint8_t> reanchored_;
  int key_valid_count_ = 0;
  bool fixed_point_sampling_ = false;
};

}  // namespace tacse3::dsp_ref
