// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: SO(3)/SE(3) exponential and logarithm, poses as quaternion + translation (double).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Twist ordering follows the paper (Sec. IV-C): ξ = [ω; t] (rotation first), units rad/s and m/s
// for rates, rad and m for an increment ξΔt. ξ̂ = [[ω]×, t; 0, 0] ∈ se(3).
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// Rigid transform x ↦ R(q) x + p. The quaternion is kept unit-norm by every function here.
struct Pose {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotation() const noexcept { return q.toRotationMatrix(); }
  Eigen::Matrix4d matrix() const noexcept;
};

Eigen::Matrix3d hat(const Eigen::Vector3d& w) noexcept;  // [w]×
Eigen::Matrix4d hat(const Vector6d& xi) noexcept;        // ξ̂

// exp: so(3) → SO(3), closed form (Rodrigues / half-angle quaternion) with Taylor series below
// θ = 1e-2 so there is no 0/0 and no cancellation near the identity.
Eigen::Quaterniond so3_exp(const Eigen::Vector3d& phi) noexcept;
Eigen::Matrix3d so3_exp_matrix(const Eigen::Vector3d& phi) noexcept;
// log: SO(3) → so(3), |result| ≤ π. Series for small angles.
Eigen::Vector3d so3_log(const Eigen::Quaterniond& q) noexcept;
// Left Jacobian V(φ) = I + (1−cosθ)/θ² [φ]× + (θ−sinθ)/θ³ [φ]×², and its inverse.
Eigen::Matrix3d so3_left_jacobian(const Eigen::Vector3d& phi) noexcept;
Eigen::Matrix3d so3_left_jacobian_inverse(const Eigen::Vector3d& phi) noexcept;

// exp: se(3) → SE(3): R = exp([φ]×), p = V(φ) ρ for ξ = [φ; ρ].
Pose se3_exp(const Vector6d& xi) noexcept;
// log: SE(3) → se(3), the inverse of se3_exp for rotation angles < π.
Vector6d se3_log(const Pose& T) noexcept;

Pose compose(const Pose& a, const Pose& b) noexcept;  // a·b (renormalised)
Pose inverse(const Pose& a) noexcept;
Eigen::Vector3d transform_point(const Pose& T, const Eigen::Vector3d& x) noexcept;
// Ad_T for ξ = [ω; t]: Ad_T ξ = [R ω; R t + p × R ω], so that T exp(ξ̂) T⁻¹ = exp((Ad_T ξ)^).
Matrix6d adjoint(const Pose& T) noexcept;
// Applies Ad_T without forming the 6x6.
Vector6d adjoint_apply(const Pose& T, const Vector6d& xi) noexcept;

// Paper Sec. IV-D: T ← T · exp(ξ̂_b Δt) with a BODY twist ξ_b (expressed in the moving frame).
Pose integrate_body(const Pose& T, const Vector6d& xi_b, double dt) noexcept;
// The fused twist is measured in the gripper frame G (spatial twist: ω and the velocity of the
// material point at G's origin). T ← exp(ξ̂_G Δt) · T, which equals T · exp((Ad_{T⁻¹} ξ_G)^ Δt):
// the paper's right-multiplication after converting the twist to the body frame.
Pose integrate_spatial(const Pose& T, const Vector6d& xi_G, double dt) noexcept;

// Holds the integrated object pose T (object frame in G, starts at identity).
class PoseIntegrator {
 public:
  void reset(const Pose& T0 = Pose{}) noexcept { T_ = T0; }
  // kBadArgument (pose unchanged) if xi is not finite or dt is not finite/positive/≤ 1 s.
  Status step_spatial(const Vector6d& xi_G, double dt) noexcept;
  const Pose& pose() const noexcept { return T_; }

 private:
  Pose T_{};
};

}  // namespace tacse3::dsp
