// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: dsp::TwistConfidence on analytic inputs: each term moves the confidence as its
// formula says, the result stays in [0, 1], the stick term's catch-up counts frames.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "tacse3/dsp/confidence.hpp"

namespace tacse3::dsp {
namespace {

constexpr double kDt = 1.0 / 120.0;
constexpr double kRest = 0.05e-3;
constexpr double kFootprint = 1.0;

ConfidenceConfig config() {
  ConfidenceConfig c;
  c.rest_speed_m_s = kRest;
  c.footprint_cells = kFootprint;
  c.catchup_frames = 3;
  c.smoothing_s = 0.04;
  return c;
}

// Cells of a disc whose radius is `r` footprints: the area term is (1 − 1/r)².
int disc_cells(double r) {
  return static_cast<int>(std::lround(std::numbers::pi * r * r * kFootprint * kFootprint));
}
double area_of(int cells) {
  const double inner = 1.0 - kFootprint / std::sqrt(cells / std::numbers::pi);
  return inner * inner;
}

// Two pads, full rank, the expected conditioning, no residual, no disagreement.
FitQuality ideal() {
  FitQuality q;
  q.pads = 2;
  q.rank = 3;
  q.rcond = q.rcond_expected = 0.03;
  q.min_points = disc_cells(10.0);
  return q;
}

TwistConfidence::Terms once(const FitQuality& q, bool slipping = false, bool onset = false) {
  TwistConfidence c;
  c.configure(config());
  return c.update(q, slipping, onset, kDt);
}

TEST(TwistConfidence, IdealFitIsTheAreaTermAlone) {
  const auto t = once(ideal());
  EXPECT_DOUBLE_EQ(t.observed, 1.0);
  EXPECT_DOUBLE_EQ(t.conditioning, 1.0);
  EXPECT_DOUBLE_EQ(t.residual, 1.0);
  EXPECT_DOUBLE_EQ(t.agreement, 1.0);
  EXPECT_DOUBLE_EQ(t.stick, 1.0);
  EXPECT_NEAR(t.area, area_of(disc_cells(10.0)), 1e-12);
  EXPECT_NEAR(t.area, 0.81, 0.01);  // (1 − 1/10)²
  EXPECT_DOUBLE_EQ(t.value, t.area);
}

TEST(TwistConfidence, NoPadIsZero) {
  const auto t = once(FitQuality{});
  EXPECT_EQ(t.value, 0.0);
}

TEST(TwistConfidence, OnePadObservesOneDirectionInThree) {
  FitQuality q = ideal();
  q.pads = 1;
  q.rank = 1;
  q.rcond = q.rcond_expected = 1.0;
  const auto t = once(q);
  EXPECT_NEAR(t.observed, 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(t.value, t.area / 3.0, 1e-15);
  EXPECT_LT(t.value, kConfidenceThreshold);
}

TEST(TwistConfidence, ConditioningIsTheRatioToTheExpectedOne) {
  FitQuality q = ideal();
  q.rcond = q.rcond_expected / 4.0;
  EXPECT_NEAR(once(q).conditioning, 0.25, 1e-15);
  q.rcond = q.rcond_expected * 3.0;  // better than a flat patch: capped
  EXPECT_DOUBLE_EQ(once(q).conditioning, 1.0);
  q.rcond_expected = 0.0;  // no lever between the pads: nothing to compare with
  EXPECT_EQ(once(q).conditioning, 0.0);
}

TEST(TwistConfidence, ResidualHalvesAtTheRestSpeed) {
  FitQuality q = ideal();
  for (const double k : {0.1, 0.5, 1.0, 2.0, 10.0}) {
    q.residual_speed_m_s = k * kRest;
    const auto t = once(q);
    EXPECT_NEAR(t.residual, 1.0 / (1.0 + k * k), 1e-12) << k;
    EXPECT_NEAR(t.value, t.area / (1.0 + k * k), 1e-12) << k;
  }
  q.residual_speed_m_s = std::numeric_limits<double>::infinity();  // too few points
  EXPECT_EQ(once(q).value, 0.0);
}

TEST(TwistConfidence, DisagreementIsSmoothedWithTheDetectorsTimeConstant) {
  TwistConfidence c;
  c.configure(config());
  FitQuality q = ideal();
  q.disagreement_m_s = -kRest;  // the first frame with two pads starts the average
  EXPECT_NEAR(c.update(q, false, false, kDt).agreement, 0.5, 1e-12);
  q.disagreement_m_s = 0.0;  // one step of the exponential average towards 0
  const double d = kRest * std::exp(-kDt / 0.04);
  EXPECT_NEAR(c.update(q, false, false, kDt).agreement, kRest * kRest / (kRest * kRest + d * d),
              1e-12);
  // A frame with one pad forgets it: the next two-pad frame starts again.
  FitQuality one = q;
  one.pads = 1;
  one.rank = 1;
  EXPECT_DOUBLE_EQ(c.update(one, false, false, kDt).agreement, 1.0);
  q.disagreement_m_s = 3.0 * kRest;
  EXPECT_NEAR(c.update(q, false, false, kDt).agreement, 0.1, 1e-12);
}

TEST(TwistConfidence, AreaFollowsTheInteriorOfTheDisc) {
  FitQuality q = ideal();
  for (const double r : {1.5, 2.0, 4.0, 20.0}) {
    q.min_points = disc_cells(r);
    EXPECT_NEAR(once(q).area, area_of(q.min_points), 1e-12) << r;
  }
  q.min_points = disc_cells(2.0);
  EXPECT_NEAR(once(q).area, 0.25, 0.01);
  q.min_points = 3;  // radius below one footprint: no interior
  EXPECT_EQ(once(q).area, 0.0);
}

TEST(TwistConfidence, SlidingAndTheCatchUpAfterAnOnsetAreZero) {
  EXPECT_EQ(once(ideal(), true).value, 0.0);
  TwistConfidence c;
  c.configure(config());
  EXPECT_GT(c.update(ideal(), false, false, kDt).value, kConfidenceThreshold);
  // The onset frame and catchup_frames (3) after it read 0, then the stick term is back.
  EXPECT_EQ(c.update(ideal(), false, true, kDt).stick, 0.0);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(c.update(ideal(), false, false, kDt).stick, 0.0) << k;
  EXPECT_EQ(c.update(ideal(), false, false, kDt).stick, 1.0);
  // reset() drops a pending catch-up.
  (void)c.update(ideal(), false, true, kDt);
  c.reset();
  EXPECT_EQ(c.update(ideal(), false, false, kDt).stick, 1.0);
}

TEST(TwistConfidence, StaysInTheUnitIntervalOnAnyInput) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  const double odd[] = {std::numeric_limits<double>::quiet_NaN(),
                        std::numeric_limits<double>::infinity(), -1.0, 0.0, 1e300};
  TwistConfidence c;
  c.configure(config());
  for (int i = 0; i < 2000; ++i) {
    FitQuality q;
    q.pads = static_cast<int>(rng() % 4) - 1;
    q.rank = static_cast<int>(rng() % 5) - 1;
    q.rcond = i % 7 == 0 ? odd[i % 5] : u(rng);
    q.rcond_expected = i % 11 == 0 ? odd[(i / 11) % 5] : u(rng);
    q.residual_speed_m_s = i % 13 == 0 ? odd[(i / 13) % 5] : u(rng) * 1e-4;
    q.disagreement_m_s = i % 17 == 0 ? odd[(i / 17) % 5] : u(rng) * 1e-4;
    q.min_points = static_cast<int>(rng() % 2000) - 10;
    const auto t = c.update(q, rng() % 5 == 0, rng() % 9 == 0, kDt);
    for (const double v :
         {t.observed, t.conditioning, t.residual, t.agreement, t.area, t.stick, t.value}) {
      ASSERT_GE(v, 0.0) << i;
      ASSERT_LE(v, 1.0) << i;
    }
  }
}

}  // namespace
}  // namespace tacse3::dsp
