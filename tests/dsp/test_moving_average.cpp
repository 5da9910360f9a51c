// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: moving average of twists is the exact mean of the last L inputs.
#include <gtest/gtest.h>

#include <deque>
#include <limits>
#include <random>

#include "tacse3/dsp/moving_average.hpp"

namespace tacse3::dsp {
namespace {

using V6 = Eigen::Matrix<double, 6, 1>;

TEST(MovingAverage, WarmUpAndWindowAreExactOnIntegers) {
  MovingAverage<8> ma(4);
  // Small integers: every partial sum and the division by 1..4 are exact in binary when the
  // mean is a multiple of 1/4; pick samples so that it is.
  const double samples[] = {4, 8, 12, 16, 20, 24, 28};
  const double expect[] = {4, 6, 8, 10, 14, 18, 22};
  for (int i = 0; i < 7; ++i) {
    const V6 m = ma.push(V6::Constant(samples[i]));
    EXPECT_EQ(m, V6::Constant(expect[i])) << i;
    EXPECT_EQ(ma.size(), std::min(i + 1, 4));
  }
}

TEST(MovingAverage, MatchesDirectMeanOverLongRuns) {
  std::mt19937 rng(20);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int L : {1, 2, 5, kMaxMovingAverage}) {
    MovingAverage<> ma(L);
    std::deque<V6> window;
    double worst = 0.0;
    for (int k = 0; k < 5000; ++k) {
      V6 x;
      for (int j = 0; j < 6; ++j) x(j) = n(rng) * (j < 3 ? 1.0 : 1e-3);
      window.push_back(x);
      if (static_cast<int>(window.size()) > L) window.pop_front();
      V6 direct = V6::Zero();
      for (const V6& w : window) direct += w;
      direct /= static_cast<double>(window.size());
      worst = std::max(worst, (ma.push(x) - direct).cwiseAbs().maxCoeff());
    }
    // No running sum: the error does not grow with the run length (a few ulp of the inputs).
    EXPECT_LT(worst, 1e-15) << "L " << L;
  }
}

TEST(MovingAverage, LengthOneIsIdentityAndBadLengthsAreRejected) {
  MovingAverage<4> ma(1);
  const V6 x = (V6() << 1.5, -2.0, 3.25, 0.125, -0.5, 7.0).finished();
  EXPECT_EQ(ma.push(x), x);
  EXPECT_EQ(ma.set_length(0), Status::kBadArgument);
  EXPECT_EQ(ma.set_length(5), Status::kBadArgument);
  EXPECT_EQ(ma.length(), 1);
  EXPECT_EQ(ma.set_length(4), Status::kOk);
  EXPECT_EQ(ma.size(), 0);  // changing the length resets
}

TEST(MovingAverage, NonFiniteSamplesBecomeZeroAndAreCounted) {
  MovingAverage<4> ma(2);
  ma.push(V6::Constant(2.0));
  V6 bad = V6::Constant(1.0);
  bad(3) = std::numeric_limits<double>::quiet_NaN();
  const V6 m = ma.push(bad);
  EXPECT_TRUE(m.allFinite());
  EXPECT_EQ(m, V6::Constant(1.0));  // (2 + 0) / 2
  EXPECT_EQ(ma.rejected(), 1);
  ma.reset();
  EXPECT_EQ(ma.size(), 0);
  EXPECT_EQ(ma.mean(), V6::Zero());
}

}  // namespace
}  // namespace tacse3::dsp
