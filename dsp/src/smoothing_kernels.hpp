// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp (private): the SIMD sums of FlowSmoother (smoothing_simd.cpp).
#pragma once

#include <cstdint>

#include "tacse3/dsp/smoothing.hpp"

namespace tacse3::dsp::detail {

// Buffers and outputs of smoothing_sums_simd. The padded inputs hold the masked field (value or 0,
// weight 1 or 0) at column kMaxRadius + x of a row of kPadWidth; their margins stay 0. The column
// buffers hold the row sums at row kMaxRadius + y of kGridWidth; their margin rows stay 0.
struct SmoothingSums {
  static constexpr int kPad = FlowSmoother::kMaxRadius;
  static constexpr int kPadWidth = kGridWidth + 2 * kPad;
  static constexpr int kPadHeight = kGridHeight + 2 * kPad;
  const std::int32_t* taps = nullptr;  // taps[|i|], Q15, i <= radius
  int radius = 0;
  bool weights = false;                // false: every point valid, the weight sums are skipped
  const std::int32_t* in_x = nullptr;  // kGridHeight x kPadWidth
  const std::int32_t* in_y = nullptr;
  const std::int32_t* in_w = nullptr;
  std::int32_t* hi_x = nullptr;  // kPadHeight x kGridWidth: row sum >> 16
  std::int32_t* lo_x = nullptr;  //                          row sum & 0xFFFF
  std::int32_t* hi_y = nullptr;
  std::int32_t* lo_y = nullptr;
  std::int32_t* row_w = nullptr;
  std::int64_t* num_x = nullptr;  // kGridCount: the column pass numerators
  std::int64_t* num_y = nullptr;
  std::int32_t* num_w = nullptr;  // kGridCount: the weights (if `weights`)
};

// The normalised convolution's numerators and weights for every grid point, equal to the scalar
// row_pass + column_pass of smoothing.cpp.
void smoothing_sums_simd(const SmoothingSums& s) noexcept;

}  // namespace tacse3::dsp::detail
