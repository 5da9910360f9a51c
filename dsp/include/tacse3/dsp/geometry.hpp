// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: compile-time frame and grid geometry shared by every pipeline stage.
#pragma once

namespace tacse3::dsp {

// DM-Tac sensor frames (paper Sec. III): 320x240 at 120 Hz.
inline constexpr int kSensorWidth = 320;
inline constexpr int kSensorHeight = 240;

// Working image: luma, 2:1 downsampled (Sec. IV-B, "downsampled block flow"; luma.hpp).
inline constexpr int kWorkScale = 2;
inline constexpr int kWorkWidth = kSensorWidth / kWorkScale;    // 160
inline constexpr int kWorkHeight = kSensorHeight / kWorkScale;  // 120
inline constexpr int kWorkPixels = kWorkWidth * kWorkHeight;

// Flow grid: one displacement sample every kGridStride working pixels.
// Grid point (gx, gy) is centred at working-image coordinate (4 gx + 1.5, 4 gy + 1.5), i.e.
// between pixels, so the grid is symmetric about the image centre. In sensor pixels that is
// (8 gx + 3.5, 8 gy + 3.5); the pad centre (159.5, 119.5) lies midway between grid points
// 19 and 20 (x) and 14 and 15 (y).
inline constexpr int kGridStride = 4;
inline constexpr int kGridWidth = kWorkWidth / kGridStride;    // 40
inline constexpr int kGridHeight = kWorkHeight / kGridStride;  // 30
inline constexpr int kGridCount = kGridWidth * kGridHeight;    // 1200

// Pad centre in sensor pixels (recording format, docs/recording-format.md).
inline constexpr double kPadCentreX = 159.5;
inline constexpr double kPadCentreY = 119.5;

constexpr double grid_work_x(int gx) noexcept {
  return kGridStride * gx + 1.5;
}
constexpr double grid_work_y(int gy) noexcept {
  return kGridStride * gy + 1.5;
}
constexpr double grid_sensor_x(int gx) noexcept {
  return kWorkScale * grid_work_x(gx) + 0.5;
}
constexpr double grid_sensor_y(int gy) noexcept {
  return kWorkScale * grid_work_y(gy) + 0.5;
}

static_assert(kSensorWidth % (kWorkScale * kGridStride) == 0, "grid must tile the frame");
static_assert(kSensorHeight % (kWorkScale * kGridStride) == 0, "grid must tile the frame");

}  // namespace tacse3::dsp
