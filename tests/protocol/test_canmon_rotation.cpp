// SPDX-License-Identifier: Apache-2.0
// tacse3-canmon: the pose quaternion shown as an angle and axis in degrees.
#include <gtest/gtest.h>

#include <cmath>

#include "output.hpp"

namespace {

using tacse3::canmon::angle_axis_deg;
namespace tp = tacse3::protocol;

tp::Quaternion about(double deg, double x, double y, double z) {
  const double h = deg * M_PI / 360.0;
  const double n = std::sqrt(x * x + y * y + z * z);
  return {std::cos(h), std::sin(h) * x / n, std::sin(h) * y / n, std::sin(h) * z / n};
}

TEST(CanmonRotation, ThirtyDegreesAboutX) {
  const auto r = angle_axis_deg(about(30.0, 1, 0, 0));
  EXPECT_NEAR(r.angle_deg, 30.0, 1e-9);
  EXPECT_NEAR(r.axis[0], 1.0, 1e-12);
  EXPECT_NEAR(r.axis[1], 0.0, 1e-12);
  EXPECT_NEAR(r.axis[2], 0.0, 1e-12);
}

TEST(CanmonRotation, NegatedQuaternionIsTheSameRotation) {
  tp::Quaternion q = about(120.0, 0, 1, 1);
  q = {-q.w, -q.x, -q.y, -q.z};
  const auto r = angle_axis_deg(q);
  EXPECT_NEAR(r.angle_deg, 120.0, 1e-9);
  EXPECT_NEAR(r.axis[1], std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(r.axis[2], std::sqrt(0.5), 1e-12);
}

TEST(CanmonRotation, BeyondHalfATurnIsTheShorterWayRound) {
  // 200 deg about +z is 160 deg about -z.
  const auto r = angle_axis_deg(about(200.0, 0, 0, 1));
  EXPECT_NEAR(r.angle_deg, 160.0, 1e-9);
  EXPECT_NEAR(r.axis[2], -1.0, 1e-12);
}

TEST(CanmonRotation, DecodedQuaternionIsNormalised) {
  // A quantised, slightly non-unit quaternion (LSB 0.00025): 90 deg about z, scaled by 1.001.
  const auto r = angle_axis_deg({0.70781, 0.0, 0.0, 0.70781});
  EXPECT_NEAR(r.angle_deg, 90.0, 1e-9);
  EXPECT_NEAR(r.axis[2], 1.0, 1e-12);
}

TEST(CanmonRotation, IdentityHasNoAxis) {
  const auto r = angle_axis_deg({1.0, 0.0, 0.0, 0.0});
  EXPECT_EQ(r.angle_deg, 0.0);
  EXPECT_EQ(r.axis[0], 0.0);
  EXPECT_EQ(r.axis[1], 0.0);
  EXPECT_EQ(r.axis[2], 0.0);
}

}  // namespace
