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

// How the sensor image is brought down to the 160x120 working image (the calibration key
// antialias_filter picks one per sensor; docs/dsp/flow.md).
enum class WorkImageFilter : std::uint8_t {
  // Each working pixel is the sum of its 2x2 block: the sharpest image, fine while the printed
  // pattern has four or more sensor pixels per period.
  kBox,
  // A 4x4 binomial low-pass ([1 3 3 1] along x and y, sensor pixels 2x - 1 .. 2x + 2 clamped to
  // the frame) before the 2:1 decimation. A finer pattern folds into the working image as a
  // moire that moves against the gel, and the flow then tracks the moire: at a 2.3-pixel
  // period the box (cos(pi f)) passes 20 % of the amplitude, the binomial (cos^3) 0.8 %.
  kBinomial,
};

// Converts one sensor frame to the working image (paper Sec. IV-B input stage): luma, then the
// filter, stored as U8.2 (luma * 4, 0..1020) in `out`. YUYV uses only the Y bytes.
//
// Scaling and overflow, kBox:
//  - GREY / YUYV: the four 8-bit luma samples of each 2x2 block are summed exactly
//    (max 4 * 255 = 1020); no rounding, no saturation.
//  - RGB888: the block's channel sums are weighted once,
//      out = (77 * sum R + 150 * sum G + 29 * sum B + 128) >> 8,
//    i.e. the exact 2x2 sum of the unrounded Q8 luma, rounded half-up once (error <= 0.5 LSB of
//    U8.2 against the real-valued sum). The weighted sum is at most 256 * 1020 = 261120 (int32).
//    The result never exceeds 1020, so nothing saturates.
// Scaling and overflow, kBinomial:
//  - Luma in Q8 per sensor pixel: GREY and YUYV are byte << 8; RGB888 is 77 R + 150 G + 29 B.
//    Both are <= 65280 (uint16).
//  - The filter along x sums to <= 8 * 65280 = 522240, along y to <= 4177920 (uint32).
//  - out = (sum + 2048) >> 12, rounded half-up once (error <= 0.5 LSB of U8.2 against the
//    real-valued filter); the result never exceeds 1020, so nothing saturates.
// On any error status `out` is left untouched. Runs on the best SIMD target (simd.hpp).
Status frame_to_work_image(const FrameView& in, WorkImage& out,
                           WorkImageFilter filter = WorkImageFilter::kBox) noexcept;

// The scalar path of frame_to_work_image: the same result, bit for bit (tests, benchmarks).
Status frame_to_work_image_scalar(const FrameView& in, WorkImage& out,
                                  WorkImageFilter filter = WorkImageFilter::kBox) noexcept;

}  // namespace tacse3::dsp
