// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp (private): the luma + 2x2 box sum of one output pixel, for the tails of the SIMD rows
// and the single-lane fallback target (luma_simd.cpp). The same integer expressions as the scalar
// rows in luma.cpp (integer sums are exact in any order).
#pragma once

#include <cstddef>
#include <cstdint>

#include "tacse3/dsp/luma.hpp"

namespace tacse3::dsp::detail {

// Scaling and overflow: four 8-bit samples, sum <= 1020 (fits uint16).
inline std::uint16_t grey_px(const std::uint8_t* r0, const std::uint8_t* r1, int x) noexcept {
  return static_cast<std::uint16_t>(r0[2 * x] + r0[2 * x + 1] + r1[2 * x] + r1[2 * x + 1]);
}

// YUYV macropixel x = Y0 U Y1 V: its two luma bytes are one 2-pixel column pair (chroma unused).
inline std::uint16_t yuyv_px(const std::uint8_t* r0, const std::uint8_t* r1, int x) noexcept {
  return static_cast<std::uint16_t>(r0[4 * x] + r0[4 * x + 2] + r1[4 * x] + r1[4 * x + 2]);
}

// Scaling and overflow: channel sums of the 2x2 block <= 1020; the weighted sum
// <= 256 * 1020 = 261120 (int32); rounded half-up once; the result <= 1020.
inline std::uint16_t rgb_px(const std::uint8_t* r0, const std::uint8_t* r1, int x) noexcept {
  const std::uint8_t* a = r0 + 6 * x;
  const std::uint8_t* b = r1 + 6 * x;
  const std::int32_t r = a[0] + a[3] + b[0] + b[3];
  const std::int32_t g = a[1] + a[4] + b[1] + b[4];
  const std::int32_t bl = a[2] + a[5] + b[2] + b[5];
  const std::int32_t y = kLumaWeightR * r + kLumaWeightG * g + kLumaWeightB * bl;
  return static_cast<std::uint16_t>((y + 128) >> 8);
}

// frame_to_work_image's rows on the best SIMD target (luma_simd.cpp); `data` and `stride` as
// checked by check_frame.
void luma_image_simd(PixelFormat format, const std::uint8_t* data, std::size_t stride,
                     std::uint16_t* out) noexcept;

}  // namespace tacse3::dsp::detail
