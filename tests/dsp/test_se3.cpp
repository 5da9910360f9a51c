// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: SO(3)/SE(3) exp/log against closed forms and the matrix exponential series,
// constant-twist integration against the exact screw motion, group identities.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>

#include "tacse3/dsp/se3.hpp"

namespace tacse3::dsp {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Matrix exponential by scaling and squaring of a 20-term Taylor series: independent of the
// closed forms under test, accurate to ~1e-15 for the norms used here.
template <int N>
Eigen::Matrix<double, N, N> expm_series(const Eigen::Matrix<double, N, N>& X) {
  using M = Eigen::Matrix<double, N, N>;
  int s = 0;
  double norm = X.cwiseAbs().rowwise().sum().maxCoeff();
  while (norm > 0.25) {
    norm *= 0.5;
    ++s;
  }
  const M Y = X / std::ldexp(1.0, s);
  M term = M::Identity(), sum = M::Identity();
  for (int k = 1; k <= 20; ++k) {
    term = term * Y / static_cast<double>(k);
    sum += term;
  }
  for (int i = 0; i < s; ++i) sum = sum * sum;
  return sum;
}

Vector6d random_twist(std::mt19937& rng, double max_angle, double max_trans) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::Vector3d w(n(rng), n(rng), n(rng));
  w = w.normalized() * max_angle * u(rng);
  Vector6d xi;
  xi << w, max_trans * Eigen::Vector3d(n(rng), n(rng), n(rng));
  return xi;
}

Pose random_pose(std::mt19937& rng) {
  return se3_exp(random_twist(rng, 3.0, 0.1));
}

