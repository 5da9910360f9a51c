// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: double-precision luma with the 2x2 box or the [1 3 3 1] filter and 2:1
// decimation.
#include "tacse3/dsp_ref/luma_ref.hpp"

#include <cstddef>

#include "tacse3/dsp/luma.hpp"

namespace tacse3::dsp_ref {

double luma_ref(double r, double g, double b) {
  return (dsp::kLumaWeightR * r + dsp::kLumaWeightG * g + dsp::kLumaWeightB * b) / 256.0;
}

std::vector<double> frame_to_work_image_ref(const dsp::FrameView& in, dsp::WorkImageFilter filter) {
  if (dsp::check_frame(in) != dsp::Status::kOk) return {};
  const std::size_t stride = static_cast<std::size_t>(
      in.stride_bytes == 0 ? dsp::packed_row_bytes(in.format) : in.stride_bytes);
  auto luma_at = [&](int x, int y) -> double {
    const std::uint8_t* row = in.data + stride * static_cast<std::size_t>(y);
    switch (in.format) {
      case dsp::PixelFormat::kRgb888:
        return luma_ref(row[3 * x], row[3 * x + 1], row[3 * x + 2]);
      case dsp::PixelFormat::kYuyv:
        return row[2 * x];  // Y0 U Y1 V: pixel x's luma is byte 2x
      case dsp::PixelFormat::kGrey:
        return row[x];
    }
    return 0.0;
  };
  // The 16 weights of the 4x4 binomial over sensor pixels 2x - 1 .. 2x + 2 (clamped to the
  // frame), normalised to the U8.2 scale: sum 64, divided by 16.
  constexpr double kW[4] = {1.0, 3.0, 3.0, 1.0};
  const auto clamp = [](int v, int n) { return v < 0 ? 0 : (v >= n ? n - 1 : v); };
  std::vector<double> out(static_cast<std::size_t>(dsp::kWorkPixels));
  if (filter == dsp::WorkImageFilter::kBox) {
    for (int y = 0; y < dsp::kWorkHeight; ++y) {
      for (int x = 0; x < dsp::kWorkWidth; ++x) {
        out[static_cast<std::size_t>(y * dsp::kWorkWidth + x)] =
            luma_at(2 * x, 2 * y) + luma_at(2 * x + 1, 2 * y) + luma_at(2 * x, 2 * y + 1) +
            luma_at(2 * x + 1, 2 * y + 1);
      }
    }
    return out;
  }
  for (int y = 0; y < dsp::kWorkHeight; ++y) {
    for (int x = 0; x < dsp::kWorkWidth; ++x) {
      double s = 0.0;
      for (int j = 0; j < 4; ++j) {
        for (int i = 0; i < 4; ++i) {
          s += kW[i] * kW[j] *
               luma_at(clamp(2 * x - 1 + i, dsp::kSensorWidth),
                       clamp(2 * y - 1 + j, dsp::kSensorHeight));
        }
      }
      out[static_cast<std::size_t>(y * dsp::kWorkWidth + x)] = s / 16.0;
    }
  }
  return out;
}

}  // namespace tacse3::dsp_ref
