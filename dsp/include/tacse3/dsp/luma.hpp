// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: camera frame (RGB888 / YUYV / GREY, 320x240) to the U8.2 working image.
#pragma once

#include <cstddef>
#include <cstdint>

#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Integer BT.601 luma weights in Q8 (sum 256): Y = (77 R + 150 G + 29 B) / 256.
// They differ from the exact 0.299 / 0.587 / 0.114 by at most 0.0018.
inline constexpr int kLumaWeightR = 77;
inline constexpr int kLumaWeightG = 150;
inline constexpr int kLumaWeightB = 29;
static_assert(kLumaWeightR + kLumaWeightG + kLumaWeightB == 256, "luma weights must sum to 1.0");

// Bytes per row of a tightly packed 320-pixel row in `format`, or 0 for an unknown format.
constexpr int packed_row_bytes(PixelFormat format) noexcept {
  switch (format) {
    case PixelFormat::kRgb888:
      return 3 * kSensorWidth;
    case PixelFormat::kYuyv:
      return 2 * kSensorWidth;
    case PixelFormat::kGrey:
      return kSensorWidth;
  }
  return 0;
}

// Checks a frame view without touching pixel data: null data -> kNullFrame, unknown format ->
// kBadPixelFormat, width/height other than 320x240, stride (if non-zero) below one packed row,
// or size_bytes below (height - 1) * stride + row bytes -> kBadFrameSize.
Status check_frame(const FrameView& in) noexcept;

// Converts one sensor frame to the working image (paper Sec. IV-B input stage): luma, then a
// 2x2 box sum, stored as U8.2 (luma * 4, 0..1020) in `out`.
//
// Scaling and overflow:
//  - GREY / YUYV: the four 8-bit luma samples of each 2x2 block are summed exactly
//    (max 4 * 255 = 1020); no rounding, no saturation.
//  - RGB888: the block's channel sums are weighted once,
//      out = (77 * sum R + 150 * sum G + 29 * sum B + 128) >> 8,
//    i.e. the exact 2x2 sum of the unrounded Q8 luma, rounded half-up once (error <= 0.5 LSB of
//    U8.2 against the real-valued sum). The weighted sum is at most 256 * 1020 = 261120 (int32).
//    The result never exceeds 1020, so nothing saturates.
//  - YUYV uses only the Y bytes; chroma is ignored.
// On any error status `out` is left untouched. Runs on the best SIMD target (simd.hpp).
Status frame_to_work_image(const FrameView& in, WorkImage& out) noexcept;

// The scalar path of frame_to_work_image: the same result, bit for bit (tests, benchmarks).
Status frame_to_work_image_scalar(const FrameView& in, WorkImage& out) noexcept;

}  // namespace tacse3::dsp
