// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: brute-force stacked least squares and per-sensor motion in double.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/load_release.hpp"
#include "tacse3/dsp/se3.hpp"
#include "tacse3/dsp/slip_detector.hpp"
#include "tacse3/dsp/types.hpp"
#include "tacse3/dsp_ref/contact_ref.hpp"

namespace tacse3::dsp_ref {

// One contact point with its velocity proxy and the normal of its sensor (all in one frame).
struct PointSample {
  Eigen::Vector3d q = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

// Eq. (twist_ls) restricted to ω, stacked explicitly: two rows per point, e_kᵀ(ω × q) = e_kᵀ ṽ
// for a tangent basis (e_1, e_2) of the point's normal. For n = z these are the paper's rows
// [0, z, −y] and [−z, 0, x].
struct StackedSystem {
  Eigen::MatrixXd A;  // 2N x 3
  Eigen::VectorXd b;  // 2N
};
StackedSystem stack_shear_rows(const std::vector<PointSample>& pts);

// argmin ‖Aω − b‖² + λ‖ω‖², by a column-pivoting QR of the augmented [A; √λ I].
Eigen::Vector3d solve_stacked(const StackedSystem& s, double lambda);

// Centroid of the points (the joint fusion's reference for the solve).
Eigen::Vector3d centroid(const std::vector<PointSample>& pts);
// Points shifted by −c (velocities unchanged).
std::vector<PointSample> shifted(const std::vector<PointSample>& pts, const Eigen::Vector3d& c);

struct SensorMotionRef {
  bool contact = false;
  int points = 0;
  std::vector<PointSample> samples;  // sensor frame, proxy in m/s
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  // Where `translation` applies (dsp::SensorMotion::translation_point_m).
  Eigen::Vector3d translation_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  // scaled, t_z = 0
  bool translation_valid = false;
  int translation_source = 0;                                // as dsp::TranslationSource
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();           // scaled, own-frame stacked LS
  Eigen::Vector3d rotation_scale = Eigen::Vector3d::Ones();  // this frame's proxy's scales
  bool proxy_valid = false;
  // kAuto detector, as dsp::SensorMotion.
  bool slipping = false;
  bool slip_onset = false;
  bool stick_confirmed = false;
  double slip_relax_rate = 0.0;
  double shear_shift_m = 0.0;
  double shear_rate_m_s = 0.0;
  double load_drop_rate = 0.0;
  bool releasing = false;   // as dsp::SensorMotion::releasing (the chosen reading is dropped)
  bool anchor_set = false;  // as dsp::SensorMotion::anchor_set (the patch anchor is this Ω)
  bool velocity_anchored = false;  // as dsp::SensorMotion (velocity proxy over Ω ∩ anchor)
  // The frame as kVelocity would have read it (dsp::SensorMotion's velocity_* fields).
  bool velocity_differs = false;
  std::vector<PointSample> velocity_samples;
  Eigen::Vector3d velocity_omega = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_rotation_scale = Eigen::Vector3d::Ones();
  Eigen::Vector3d velocity_translation = Eigen::Vector3d::Zero();
  bool velocity_translation_valid = false;
  Eigen::Vector3d velocity_translation_point = Eigen::Vector3d::Zero();
};

// A stick/slip decision to follow, taken from the fixed-point pipeline's dsp::SensorMotion of
// the same frame (the slip fields in kAuto only, `releasing` in every mode): `slipping` is the
// proxy that frame used, `slip_onset` whether the detector switched to slip at its end,
// `stick_confirmed` whether it confirmed a stick (the dual pipeline's slip payback reads both),
// `releasing` whether the frame's chosen reading was dropped as a release (load falling faster
// than release_load_rate), `anchor_set` (if `has_anchor`) whether the displacement proxy's patch
// anchor was set to the frame's Ω and `velocity_anchored` whether the velocity proxy read
// Ω ∩ anchor (every mode; without `has_anchor` the reference decides both). Used
// ONLY to measure the numeric fixed−ref difference with the
// detector's threshold crossings taken out ("decision-locked"; docs/dsp/reference.md).
struct SlipDecision {
  bool slipping = false;
  bool stick_confirmed = false;
  bool slip_onset = false;
  bool releasing = false;
  bool has_anchor = false;
  bool anchor_set = false;
  bool velocity_anchored = false;
};

// Same rules as dsp::MotionEstimator (translation sources, proxy modes, λ), in double.
class MotionRef {
 public:
  explicit MotionRef(const dsp::Calibration& cal = {});
  void reset();
  // shear_x/shear_y: calibrated shear (shear units, real values) per grid point.
  // follow (may be null): take the stick/slip transitions (kAuto only) and the releasing flag
  // (every mode) from this decision instead of the reference's own detector (whose features are
  // still computed and reported).
  SensorMotionRef update(const ContactSetRef& c, const std::vector<double>& shear_x,
                         const std::vector<double>& shear_y, double dt,
                         const SlipDecision* follow = nullptr);

