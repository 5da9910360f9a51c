// SPDX-License-Identifier: Apache-2.0
// The velocity proxy's rate that persists at rest, told from the truth's orientations.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "tacse3/tools/rest_persistence.hpp"

namespace tt = tacse3::tools;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kRate = 120.0;

// A 20° minimum-jerk turn about x over 1 s, 0.3 s still before it and 1 s after it, sampled at
// 120 Hz; `noise_deg` of pose noise per frame about random axes (a robot log's).
struct Turn {
  std::vector<Eigen::Quaterniond> truth;
  std::vector<double> rate;  // the true rate, rad/s
};

Turn turn(double noise_deg) {
  Turn t;
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, noise_deg * kDeg);
  for (int i = 0; i < static_cast<int>(2.3 * kRate); ++i) {
    const double s = std::clamp((i / kRate - 0.3) / 1.0, 0.0, 1.0);
    const double shape = 10 * std::pow(s, 3) - 15 * std::pow(s, 4) + 6 * std::pow(s, 5);
    const double dshape = 30 * s * s - 60 * std::pow(s, 3) + 30 * std::pow(s, 4);
    const Eigen::Vector3d n(g(rng), g(rng), g(rng));
    t.truth.push_back(
        Eigen::Quaterniond(Eigen::AngleAxisd(20 * kDeg * shape, Eigen::Vector3d::UnitX())) *
        Eigen::Quaterniond(Eigen::AngleAxisd(n.norm(), n.normalized())));
    t.rate.push_back(20 * kDeg * dshape);
  }
  return t;
}

}  // namespace

TEST(RestPersistence, ASlideRelaxesAndAStickStays) {
  const Turn t = turn(0.0);
  std::vector<Eigen::Vector3d> slide, stick;
  double angle = 0.0;
  for (const double w : t.rate) {
    angle += w / kRate;
    slide.emplace_back(w, 0.0, 0.0);      // reads the rate: nothing at rest
    stick.emplace_back(angle, 0.0, 0.0);  // reads the displacement: all of it stays
  }
  // The rest starts 0.1 s after the turn is within 2 % of its end, where its rate is nearly 0.
  EXPECT_LT(tt::rest_persistence(slide, t.truth), 1e-3);
  // The displacement at rest is 20°; while moving it averages about half of that.
  const double p = tt::rest_persistence(stick, t.truth);
  EXPECT_GT(p, 1.8);
  EXPECT_LT(p, 2.2);
}

TEST(RestPersistence, ARobotLogsPoseNoiseStillShowsTheRest) {
  // 0.01° per frame: differentiated at 120 Hz that is about 2°/s, more than 2 % of this turn's
  // peak rate (37.5°/s), so the rest is told from the orientations.
  const Turn t = turn(0.01);
  std::vector<Eigen::Vector3d> slide;
  for (const double w : t.rate) slide.emplace_back(w + (w == 0.0 ? 0.001 : 0.0), 0.0, 0.0);
  const double p = tt::rest_persistence(slide, t.truth);
  ASSERT_GE(p, 0.0);
  EXPECT_LT(p, 0.01);
}

TEST(RestPersistence, NoMotionOrNoRestGivesMinusOne) {
  const std::vector<Eigen::Quaterniond> still(100, Eigen::Quaterniond::Identity());
  const std::vector<Eigen::Vector3d> est(100, Eigen::Vector3d(0.1, 0.0, 0.0));
  EXPECT_EQ(tt::rest_persistence(est, still), -1.0);
  // A recording that ends 0.7 s into the turn: no frame at rest.
  Turn t = turn(0.0);
  t.truth.resize(static_cast<std::size_t>(1.0 * kRate));
  const std::vector<Eigen::Vector3d> e(t.truth.size(), Eigen::Vector3d(0.1, 0.0, 0.0));
  EXPECT_EQ(tt::rest_persistence(e, t.truth), -1.0);
}
