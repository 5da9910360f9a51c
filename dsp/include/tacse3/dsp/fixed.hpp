// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: fixed-point (Q format) arithmetic helpers with explicit saturation and rounding.
#pragma once

#include <cstdint>
#include <limits>

namespace tacse3::dsp {

// Conventions used by every Q-format helper in this file (see docs/dsp/flow.md, "Scaling and
// overflow"):
//  - A value in format QF of an integer type T represents  raw * 2^-F.
//  - Rounding is round-half-up (towards +inf): add 2^(s-1) before an arithmetic right shift by s.
//    This is what CMSIS-DSP calls "rounding"; it is cheap and has no sign branch. Its bias is
//    +2^-(s+1) LSB only on exact ties, which are rare for sensor data.
//  - Saturation clamps to [MAXNEG, MAXPOS] of the destination type. No helper ever wraps.
//  - Right shifts of negative numbers are arithmetic (guaranteed by C++20).

inline constexpr std::int16_t kQ16MaxPos = std::numeric_limits<std::int16_t>::max();
inline constexpr std::int16_t kQ16MaxNeg = std::numeric_limits<std::int16_t>::min();
inline constexpr std::int32_t kQ32MaxPos = std::numeric_limits<std::int32_t>::max();
inline constexpr std::int32_t kQ32MaxNeg = std::numeric_limits<std::int32_t>::min();

// Saturate a wider integer into int16.
constexpr std::int16_t sat16(std::int32_t x) noexcept {
  return x > kQ16MaxPos ? kQ16MaxPos : (x < kQ16MaxNeg ? kQ16MaxNeg : static_cast<std::int16_t>(x));
}
constexpr std::int16_t sat16(std::int64_t x) noexcept {
  return x > kQ16MaxPos ? kQ16MaxPos : (x < kQ16MaxNeg ? kQ16MaxNeg : static_cast<std::int16_t>(x));
}

// Saturate an int64 into int32.
constexpr std::int32_t sat32(std::int64_t x) noexcept {
  return x > kQ32MaxPos ? kQ32MaxPos : (x < kQ32MaxNeg ? kQ32MaxNeg : static_cast<std::int32_t>(x));
}

// Saturating add/sub. The sum is formed in the next wider type, so it cannot overflow before
// the clamp.
constexpr std::int16_t add_sat16(std::int16_t a, std::int16_t b) noexcept {
  return sat16(static_cast<std::int32_t>(a) + b);
}
constexpr std::int16_t sub_sat16(std::int16_t a, std::int16_t b) noexcept {
  return sat16(static_cast<std::int32_t>(a) - b);
}
constexpr std::int32_t add_sat32(std::int32_t a, std::int32_t b) noexcept {
  return sat32(static_cast<std::int64_t>(a) + b);
}
constexpr std::int32_t sub_sat32(std::int32_t a, std::int32_t b) noexcept {
  return sat32(static_cast<std::int64_t>(a) - b);
}

// Arithmetic right shift by s >= 0 with round-half-up. s == 0 returns x unchanged.
// Overflow: none for |x| < 2^62; the caller saturates the result to its destination type.
constexpr std::int64_t rshift_round(std::int64_t x, int s) noexcept {
  return s <= 0 ? x : ((x + (std::int64_t{1} << (s - 1))) >> s);
}

// Multiply two Q values and shift back by `shift` bits with rounding, saturating to int32.
// For QA * QB -> QC use shift = A + B - C. The product is exact in int64 (|a*b| < 2^62).
constexpr std::int32_t mul_shift_sat32(std::int32_t a, std::int32_t b, int shift) noexcept {
  return sat32(rshift_round(static_cast<std::int64_t>(a) * b, shift));
}

// Q15 x Q15 -> Q15 with rounding and saturation. The single overflow case,
// (-1.0) * (-1.0) = +1.0, saturates to MAXPOS (0x7FFF), as in CMSIS-DSP's arm_mult_q15.
constexpr std::int16_t mul_q15(std::int16_t a, std::int16_t b) noexcept {
  return sat16(static_cast<std::int32_t>(rshift_round(static_cast<std::int32_t>(a) * b, 15)));
}

// Convert a real constant to Q format with rounding to nearest and saturation. Intended for
// constants computed once at initialisation (calibration gains, kernel taps), never per pixel.
template <int F>
constexpr std::int32_t to_q32(double v) noexcept {
  const double scaled = v * static_cast<double>(std::int64_t{1} << F);
  if (!(scaled == scaled)) return 0;  // NaN maps to 0; callers validate inputs beforehand.
  if (scaled >= 2147483647.0) return kQ32MaxPos;
  if (scaled <= -2147483648.0) return kQ32MaxNeg;
  return static_cast<std::int32_t>(scaled >= 0.0 ? scaled + 0.5 : scaled - 0.5);
}
template <int F>
constexpr std::int16_t to_q16(double v) noexcept {
  return sat16(to_q32<F>(v));
}

// Convert a Q value back to double (tests, the scalar float stages, diagnostics).
template <int F>
constexpr double from_q(std::int64_t raw) noexcept {
  return static_cast<double>(raw) / static_cast<double>(std::int64_t{1} << F);
}

}  // namespace tacse3::dsp
