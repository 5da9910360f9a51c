// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: dual-sensor fusion of the per-sensor motion into one twist in the gripper frame G.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "tacse3/dsp/confidence.hpp"
#include "tacse3/dsp/motion.hpp"
#include "tacse3/dsp/se3.hpp"
#include "tacse3/dsp/solve3.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

enum class FusionMethod : std::uint8_t {
  // Paper Sec. V-B: ξ = ½(ξ₁ + S ξ₂) of the per-sensor own-frame twists, then rotated into G with
  // sensor 1's R_GS. The lever arm to the object is absorbed by the per-axis calibrated scales.
  kPaper = 0,
  // Both sensors' moments mapped into G with the extrinsics and the current finger separation,
  // ONE 3x3 solve for ω over all points (the lever arm W/2 is physical), translations averaged in
  // G and referred to G's origin. Output is a spatial twist in G in SI units without scales.
  kJoint = 1,
};

// Pose of sensor frame S in G for finger separation W: x_G = R_GS x_S + p_GS(W),
// p_GS(W) = offset_m + separation_sign · (W/2) · z_G.
struct SensorExtrinsics {
  Eigen::Matrix3d R_GS = Eigen::Matrix3d::Identity();
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();
  double separation_sign = 1.0;
  Eigen::Vector3d p_GS(double separation_m) const noexcept {
    return offset_m + separation_sign * 0.5 * separation_m * Eigen::Vector3d::UnitZ();
  }
};

// The board's default mounts (contract "Frames"): left pad (sensor 1) at z = +W/2 with R = I;
// right pad (sensor 2) at z = −W/2, mirrored, R = diag(1, −1, −1).
SensorExtrinsics left_pad_extrinsics() noexcept;
SensorExtrinsics right_pad_extrinsics() noexcept;

struct FusionConfig {
  FusionMethod method = FusionMethod::kJoint;
  // S of the paper (diag of s_ωx, s_ωy, s_ωz, s_tx, s_ty, s_tz); mirrored board default.
  std::array<double, 6> sign{1.0, -1.0, -1.0, 1.0, -1.0, -1.0};
  std::array<SensorExtrinsics, 2> extrinsics{left_pad_extrinsics(), right_pad_extrinsics()};
  // Joint solve regularisation (same meaning and defaults as Calibration::solve_*).
  double solve_lambda_rel = 1e-6;
  double solve_lever_floor_m = 1e-5;
  double solve_rcond_min = 1e-4;
};

// kBadArgument unless: signs are ±1, every R_GS is a rotation (‖RᵀR − I‖ < 1e-6, det > 0), all
// numbers finite, regularisation in the Calibration ranges, method known.
Status validate(const FusionConfig& cfg) noexcept;

// Bits of FusedMotion::rotation_sensors / translation_sensors.
inline constexpr std::uint8_t kSensor1 = 1;
inline constexpr std::uint8_t kSensor2 = 2;

struct FusedMotion {
  Vector6d xi = Vector6d::Zero();  // [ω (rad/s); t (m/s)] in G; never NaN; 0 when invalid
  FusionMethod method = FusionMethod::kJoint;
  Status status = Status::kOk;  // kBadArgument for a bad config or separation
  std::array<bool, 2> contact{false, false};
  std::uint8_t rotation_sensors = 0;     // which sensors entered ω
  std::uint8_t translation_sensors = 0;  // which sensors entered t
  bool single_sensor = false;            // exactly one sensor contributed (to ω or t)
  bool rotation_valid = false;
  bool translation_valid = false;
  bool valid = false;  // rotation_valid && translation_valid
  // rcond of the 3x3 normal equations (min over sensors for kPaper). kJoint with one pad: still
  // the 3x3 system's, although ω then comes from the 1-D solve about the pad normal.
  double rcond = 0.0;
  // The joint fit's quality whatever the method (fit_quality()); TwistConfidence's input.
  FitQuality quality{};
  // Observed ω directions (min over sensors for kPaper); kJoint with one pad: 1 (0 when the pad's
  // points have no lever about its normal, then ω = 0 and rotation_valid is false).
  int rank = 0;
  // kJoint: the point (in G) whose velocity the averaged centroid translation measured; t was
  // referred from it to G's origin (t = t̄ − ω × m̄). kPaper: unused (zero).
  Eigen::Vector3d reference_point = Eigen::Vector3d::Zero();
};

// Fuses sensor 1 (left pad, extrinsics[0]) and sensor 2 (right pad, extrinsics[1]).
// Either pointer may be nullptr (sensor absent); one sensor without contact or absent gives
// single-sensor operation, flagged in single_sensor.
// separation_m: current distance W between the two gel surfaces, finite, in [0, 0.5] m.
// A sensor enters ω if it has contact and a valid proxy (rotation_valid in kPaper), and t if its
// translation_valid. Per-axis scales: kPaper uses each sensor's already-scaled ξ; kJoint applies
// mean_s(R_GS diag(rotation_scale_s) R_GSᵀ) to ω (identity with default scales).
Status fuse(const SensorMotion* s1, const SensorMotion* s2, const FusionConfig& cfg,
            double separation_m, FusedMotion& out) noexcept;

// The quality of the joint least squares over the pads that enter ω (fuse()'s rule), from their
// moments in G: conditioning, residual (needs ContactMoments::svv), the pads' agreement about
// their normals and the smaller pad's size (FitQuality). kJoint solves the same system; kPaper's
// twist is read from the same points. No pad: all zero. Fixed work, no heap, never NaN.
FitQuality fit_quality(const SensorMotion* s1, const SensorMotion* s2, const FusionConfig& cfg,
                       double separation_m) noexcept;

}  // namespace tacse3::dsp
