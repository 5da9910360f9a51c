// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: fixed 3x3 regularised solve against Eigen's full-pivot LU and SVD.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>

#include "tacse3/dsp/solve3.hpp"

namespace tacse3::dsp {
namespace {

Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

// SPD with the given eigenvalues in a random basis.
Eigen::Matrix3d spd(std::mt19937& rng, const Eigen::Vector3d& ev) {
  const Eigen::Matrix3d V = random_rotation(rng);
  return V * ev.asDiagonal() * V.transpose();
}

Solve3Options exact() {
  Solve3Options o;
  o.lambda_rel = 0.0;
  o.lambda_abs = 0.0;
  o.rcond_min = 1e-12;
  return o;
}

TEST(Solve3, RandomSpdMatchesFullPivLu) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> logu(-2.0, 0.0), u(-1.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 2000; ++trial) {
    // Condition numbers up to 1e2, absolute scale from 1e-12 (mm² moments) to 1e6.
    const double scale = std::pow(10.0, 18.0 * (0.5 + 0.5 * u(rng)) - 12.0);
    const Eigen::Vector3d ev(std::pow(10.0, logu(rng)), std::pow(10.0, logu(rng)), 1.0);
    const Eigen::Matrix3d A = scale * spd(rng, ev);
    const Eigen::Vector3d b = scale * Eigen::Vector3d(u(rng), u(rng), u(rng));
    const Eigen::Vector3d x_lu = A.fullPivLu().solve(b);
    const Solve3Result r = solve3(A, b, exact());
    ASSERT_TRUE(r.valid);
    EXPECT_EQ(r.rank, 3);
    const double rel = (r.x - x_lu).norm() / x_lu.norm();
    worst = std::max(worst, rel);
    // rcond is λ_min/λ_max of A.
    EXPECT_NEAR(r.rcond, ev.minCoeff() / ev.maxCoeff(), 1e-9);
  }
  // Backward-stable solves of cond ≤ 1e2 systems: a few ulp · cond.
  EXPECT_LT(worst, 1e-13);
}

TEST(Solve3, DefaultRegularisationBiasIsBoundedByLambdaOverLambdaMin) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 500; ++trial) {
    const Eigen::Vector3d ev(0.01 + 0.99 * std::abs(u(rng)), 0.5, 1.0);
    const Eigen::Matrix3d A = spd(rng, ev);
    const Eigen::Vector3d b(u(rng), u(rng), u(rng));
    const Solve3Options def;  // λ = 1e-6 · tr(A)/3
    const Solve3Result r = solve3(A, b, def);
    const Eigen::Vector3d x_lu = A.fullPivLu().solve(b);
    ASSERT_TRUE(r.valid);
    const double lambda = def.lambda_rel * A.trace() / 3.0;
    EXPECT_DOUBLE_EQ(r.lambda, lambda);
    // Tikhonov shrinks each eigen-component by λ_i/(λ_i + λ): relative error ≤ λ/λ_min.
    EXPECT_LE((r.x - x_lu).norm(), 1.01 * lambda / ev.minCoeff() * x_lu.norm());
    // and it equals the exact solution of the shifted system.
    const Eigen::Vector3d x_shift = (A + lambda * Eigen::Matrix3d::Identity()).fullPivLu().solve(b);
    EXPECT_LT((r.x - x_shift).norm(), 1e-12 * x_shift.norm());
  }
}

TEST(Solve3, NearSingularMatchesLuWithinConditioningAndIsFlagged) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double cond : {1e5, 1e6, 1e8, 1e10}) {
    for (int trial = 0; trial < 200; ++trial) {
      const Eigen::Matrix3d A = spd(rng, Eigen::Vector3d(1.0 / cond, 0.3, 1.0));
      const Eigen::Vector3d b(u(rng), u(rng), u(rng));
      const Eigen::Vector3d x_lu = A.fullPivLu().solve(b);
      const Solve3Result r = solve3(A, b, exact());
      ASSERT_TRUE(r.x.allFinite());
      // Forward error of any backward-stable solver: ~ cond · ε.
      EXPECT_LT((r.x - x_lu).norm() / x_lu.norm(), cond * 1e-14) << "cond " << cond;
      EXPECT_NEAR(std::log10(r.rcond), -std::log10(cond), 0.01) << "cond " << cond;
      // With the default rcond_min = 1e-4 every one of these is flagged, rank 2.
      const Solve3Result rd = solve3(A, b);
      EXPECT_FALSE(rd.valid);
      EXPECT_EQ(rd.rank, 2);
      ASSERT_TRUE(rd.x.allFinite());
    }
  }
}