double pose_distance(const Pose& a, const Pose& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

TEST(Se3, So3ExpMatchesRodriguesAndAngleAxis) {
  std::mt19937 rng(10);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d phi = random_twist(rng, kPi - 1e-3, 0.0).head<3>();
    const double t = phi.norm();
    const Eigen::Matrix3d K = hat(phi);
    const Eigen::Matrix3d R_rod =
        Eigen::Matrix3d::Identity() + std::sin(t) / t * K + (1.0 - std::cos(t)) / (t * t) * K * K;
    const Eigen::Matrix3d R = so3_exp_matrix(phi);
    EXPECT_LT((R - R_rod).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_LT((R - Eigen::AngleAxisd(t, phi / t).toRotationMatrix()).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_NEAR(so3_exp(phi).norm(), 1.0, 1e-15);
  }
}

TEST(Se3, SmallAngleSeriesMatchesMatrixExponential) {
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  // Straddle the series threshold (1e-2) and go down to exact zero.
  for (double angle : {0.0, 1e-12, 1e-8, 1e-6, 1e-4, 1e-3, 0.999e-2, 1e-2, 1.001e-2, 0.1, 1.0}) {
    for (int i = 0; i < 20; ++i) {
      Eigen::Vector3d dir(n(rng), n(rng), n(rng));
      dir.normalize();
      Vector6d xi;
      xi << angle * dir, Eigen::Vector3d(n(rng), n(rng), n(rng)) * 0.05;
      const Eigen::Matrix4d E = expm_series<4>(hat(xi));
      const Pose T = se3_exp(xi);
      EXPECT_LT((T.matrix() - E).cwiseAbs().maxCoeff(), 2e-15) << "angle " << angle;
      const Eigen::Matrix3d Er = expm_series<3>(hat(Eigen::Vector3d(angle * dir)));
      EXPECT_LT((so3_exp_matrix(angle * dir) - Er).cwiseAbs().maxCoeff(), 2e-15);
    }
  }
}

TEST(Se3, ExpMatchesMatrixExponentialForLargeTwists) {
  std::mt19937 rng(12);
  for (int i = 0; i < 300; ++i) {
    const Vector6d xi = random_twist(rng, 3.0, 0.5);
    const Eigen::Matrix4d E = expm_series<4>(hat(xi));
    EXPECT_LT((se3_exp(xi).matrix() - E).cwiseAbs().maxCoeff(), 1e-13);
  }
}

TEST(Se3, LogInvertsExp) {
  std::mt19937 rng(13);
  for (double max_angle : {1e-9, 1e-5, 1e-2, 0.5, 3.0}) {
    for (int i = 0; i < 300; ++i) {
      const Vector6d xi = random_twist(rng, max_angle, 0.2);
      const Vector6d back = se3_log(se3_exp(xi));
      EXPECT_LT((back - xi).cwiseAbs().maxCoeff(), 1e-12 * (1.0 + xi.norm())) << max_angle;
    }
  }
  // Quaternion sign: q and −q give the same log.
  const Pose T = se3_exp((Vector6d() << 0.3, -0.2, 0.1, 0.01, 0.02, 0.03).finished());
  Pose Tn = T;
  Tn.q.coeffs() = -Tn.q.coeffs();
  EXPECT_LT((se3_log(Tn) - se3_log(T)).norm(), 1e-15);
}

TEST(Se3, CompositionAndInverseIdentities) {
  std::mt19937 rng(14);
  for (int i = 0; i < 100; ++i) {
    const Pose A = random_pose(rng), B = random_pose(rng), C = random_pose(rng);
    EXPECT_LT(pose_distance(compose(A, inverse(A)), Pose{}), 1e-15);
    EXPECT_LT(pose_distance(compose(inverse(A), A), Pose{}), 1e-15);
    EXPECT_LT(pose_distance(inverse(compose(A, B)), compose(inverse(B), inverse(A))), 1e-15);
    EXPECT_LT(pose_distance(compose(compose(A, B), C), compose(A, compose(B, C))), 4e-15);
    EXPECT_LT((compose(A, B).matrix() - A.matrix() * B.matrix()).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT((inverse(A).matrix() - A.matrix().inverse()).cwiseAbs().maxCoeff(), 1e-14);
    const Eigen::Vector3d x(0.01, -0.02, 0.03);
    EXPECT_LT(
        (transform_point(compose(A, B), x) - transform_point(A, transform_point(B, x))).norm(),
        1e-15);
    // exp(ξ) exp(−ξ) = I and exp(2ξ) = exp(ξ)².
    const Vector6d xi = random_twist(rng, 1.5, 0.1);
    EXPECT_LT(pose_distance(compose(se3_exp(xi), se3_exp(-xi)), Pose{}), 1e-15);
    EXPECT_LT(pose_distance(se3_exp(2.0 * xi), compose(se3_exp(xi), se3_exp(xi))), 1e-14);
    // Adjoint: T ξ̂ T⁻¹ = (Ad_T ξ)^, exp(Ad_T ξ) = T exp(ξ) T⁻¹, Ad_{AB} = Ad_A Ad_B.
    const Eigen::Matrix4d lhs = A.matrix() * hat(xi) * A.matrix().inverse();
    EXPECT_LT((lhs - hat(Vector6d(adjoint(A) * xi))).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_LT((adjoint_apply(A, xi) - adjoint(A) * xi).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT(pose_distance(se3_exp(adjoint(A) * xi), compose(compose(A, se3_exp(xi)), inverse(A))),
              1e-14);
    EXPECT_LT((adjoint(compose(A, B)) - adjoint(A) * adjoint(B)).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_LT((adjoint(inverse(A)) - adjoint(A).inverse()).cwiseAbs().maxCoeff(), 1e-13);
  }
}

// Exact screw motion of a constant spatial twist (ω ≠ 0) over time T: rotation by |ω|T about
// the axis through c = ω × v/|ω|², plus a slide h|ω|T along it, h = ω·v/|ω|².
Pose screw_motion(const Vector6d& xi, double T) {
  const Eigen::Vector3d w = xi.head<3>(), v = xi.tail<3>();
  const double wn = w.norm();
  const Eigen::Vector3d axis = w / wn;
  const Eigen::Vector3d c = w.cross(v) / (wn * wn);
  const double h = w.dot(v) / (wn * wn);
  Pose S;
  S.q = Eigen::Quaterniond(Eigen::AngleAxisd(wn * T, axis));
  S.p = c - S.q * c + h * wn * T * axis;
  return S;
}

TEST(Se3, ConstantTwistIntegrationMatchesExactScrewMotion) {
  std::mt19937 rng(15);
  const double dt = 1.0 / 120.0;
  const int steps = 1200;  // 10 s at 120 Hz
  for (int trial = 0; trial < 4; ++trial) {
    Vector6d xi;
    xi << random_twist(rng, 1.0, 0.02).head<3>() + Eigen::Vector3d(0.05, 0.0, 0.0),
        random_twist(rng, 0.0, 0.02).tail<3>();
    const Pose T0 = random_pose(rng);
    const Pose S = screw_motion(xi, steps * dt);
    // Spatial twist (what fusion produces): T(t) = exp(ξ̂ t) T0.
    PoseIntegrator integ;
    integ.reset(T0);
    // Body twist: T(t) = T0 exp(ξ̂ t).
    Pose Tb = T0;
    for (int k = 0; k < steps; ++k) {
      ASSERT_EQ(integ.step_spatial(xi, dt), Status::kOk);
      Tb = integrate_body(Tb, xi, dt);
    }
    EXPECT_LT(pose_distance(integ.pose(), compose(S, T0)), 1e-12);
    EXPECT_LT(pose_distance(Tb, compose(T0, S)), 1e-12);
    // Spatial integration is body integration of Ad_{T⁻¹} ξ (evaluated at the current pose).
    const Pose T1 = integrate_spatial(T0, xi, dt);
    const Pose T1b = integrate_body(T0, adjoint(inverse(T0)) * xi, dt);
    EXPECT_LT(pose_distance(T1, T1b), 1e-15);
  }
  // Pure translation (ω = 0): the closed form degenerates to p += v T.
  Vector6d xt;
  xt << 0.0, 0.0, 0.0, 0.01, -0.02, 0.005;
  PoseIntegrator integ;
  for (int k = 0; k < steps; ++k) ASSERT_EQ(integ.step_spatial(xt, dt), Status::kOk);
  // 1200 additions of ~1e-4 m: round-off ~ steps · ulp(0.1 m).
  EXPECT_LT((integ.pose().p - xt.tail<3>() * steps * dt).norm(), 1e-13);
  EXPECT_EQ(integ.pose().q.w(), 1.0);
}

TEST(Se3, QuaternionStaysUnitOverLongIntegration) {
  std::mt19937 rng(16);
  PoseIntegrator integ;
  for (int k = 0; k < 5000; ++k) {
    ASSERT_EQ(integ.step_spatial(random_twist(rng, 2.0, 0.05), 1.0 / 120.0), Status::kOk);
  }
  EXPECT_NEAR(integ.pose().q.norm(), 1.0, 1e-15);
  EXPECT_TRUE(integ.pose().p.allFinite());
}

TEST(Se3, IntegratorRejectsNonFiniteInputs) {
  PoseIntegrator integ;
  const Vector6d ok = (Vector6d() << 0.1, 0, 0, 0.01, 0, 0).finished();
  ASSERT_EQ(integ.step_spatial(ok, 0.01), Status::kOk);
  const Pose before = integ.pose();
  Vector6d bad = ok;
  bad(2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(integ.step_spatial(bad, 0.01), Status::kBadArgument);
  EXPECT_EQ(integ.step_spatial(ok, std::numeric_limits<double>::infinity()), Status::kBadArgument);
  EXPECT_EQ(integ.step_spatial(ok, -0.01), Status::kBadArgument);
  EXPECT_EQ(integ.step_spatial(ok, 0.0), Status::kBadArgument);
  EXPECT_EQ(pose_distance(integ.pose(), before), 0.0);
  // A non-unit quaternion is renormalised by every operation.
  Pose T;
  T.q.coeffs() << 0.0, 0.0, 0.0, 2.0;
  EXPECT_NEAR(compose(T, Pose{}).q.norm(), 1.0, 1e-16);
}

}  // namespace
}  // namespace tacse3::dsp
