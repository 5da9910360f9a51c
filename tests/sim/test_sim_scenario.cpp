// SPDX-License-Identifier: Apache-2.0
// Tests of the simulator's scenario: timeline, regimes and the analytic truth trajectory.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tacse3/sim/scenario.hpp"

namespace tacse3::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

ScenarioSpec spec_for(MotionAxis axis, double magnitude) {
  ScenarioSpec s;
  s.axis = axis;
  s.magnitude = magnitude;
  return s;
}

double angle_of(const Eigen::Quaterniond& q) {
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

TEST(SimScenario, RotationReachesTheCommandedAngleAboutTheCommandedAxis) {
  const MotionAxis axes[] = {MotionAxis::kRx, MotionAxis::kRy, MotionAxis::kRz};
  const Eigen::Vector3d units[] = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                   Eigen::Vector3d::UnitZ()};
  for (int a = 0; a < 3; ++a) {
    for (double deg : {30.0, 60.0, 90.0, -45.0}) {
      const Scenario scn(spec_for(axes[a], deg));
      // Identity until the motion starts (approach, grasp, settle).
      EXPECT_NEAR(angle_of(scn.pose(0.0).q), 0.0, 1e-15);
      EXPECT_NEAR(angle_of(scn.pose(scn.motion_start_s()).q), 0.0, 1e-15);
      const Pose end = scn.pose(scn.motion_end_s());
      const Pose last = scn.pose(scn.duration_s());
      EXPECT_NEAR(angle_of(end.q), std::abs(deg) * kDeg, 1e-12);
      const Eigen::AngleAxisd aa(end.q);
      EXPECT_NEAR(std::abs(aa.axis().dot(units[a])), 1.0, 1e-12);
      EXPECT_NEAR((aa.axis() * aa.angle() - units[a] * deg * kDeg).norm(), 0.0, 1e-12);
      EXPECT_NEAR(end.p.norm(), 0.0, 1e-15);
      EXPECT_NEAR(angle_of(last.q.conjugate() * end.q), 0.0, 1e-12);  // held still
      // Half-way in time is half-way in angle (the profile is symmetric).
      const double mid = 0.5 * (scn.motion_start_s() + scn.motion_end_s());
      EXPECT_NEAR(angle_of(scn.pose(mid).q), 0.5 * std::abs(deg) * kDeg, 1e-12);
    }
  }
}

