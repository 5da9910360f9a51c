// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: dsp::LoadRelease, the release rule's relative load rate, against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "tacse3/dsp/load_release.hpp"

namespace tacse3::dsp {
namespace {

constexpr double kDt = 1.0 / 120.0;

LoadRelease configured(double smoothing_s, double release_load_rate) {
  Calibration cal;
  cal.slip_smoothing_s = smoothing_s;
  cal.release_load_rate = release_load_rate;
  LoadRelease r;
  r.configure(cal);
  r.reset();
  return r;
}

TEST(LoadRelease, AHeldLoadAndAContactsFirstFrameReadZero) {
  LoadRelease r = configured(0.04, 4.0);
  EXPECT_EQ(r.update(5.0, false, 0.0, kDt), 0.0);  // first frame: no previous load
  for (int k = 0; k < 10; ++k) EXPECT_EQ(r.update(5.0, true, 5.0, kDt), 0.0);
}

// Unsmoothed, an exponential fall L = L0 e^{−kt} reads (L_{t−1} − L_t) / (L_t Δt) = (e^{kΔt} −
// 1)/Δt.
TEST(LoadRelease, UnsmoothedRateOfAnExponentialFall) {
  LoadRelease r = configured(0.0, 4.0);
  const double k = 6.0;
  double load = 1000.0;
  (void)r.update(load, false, 0.0, kDt);
  for (int i = 0; i < 20; ++i) {
    const double next = load * std::exp(-k * kDt);
    EXPECT_NEAR(r.update(next, true, load, kDt), std::expm1(k * kDt) / kDt, 1e-9);
    load = next;
  }
}

// Smoothed with τ, a load lost at once reads exactly 1/τ: α = Δt/(τ + Δt) of the drop over the
// 1 − α of the load left, per Δt. That is the largest rate the rule can see at a constant frame
// period, which is why validate() refuses release_load_rate ≥ 1/slip_smoothing_s.
TEST(LoadRelease, ALoadLostAtOnceReadsTheInverseSmoothingTime) {
  const double tau = 0.04;
  LoadRelease r = configured(tau, 4.0);
  (void)r.update(2.0, false, 0.0, kDt);
  for (int i = 0; i < 30; ++i) (void)r.update(2.0, true, 2.0, kDt);
  EXPECT_NEAR(r.update(0.0, true, 2.0, kDt), 1.0 / tau, 1e-9);
}

TEST(LoadRelease, UnloadingFastIsAboveTheRateWithTheRuleOn) {
  const LoadRelease on = configured(0.04, 4.0);
  EXPECT_TRUE(on.rule_on());
  EXPECT_FALSE(on.unloading_fast(4.0));
  EXPECT_TRUE(on.unloading_fast(4.5));
  const LoadRelease off = configured(0.04, kReleaseRuleOff);
  EXPECT_FALSE(off.rule_on());
  EXPECT_FALSE(off.unloading_fast(1e9));
}

}  // namespace
}  // namespace tacse3::dsp
