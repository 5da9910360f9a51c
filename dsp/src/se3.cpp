// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: SO(3)/SE(3) exponential and logarithm, poses as quaternion + translation (double).
#include "tacse3/dsp/se3.hpp"

#include <cmath>

namespace tacse3::dsp {
namespace {

// Below this angle the closed forms lose digits to cancellation ((θ − sinθ)/θ³ has ~1e-12
// relative error at θ = 1e-2); the series up to θ⁶ are accurate to < 1e-20 there.
constexpr double kSmallAngle = 1e-2;

// Normalised quaternion with w ≥ 0 (q and −q are the same rotation; fixing the sign keeps
// so3_log in the principal branch).
Eigen::Quaterniond normalised(const Eigen::Quaterniond& q) noexcept {
  const double n = q.norm();
  if (!(n > 0.0) || !std::isfinite(n)) return Eigen::Quaterniond::Identity();
  Eigen::Quaterniond r(q.coeffs() / n);
  if (r.w() < 0.0) r.coeffs() = -r.coeffs();
  return r;
}

}  // namespace

Eigen::Matrix4d Pose::matrix() const noexcept {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = rotation();
  m.topRightCorner<3, 1>() = p;
  return m;
}

Eigen::Matrix3d hat(const Eigen::Vector3d& w) noexcept {
  Eigen::Matrix3d m;
  m << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return m;
}

Eigen::Matrix4d hat(const Vector6d& xi) noexcept {
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m.topLeftCorner<3, 3>() = hat(Eigen::Vector3d(xi.head<3>()));
  m.topRightCorner<3, 1>() = xi.tail<3>();
  return m;
}

Eigen::Quaterniond so3_exp(const Eigen::Vector3d& phi) noexcept {
  const double t2 = phi.squaredNorm();
  const double t = std::sqrt(t2);
  double c, s_over_t;  // cos(θ/2), sin(θ/2)/θ
  if (t < kSmallAngle) {
    const double t4 = t2 * t2;
    c = 1.0 - t2 / 8.0 + t4 / 384.0 - t4 * t2 / 46080.0;
    s_over_t = 0.5 - t2 / 48.0 + t4 / 3840.0 - t4 * t2 / 645120.0;
  } else {
    c = std::cos(0.5 * t);
    s_over_t = std::sin(0.5 * t) / t;
  }
  return normalised(
      Eigen::Quaterniond(c, s_over_t * phi.x(), s_over_t * phi.y(), s_over_t * phi.z()));
}

Eigen::Matrix3d so3_exp_matrix(const Eigen::Vector3d& phi) noexcept {
  return so3_exp(phi).toRotationMatrix();
}

Eigen::Vector3d so3_log(const Eigen::Quaterniond& q_in) noexcept {
  const Eigen::Quaterniond q = normalised(q_in);
  const Eigen::Vector3d v = q.vec();
  const double s = v.norm();  // sin(θ/2)
  const double w = q.w();     // cos(θ/2) ≥ 0
  double k;                   // θ / sin(θ/2)
  if (s < 1e-6) {
    // θ = 2 atan(s/w) = 2 (s/w − s³/(3w³) + …); w ≈ 1 here.
    k = 2.0 / w * (1.0 - s * s / (3.0 * w * w));
  } else {
    k = 2.0 * std::atan2(s, w) / s;
  }
  return k * v;
}

Eigen::Matrix3d so3_left_jacobian(const Eigen::Vector3d& phi) noexcept {
  const double t2 = phi.squaredNorm();
  const double t = std::sqrt(t2);
  double B, C;  // (1 − cosθ)/θ², (θ − sinθ)/θ³
  if (t < kSmallAngle) {
    const double t4 = t2 * t2;
    B = 0.5 - t2 / 24.0 + t4 / 720.0 - t4 * t2 / 40320.0;
    C = 1.0 / 6.0 - t2 / 120.0 + t4 / 5040.0 - t4 * t2 / 362880.0;
  } else {
    B = (1.0 - std::cos(t)) / t2;
    C = (t - std::sin(t)) / (t2 * t);
  }
  const Eigen::Matrix3d K = hat(phi);
  return Eigen::Matrix3d::Identity() + B * K + C * K * K;
}

Eigen::Matrix3d so3_left_jacobian_inverse(const Eigen::Vector3d& phi) noexcept {
  const double t2 = phi.squaredNorm();
  const double t = std::sqrt(t2);
  double D;  // (1 − θ sinθ / (2(1 − cosθ))) / θ²
  if (t < kSmallAngle) {
    const double t4 = t2 * t2;
    D = 1.0 / 12.0 + t2 / 720.0 + t4 / 30240.0 + t4 * t2 / 1209600.0;
  } else {
    D = (1.0 - t * std::sin(t) / (2.0 * (1.0 - std::cos(t)))) / t2;
  }
  const Eigen::Matrix3d K = hat(phi);
  return Eigen::Matrix3d::Identity() - 0.5 * K + D * K * K;
}

Pose se3_exp(const Vector6d& xi) noexcept {
  const Eigen::Vector3d phi = xi.head<3>();
  const Eigen::Vector3d rho = xi.tail<3>();
  Pose T;
  T.q = so3_exp(phi);
  T.p = so3_left_jacobian(phi) * rho;
  return T;
}

Vector6d se3_log(const Pose& T) noexcept {
  const Eigen::Vector3d phi = so3_log(T.q);
  Vector6d xi;
  xi.head<3>() = phi;
  xi.tail<3>() = so3_left_jacobian_inverse(phi) * T.p;
  return xi;
}

Pose compose(const Pose& a, const Pose& b) noexcept {
  Pose r;
  r.q = normalised(a.q * b.q);
  r.p = a.q * b.p + a.p;
  return r;
}

Pose inverse(const Pose& a) noexcept {
  Pose r;
  r.q = normalised(a.q.conjugate());
  r.p = -(r.q * a.p);
  return r;
}

Eigen::Vector3d transform_point(const Pose& T, const Eigen::Vector3d& x) noexcept {
  return T.q * x + T.p;
}

Matrix6d adjoint(const Pose& T) noexcept {
  const Eigen::Matrix3d R = T.rotation();
  Matrix6d A = Matrix6d::Zero();
  A.topLeftCorner<3, 3>() = R;
  A.bottomLeftCorner<3, 3>() = hat(T.p) * R;
  A.bottomRightCorner<3, 3>() = R;
  return A;
}

Vector6d adjoint_apply(const Pose& T, const Vector6d& xi) noexcept {
  const Eigen::Vector3d w = T.q * Eigen::Vector3d(xi.head<3>());
  Vector6d r;
  r.head<3>() = w;
  r.tail<3>() = T.q * Eigen::Vector3d(xi.tail<3>()) + T.p.cross(w);
  return r;
}

Pose integrate_body(const Pose& T, const Vector6d& xi_b, double dt) noexcept {
  return compose(T, se3_exp(xi_b * dt));
}

Pose integrate_spatial(const Pose& T, const Vector6d& xi_G, double dt) noexcept {
  // exp(ξ̂_G Δt) T  ==  T exp((Ad_{T⁻¹} ξ_G)^ Δt); left-multiplication avoids forming Ad.
  return compose(se3_exp(xi_G * dt), T);
}

Status PoseIntegrator::step_spatial(const Vector6d& xi_G, double dt) noexcept {
  if (!xi_G.allFinite() || !std::isfinite(dt) || !(dt > 0.0) || dt > 1.0) {
    return Status::kBadArgument;
  }
  T_ = integrate_spatial(T_, xi_G, dt);
  return Status::kOk;
}

}  // namespace tacse3::dsp