TEST(Solve3, SingularSystemsAreFiniteFlaggedAndPseudoInverseLike) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int rank = 0; rank <= 2; ++rank) {
    for (int trial = 0; trial < 200; ++trial) {
      Eigen::Vector3d ev(0.0, rank >= 2 ? 0.4 : 0.0, rank >= 1 ? 1.0 : 0.0);
      const Eigen::Matrix3d A = spd(rng, ev);
      // b in the range of A (consistent normal equations, as AᵀA ω = Aᵀb always are).
      const Eigen::Vector3d b = A * Eigen::Vector3d(u(rng), u(rng), u(rng));
      for (const bool regularised : {true, false}) {
        const Solve3Result r = solve3(A, b, regularised ? Solve3Options{} : exact());
        ASSERT_TRUE(r.x.allFinite());
        EXPECT_FALSE(r.valid);
        EXPECT_EQ(r.rank, rank);
        EXPECT_LT(r.rcond, 1e-12);
        if (rank == 0) {
          EXPECT_EQ(r.x, Eigen::Vector3d::Zero());
          continue;
        }
        if (regularised) {
          // Tikhonov tends to the minimum-norm (pseudo-inverse) solution: no component along
          // the null space; bias λ/λ_i ≤ 1e-6 · (tr/3)/0.4 on the range.
          const Eigen::Vector3d x_pinv =
              A.jacobiSvd(Eigen::ComputeFullU | Eigen::ComputeFullV).solve(b);
          EXPECT_LT((r.x - x_pinv).norm(), 1e-5 * (1.0 + x_pinv.norm())) << "rank " << rank;
        } else {
          // λ = 0: the pivot floor drops the null direction; what remains solves the system.
          EXPECT_LT((A * r.x - b).norm(), 1e-9 * (1.0 + b.norm())) << "rank " << rank;
        }
      }
    }
  }
}

TEST(Solve3, EmptyAndNonFiniteInputsGiveZeroInvalidNeverNan) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d b(1.0, 2.0, 3.0);
  for (const Eigen::Matrix3d& A :
       {Eigen::Matrix3d(Eigen::Matrix3d::Zero()), Eigen::Matrix3d(-Eigen::Matrix3d::Identity()),
        Eigen::Matrix3d(Eigen::Matrix3d::Constant(nan)),
        Eigen::Matrix3d(Eigen::Matrix3d::Identity() * inf)}) {
    const Solve3Result r = solve3(A, b);
    EXPECT_FALSE(r.valid);
    EXPECT_EQ(r.x, Eigen::Vector3d::Zero());
    EXPECT_EQ(r.rcond, 0.0);
  }
  const Solve3Result rb = solve3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(nan, 0.0, 0.0));
  EXPECT_FALSE(rb.valid);
  EXPECT_EQ(rb.x, Eigen::Vector3d::Zero());
  // Overflowing right-hand side: the result would be inf; reported as invalid zero.
  const Solve3Result ro =
      solve3(Eigen::Matrix3d::Identity() * 1e-300, Eigen::Vector3d(1e300, 0.0, 0.0));
  EXPECT_FALSE(ro.valid);
  EXPECT_TRUE(ro.x.allFinite());
}

TEST(Solve3, ScaleInvariance) {
  std::mt19937 rng(5);
  const Eigen::Matrix3d A = spd(rng, Eigen::Vector3d(0.2, 0.5, 1.0));
  const Eigen::Vector3d b(0.3, -0.1, 0.7);
  const Solve3Result r1 = solve3(A, b);
  for (double s : {1e-20, 1e-10, 1e10, 1e20}) {
    const Solve3Result rs = solve3(s * A, s * b);
    EXPECT_TRUE(rs.valid);
    EXPECT_LT((rs.x - r1.x).norm(), 1e-13 * r1.x.norm()) << s;
    EXPECT_NEAR(rs.rcond, r1.rcond, 1e-12);
  }
}

}  // namespace
}  // namespace tacse3::dsp