 private:
  dsp::Calibration cal_;
  std::vector<std::uint8_t> prev_mask_;
  std::vector<Eigen::Vector3d> prev_q_;
  std::vector<double> prev_sx_, prev_sy_;
  bool have_prev_shear_ = false;
  // The displacement proxy's patch anchor (dsp::MotionEstimator's rule).
  std::vector<std::uint8_t> anchor_;
  bool have_anchor_ = false;
  int anchor_count_ = 0;  // |anchor|
  // kAuto: the same decision class as dsp::MotionEstimator; the features fed to it are computed
  // here in double.
  dsp::SlipDetector detector_;
  // Normal load (every mode): the same release rule, fed with Σ z over Ω in metres.
  dsp::LoadRelease release_;
};

// dsp::SlipPayback in plain form: the deficit D (fused velocity reading − fused chosen reading,
// integrated while some sensor sticks) is paid back as D/left over slip_catchup_frames frames
// from a slip onset, and dropped on a confirmed stick, without contact or after a gap.
class SlipPaybackRef {
 public:
  explicit SlipPaybackRef(int catchup_frames) : catchup_frames_(catchup_frames) {}
  // Returns the twist to use: chosen plus this frame's payback.
  dsp::Vector6d update(const dsp::Vector6d& chosen, const dsp::Vector6d& velocity, bool differs,
                       bool contact, bool onset, bool confirmed, bool gap, double dt);

 private:
  int catchup_frames_;
  int left_ = 0;
  dsp::Vector6d deficit_ = dsp::Vector6d::Zero();
};

// --- Analytic scene for tests and benchmarks: one pad touching an object that moves rigidly.
// The contact is a paraboloid cap of f^z (peak_fz at the centre, 0 at radius_m) centred where
// contact_centre_G projects onto the pad. The object twist (ω, t) is in G (spatial: t is the
// velocity of the material point at G's origin). Frames:
//   frame t−1: w_prev = −v_S·dt (points were there), shear_prev
//   frame t:   w_now = 0 (points at their reference positions, where v is evaluated), shear_now
// so that the contact-centroid displacement is exactly mean(v_S)·dt and, per proxy mode,
// velocity: shear = v_S / c_velocity (both frames); displacement: shear_now − shear_prev =
// v_S·dt / c_displacement. v_S is the tangential (x, y) part of R_GSᵀ(ω × q_G + t) at the contact
// points q_G = R_GS q_S + p_GS, with q_S exactly as ContactDetectorRef builds them.
struct RigidContactScene {
  Eigen::Matrix3d R_GS = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_GS = Eigen::Vector3d::Zero();
  Eigen::Vector3d contact_centre_G = Eigen::Vector3d::Zero();
  double radius_m = 4e-3;
  double peak_fz = 0.1;
  Eigen::Vector3d omega_G = Eigen::Vector3d::Zero();
  Eigen::Vector3d t_G = Eigen::Vector3d::Zero();
  double dt = 1.0 / 120.0;
};
struct SyntheticSensorFrames {
  dsp::ScalarField fz;                                    // Q16
  dsp::GridMask valid;                                    // all valid
  dsp::VectorField w_prev, w_now, shear_prev, shear_now;  // Q16
  std::vector<PointSample> points_G;  // contact points and tangential rigid velocities, in G
};
SyntheticSensorFrames render_rigid_contact(const dsp::Calibration& cal,
                                           const RigidContactScene& scene);

}  // namespace tacse3::dsp_ref
