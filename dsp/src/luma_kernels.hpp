// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp (private): the per-pixel kernels of frame_to_work_image's two filters, and the
// binomial's row driver, shared by the scalar path (luma.cpp) and the Highway targets
// (luma_simd.cpp). Every step is exact integer arithmetic up to one final rounding, so any
// evaluation order gives the same bits.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>

#include "tacse3/dsp/luma.hpp"

namespace tacse3::dsp::detail {

// kBox: the luma + 2x2 box sum of one output pixel, for the tails of the SIMD rows and the
// single-lane fallback target. Scaling and overflow: four 8-bit samples, sum <= 1020 (uint16).
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

// kBinomial. A sensor row's luma in Q8, with one clamped pixel each side: y[0] = Y(0), y[1 + i] =
// Y(i), y[kSensorWidth + 1] = Y(kSensorWidth - 1).
using LumaRow = std::array<std::uint16_t, kSensorWidth + 2>;
// A sensor row filtered and decimated along x: h[x] = [1 3 3 1] . Y(2x - 1 .. 2x + 2).
using DecimatedRow = std::array<std::uint32_t, kWorkWidth>;

// Scaling and overflow: Q8 luma <= 256 * 255 = 65280 (uint16) in every format: GREY and YUYV
// shift their byte left by 8; RGB888 weights its channels with kLumaWeight* (sum 256).
inline std::uint16_t luma_q8(PixelFormat format, const std::uint8_t* row, int i) noexcept {
  switch (format) {
    case PixelFormat::kRgb888:
      return static_cast<std::uint16_t>(kLumaWeightR * row[3 * i] + kLumaWeightG * row[3 * i + 1] +
                                        kLumaWeightB * row[3 * i + 2]);
    case PixelFormat::kYuyv:
      return static_cast<std::uint16_t>(row[2 * i] << 8);  // Y0 U Y1 V: pixel i's Y is byte 2i
    case PixelFormat::kGrey:
      return static_cast<std::uint16_t>(row[i] << 8);
  }
  return 0;
}

inline void pad_luma_row(LumaRow& y) noexcept {
  y[0] = y[1];
  y[kSensorWidth + 1] = y[kSensorWidth];
}

// Scaling and overflow: 8 * 65280 = 522240 (uint32).
inline std::uint32_t decimate_px(const std::uint16_t* y, int x) noexcept {
  const std::uint16_t* p = y + 2 * x;  // p[0] = Y(2x - 1) through the pad
  return static_cast<std::uint32_t>(p[0]) + 3u * (static_cast<std::uint32_t>(p[1]) + p[2]) + p[3];
}

// Scaling and overflow: [1 3 3 1] of decimated rows <= 64 * 65280 = 4177920 (uint32); / 4096
// rounded half-up once is U8.2 (the 16-weight mean luma * 4), <= 1020.
inline std::uint16_t vertical_px(const std::uint32_t* m1, const std::uint32_t* a,
                                 const std::uint32_t* b, const std::uint32_t* c, int x) noexcept {
  return static_cast<std::uint16_t>((m1[x] + 3u * (a[x] + b[x]) + c[x] + 2048u) >> 12);
}

// Runs the binomial's steps over the frame. Output row y takes sensor rows 2y - 1 .. 2y + 2,
// clamped to the frame; four decimated rows in a ring hold them (2.5 KB of stack).
template <class LumaStep, class DecimateStep, class VerticalStep>
void filter_frame(const std::uint8_t* data, std::size_t stride, std::uint16_t* out,
                  LumaStep luma_step, DecimateStep decimate_step, VerticalStep vertical_step) {
  LumaRow luma;
  std::array<DecimatedRow, 4> ring;  // every element is written before it is read
  const auto slot = [&](int r) { return ring[static_cast<std::size_t>(r & 3)].data(); };
  const auto decimate = [&](int r) {
    luma_step(data + stride * static_cast<std::size_t>(r), luma.data() + 1);
    pad_luma_row(luma);
    decimate_step(luma.data(), slot(r));
  };
  decimate(0);
  for (int y = 0; y < kWorkHeight; ++y) {
    decimate(2 * y + 1);
    if (2 * y + 2 < kSensorHeight) decimate(2 * y + 2);
    vertical_step(slot(std::max(2 * y - 1, 0)), slot(2 * y), slot(2 * y + 1),
                  slot(std::min(2 * y + 2, kSensorHeight - 1)),
                  out + static_cast<std::size_t>(y) * kWorkWidth);
  }
}

// frame_to_work_image on the best SIMD target (luma_simd.cpp); `data` and `stride` as checked
// by check_frame.
void luma_image_simd(PixelFormat format, const std::uint8_t* data, std::size_t stride,
                     std::uint16_t* out) noexcept;
void luma_binomial_simd(PixelFormat format, const std::uint8_t* data, std::size_t stride,
                        std::uint16_t* out) noexcept;

}  // namespace tacse3::dsp::detail
