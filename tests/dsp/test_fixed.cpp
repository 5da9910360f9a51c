// SPDX-License-Identifier: Apache-2.0
// tacse3 tests: saturating Q-format helpers at MAXPOS/MAXNEG and their rounding rule.
#include <gtest/gtest.h>

#include "tacse3/dsp/fixed.hpp"

namespace tacse3::dsp {
namespace {

TEST(Fixed, Sat16ClampsAtBothEnds) {
  EXPECT_EQ(sat16(std::int32_t{32767}), 32767);
  EXPECT_EQ(sat16(std::int32_t{32768}), 32767);
  EXPECT_EQ(sat16(std::int32_t{-32768}), -32768);
  EXPECT_EQ(sat16(std::int32_t{-32769}), -32768);
  EXPECT_EQ(sat16(std::int64_t{1} << 40), 32767);
  EXPECT_EQ(sat16(-(std::int64_t{1} << 40)), -32768);
}

TEST(Fixed, Sat32ClampsAtBothEnds) {
  EXPECT_EQ(sat32(std::int64_t{kQ32MaxPos}), kQ32MaxPos);
  EXPECT_EQ(sat32(std::int64_t{kQ32MaxPos} + 1), kQ32MaxPos);
  EXPECT_EQ(sat32(std::int64_t{kQ32MaxNeg}), kQ32MaxNeg);
  EXPECT_EQ(sat32(std::int64_t{kQ32MaxNeg} - 1), kQ32MaxNeg);
}

TEST(Fixed, AddSubSaturateInsteadOfWrapping) {
  EXPECT_EQ(add_sat16(kQ16MaxPos, 1), kQ16MaxPos);
  EXPECT_EQ(add_sat16(kQ16MaxNeg, -1), kQ16MaxNeg);
  EXPECT_EQ(sub_sat16(kQ16MaxNeg, 1), kQ16MaxNeg);
  EXPECT_EQ(sub_sat16(kQ16MaxPos, -1), kQ16MaxPos);
  EXPECT_EQ(add_sat16(100, -300), -200);
  EXPECT_EQ(add_sat32(kQ32MaxPos, kQ32MaxPos), kQ32MaxPos);
  EXPECT_EQ(add_sat32(kQ32MaxNeg, kQ32MaxNeg), kQ32MaxNeg);
  EXPECT_EQ(sub_sat32(kQ32MaxNeg, 1), kQ32MaxNeg);
  EXPECT_EQ(sub_sat32(kQ32MaxPos, -1), kQ32MaxPos);
  EXPECT_EQ(sub_sat32(5, 7), -2);
}

TEST(Fixed, RoundHalfUpShift) {
  EXPECT_EQ(rshift_round(5, 1), 3);    // 2.5 -> 3
  EXPECT_EQ(rshift_round(-5, 1), -2);  // -2.5 -> -2 (ties go towards +inf)
  EXPECT_EQ(rshift_round(-6, 1), -3);
  EXPECT_EQ(rshift_round(7, 2), 2);    // 1.75 -> 2
  EXPECT_EQ(rshift_round(-7, 2), -2);  // -1.75 -> -2
  EXPECT_EQ(rshift_round(12345, 0), 12345);
}

TEST(Fixed, MulQ15MatchesRealProductWithinHalfLsb) {
  for (int a = -32768; a <= 32767; a += 257) {
    for (int b = -32768; b <= 32767; b += 263) {
      const double exact = (a / 32768.0) * (b / 32768.0);
      const auto got = mul_q15(static_cast<std::int16_t>(a), static_cast<std::int16_t>(b));
      if (exact >= 32767.0 / 32768.0) {
        EXPECT_EQ(got, kQ16MaxPos);
      } else {
        EXPECT_LE(std::abs(got / 32768.0 - exact), 0.5 / 32768.0 + 1e-12) << a << " " << b;
      }
    }
  }
  // The one overflow case: -1 * -1 saturates to MAXPOS.
  EXPECT_EQ(mul_q15(kQ16MaxNeg, kQ16MaxNeg), kQ16MaxPos);
  EXPECT_EQ(mul_q15(kQ16MaxPos, kQ16MaxNeg), -32767);
}

TEST(Fixed, MulShiftSat32) {
  EXPECT_EQ(mul_shift_sat32(3 << 16, 5 << 16, 16), 15 << 16);
  EXPECT_EQ(mul_shift_sat32(kQ32MaxPos, kQ32MaxPos, 0), kQ32MaxPos);
  EXPECT_EQ(mul_shift_sat32(kQ32MaxNeg, kQ32MaxPos, 0), kQ32MaxNeg);
  EXPECT_EQ(mul_shift_sat32(kQ32MaxNeg, kQ32MaxNeg, 31), kQ32MaxPos);  // +1.0 in Q31 saturates
}

TEST(Fixed, ToQConvertsAndSaturates) {
  EXPECT_EQ(to_q32<16>(1.5), 98304);
  EXPECT_EQ(to_q32<16>(-1.5), -98304);
  EXPECT_EQ(to_q32<16>(1e12), kQ32MaxPos);
  EXPECT_EQ(to_q32<16>(-1e12), kQ32MaxNeg);
  EXPECT_EQ(to_q16<15>(1.0), kQ16MaxPos);
  EXPECT_EQ(to_q16<15>(-1.0), kQ16MaxNeg);
  EXPECT_DOUBLE_EQ(from_q<16>(to_q32<16>(0.25)), 0.25);
}

}  // namespace
}  // namespace tacse3::dsp