TEST(SimScenario, TranslationReachesTheCommandedDistanceAndIsCentredOnThePad) {
  const Scenario tx(spec_for(MotionAxis::kTx, 10.0));
  EXPECT_NEAR((tx.pose(tx.duration_s()).p - Eigen::Vector3d(10.0, 0.0, 0.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(angle_of(tx.pose(tx.duration_s()).q), 0.0, 1e-15);
  EXPECT_NEAR(tx.object().offset_mm.x(), -5.0, 1e-12);
  EXPECT_NEAR(tx.object().offset_mm.y(), 0.0, 1e-12);
  const Scenario ty(spec_for(MotionAxis::kTy, -8.0));
  EXPECT_NEAR((ty.pose(ty.duration_s()).p - Eigen::Vector3d(0.0, -8.0, 0.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(ty.object().offset_mm.y(), 4.0, 1e-12);
}

TEST(SimScenario, TwistIsTheDerivativeOfThePoseAndTheProfileIsSmooth) {
  for (MotionAxis axis : {MotionAxis::kRy, MotionAxis::kTx}) {
    const Scenario scn(spec_for(axis, axis == MotionAxis::kRy ? 60.0 : 10.0));
    const double t0 = scn.motion_start_s(), t1 = scn.motion_end_s(), T = t1 - t0;
    EXPECT_NEAR(T, axis == MotionAxis::kRy ? 1.5 : 1.0, 1e-12);  // auto duration
    const double h = 1e-6;
    double peak = 0.0;
    for (int k = 0; k <= 200; ++k) {
      const double t = t0 - 0.1 + (T + 0.2) * k / 200.0;
      const Pose a = scn.pose(t - h), b = scn.pose(t + h);
      const Twist tw = scn.twist(t);
      if (axis == MotionAxis::kRy) {
        const double fd = (angle_of(b.q) - angle_of(a.q)) / (2 * h);
        EXPECT_NEAR(tw.w.y(), fd, 1e-5) << "t=" << t;
        EXPECT_NEAR(tw.w.x(), 0.0, 1e-15);
        peak = std::max(peak, tw.w.norm());
      } else {
        const double fd = (b.p.x() - a.p.x()) / (2 * h);
        EXPECT_NEAR(tw.v.x(), fd, 1e-5) << "t=" << t;
        peak = std::max(peak, tw.v.norm());
      }
    }
    // Minimum-jerk: zero velocity at both ends, peak 15/8 of the mean velocity at mid-motion.
    const double amount = axis == MotionAxis::kRy ? 60.0 * kDeg : 10.0;
    EXPECT_NEAR(peak, 1.875 * amount / T, 1e-9);
    for (double t : {t0, t1}) {
      EXPECT_NEAR(scn.twist(t).w.norm() + scn.twist(t).v.norm(), 0.0, 1e-12);
      // Acceleration also vanishes at the ends: the velocity is flat to second order.
      const Twist near = scn.twist(t + (t == t0 ? 1e-3 : -1e-3));
      EXPECT_LT(near.w.norm() + near.v.norm(), 30.0 * amount * 1e-6 / T / T + 1e-12);
    }
  }
}

TEST(SimScenario, TimelineFramesAndIndentation) {
  ScenarioSpec s = spec_for(MotionAxis::kRz, 30.0);
  const Scenario scn(s);
  EXPECT_NEAR(scn.duration_s(), 0.1 + 0.4 + 0.1 + 1.0 + 0.4, 1e-12);
  EXPECT_EQ(scn.frame_count(), 240);
  EXPECT_EQ(scn.frame_time_ns(0), 0);
  EXPECT_EQ(scn.frame_time_ns(1), 8333333);
  EXPECT_EQ(scn.frame_time_ns(120), 1000000000);
  EXPECT_EQ(scn.phase(0.05), Phase::kApproach);
  EXPECT_EQ(scn.phase(0.3), Phase::kGrasp);
  EXPECT_EQ(scn.phase(0.55), Phase::kSettle);
  EXPECT_EQ(scn.phase(1.0), Phase::kMotion);
  EXPECT_EQ(scn.phase(1.9), Phase::kHold);
  EXPECT_DOUBLE_EQ(scn.indentation_mm(0.0), -s.approach_gap_mm);
  EXPECT_DOUBLE_EQ(scn.indentation_mm(0.5), s.indentation_mm);
  EXPECT_DOUBLE_EQ(scn.indentation_mm(1.9), s.indentation_mm);
  const double mid = scn.indentation_mm(0.3);
  EXPECT_NEAR(mid, 0.5 * (s.indentation_mm - s.approach_gap_mm), 1e-12);
}

TEST(SimScenario, AutoRegimeFollowsTheMagnitude) {
  ScenarioSpec s;
  s.regime = Regime::kAuto;
  for (auto [axis, mag, slide] :
       {std::tuple{MotionAxis::kRx, 3.0, false}, std::tuple{MotionAxis::kRz, 5.0, false},
        std::tuple{MotionAxis::kRy, 30.0, true}, std::tuple{MotionAxis::kTx, 0.6, false},
        std::tuple{MotionAxis::kTy, 10.0, true}}) {
    s.axis = axis;
    s.magnitude = mag;
    EXPECT_EQ(Scenario(s).sliding(), slide) << to_string(axis) << " " << mag;
  }
  s.regime = Regime::kStick;
  EXPECT_FALSE(Scenario(s).sliding());
}

TEST(SimScenario, LoopAndReleaseRepeatTheTimeline) {
  ScenarioSpec s = spec_for(MotionAxis::kRz, 10.0);
  s.release_s = 0.2;
  s.loop = true;
  const Scenario scn(s);
  const double d = scn.duration_s();
  EXPECT_EQ(scn.phase(d - 0.1), Phase::kRelease);
  EXPECT_NEAR(scn.indentation_mm(d - 1e-9), -s.approach_gap_mm, 1e-9);
  EXPECT_NEAR(scn.local_time(d + 0.25), 0.25, 1e-12);
  EXPECT_NEAR(angle_of(scn.pose(d + 0.01).q), 0.0, 1e-15);
}

TEST(SimScenario, ValidationNamesTheField) {
  ScenarioSpec s;
  s.indentation_mm = -1.0;
  EXPECT_NE(validate(s).find("indentation_mm"), std::string::npos);
  s = ScenarioSpec{};
  s.magnitude = 500.0;
  EXPECT_NE(validate(s).find("magnitude"), std::string::npos);
  s = ScenarioSpec{};
  s.object.size_mm = 0.0;
  EXPECT_NE(validate(s).find("size_mm"), std::string::npos);
  EXPECT_EQ(validate(ScenarioSpec{}), "");
}

}  // namespace
}  // namespace tacse3::sim
