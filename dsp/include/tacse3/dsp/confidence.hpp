// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: the confidence of the fused twist, one number in [0, 1] for a controller.
#pragma once

namespace tacse3::dsp {

// What the joint least squares of the fused ω says about its own quality (fit_quality() in
// fusion.hpp computes it from the pads' moments; the double reference from its stacked rows).
struct FitQuality {
  int pads = 0;  // pads whose contact points entered ω (0..2)
  int rank = 0;  // ω directions the pads observe: 3 with two pads, 1 with one, 0 without
  // Two pads: λ_min/λ_max of the joint AᵀA about the common centroid, and the same ratio for
  // flat parallel patches of the measured sizes at the measured distance along the normal
  // (diag(Σ N_i d_i², Σ N_i d_i², Σ I_i), I_i the in-plane Σ|r|²). One pad: both 1.
  double rcond = 0.0;
  double rcond_expected = 0.0;
  // Standard error of the rigid speed the fit reads, σ̂/√N (m/s): σ̂² the residual of the shear
  // proxy per tangential equation after the fitted ω and the common translation (2N − rank − 2
  // degrees of freedom), N the points.
  double residual_speed_m_s = 0.0;
  // Two pads: (ω_1 − ω_2)·n_1 · L (m/s), the pads' own rotations about their normals (each from
  // its points alone, rotation_scale applied) read as a speed on the rms lever L of all points.
  // 0 with one pad.
  double disagreement_m_s = 0.0;
  int min_points = 0;  // contact points |Ω| of the smaller contributing pad
};

// The scales of the terms; each comes from the calibration or the pipeline configuration.
struct ConfidenceConfig {
  // Calibration::stick_rest_speed_m_s: the rigid speed the stick/slip detector reads as rest,
  // i.e. the speed resolution of the shear's rigid content. Speed errors are measured in it.
  double rest_speed_m_s = 0.05e-3;
  // Spread of one grid point's flow footprint, in cells: the matching window (kFlowWindow working
  // px = 2 cells wide, per-axis std 2/√12) convolved with the flow smoothing (σ, SmoothingConfig),
  // √(σ² + 1/3). A cell closer than this to the patch's rim reads the surrounding gel's shear too.
  double footprint_cells = 1.1547005383792515;
  // Calibration::slip_catchup_frames: the frames after a slip onset whose twist carries the
  // slip payback (the shear the stick phase had not yet reported) instead of the object's motion.
  int catchup_frames = 12;
  // Calibration::slip_smoothing_s: the detector's rest bar holds for the rigid content smoothed
  // with this time constant, so the pads' disagreement is smoothed alike before it is compared.
  double smoothing_s = 0.04;
};

// Confidence c = observed · conditioning · residual · agreement · area · stick, each term in
// [0, 1] (docs/dsp/solve-fusion-se3.md, confidence). State: the smoothed disagreement of the
// pads, and the stick term's catch-up count (0 while a pad slides and through the catch-up frames
// that follow an onset). Fixed work, no heap; the
// fixed-point pipeline and the double reference both use this class on their own FitQuality.
class TwistConfidence {
 public:
  struct Terms {
    double observed = 0.0;      // rank / 3
    double conditioning = 0.0;  // min(1, rcond / rcond_expected)
    double residual = 0.0;      // v² / (v² + residual_speed²), v = rest_speed_m_s
    double agreement = 0.0;     // v² / (v² + d̄²), d̄ the disagreement smoothed (smoothing_s)
    double area = 0.0;          // (1 − footprint/R)², R = √(N/π), N = min_points
    double stick = 0.0;         // 0 while sliding or catching up after an onset, else 1
    double value = 0.0;         // the product; 0 without pads
  };

  void configure(const ConfidenceConfig& config) noexcept;
  void reset() noexcept;  // forget a pending catch-up (tare)
  // One frame, dt_s after the previous one (> 0). slipping: a contributing pad's detector reads a
  // slide this frame; onset: a pad's detector switched to slip at the end of this frame. Never
  // NaN.
  const Terms& update(const FitQuality& q, bool slipping, bool onset, double dt_s) noexcept;
  const Terms& terms() const noexcept { return terms_; }

 private:
  void smooth_disagreement(const FitQuality& q, double dt_s) noexcept;

  ConfidenceConfig config_{};
  int catchup_left_ = 0;
  double disagreement_ = 0.0;  // smoothed; restarts from the first frame with two pads
  bool have_disagreement_ = false;
  Terms terms_{};
};

// The controller's recommended threshold: trust the twist when confidence ≥ this
// (docs/can-protocol.md). With one pad the observed term alone is 1/3.
inline constexpr double kConfidenceThreshold = 0.5;

}  // namespace tacse3::dsp
