// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: fixed-size containers and status codes passed between pipeline stages.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "tacse3/dsp/geometry.hpp"

namespace tacse3::dsp {

// Every fallible dsp call returns a Status; dsp code throws nothing (built with -fno-exceptions
// semantics in mind) and never aborts on bad input.
enum class Status : std::uint8_t {
  kOk = 0,
  kNullFrame,       // data pointer is null
  kBadFrameSize,    // width/height/stride/byte count do not match 320x240 in the given format
  kBadPixelFormat,  // unknown PixelFormat value
  kBadCalibration,  // a calibration field is NaN, infinite or out of its documented range
  kBadArgument,     // any other argument outside its documented range
};

constexpr const char* to_string(Status s) noexcept {
  switch (s) {
    case Status::kOk:
      return "ok";
    case Status::kNullFrame:
      return "null frame data";
    case Status::kBadFrameSize:
      return "frame size does not match 320x240 in the given pixel format";
    case Status::kBadPixelFormat:
      return "unsupported pixel format";
    case Status::kBadCalibration:
      return "calibration field out of range or not finite";
    case Status::kBadArgument:
      return "argument out of range";
  }
  return "unknown status";
}

enum class PixelFormat : std::uint8_t {
  kRgb888 = 0,  // 3 bytes per pixel, R G B
  kYuyv = 1,    // 4 bytes per 2 pixels, Y0 U Y1 V (V4L2_PIX_FMT_YUYV)
  kGrey = 2,    // 1 byte per pixel
};

// A borrowed view of one camera frame. The pipeline never keeps the pointer past the call.
struct FrameView {
  const std::uint8_t* data = nullptr;
  std::size_t size_bytes = 0;  // bytes available at data
  int width = 0;
  int height = 0;
  int stride_bytes = 0;  // bytes per row; 0 means tightly packed
  PixelFormat format = PixelFormat::kGrey;
};

// Working image: luma after the 2:1 downsample (luma.hpp), format U8.2 (luma * 4, range
// 0..1020).
struct WorkImage {
  alignas(16) std::array<std::uint16_t, kWorkPixels> px{};
  std::uint16_t& at(int x, int y) noexcept {
    return px[static_cast<std::size_t>(y * kWorkWidth + x)];
  }
  std::uint16_t at(int x, int y) const noexcept {
    return px[static_cast<std::size_t>(y * kWorkWidth + x)];
  }
};

// A scalar sample per flow-grid point, row-major (gy * kGridWidth + gx).
template <typename T>
struct GridArray {
  alignas(16) std::array<T, kGridCount> v{};
  T& operator()(int gx, int gy) noexcept {
    return v[static_cast<std::size_t>(gy * kGridWidth + gx)];
  }
  const T& operator()(int gx, int gy) const noexcept {
    return v[static_cast<std::size_t>(gy * kGridWidth + gx)];
  }
  void fill(T value) noexcept { v.fill(value); }
};

// Fixed-point format of every grid vector/scalar field exchanged between stages: Q16
// (int32, LSB 2^-16). Displacements are in working-image pixels; see docs/dsp.md.
inline constexpr int kFieldFrac = 16;

struct VectorField {
  GridArray<std::int32_t> x;
  GridArray<std::int32_t> y;
};
using ScalarField = GridArray<std::int32_t>;
using GridMask = GridArray<std::uint8_t>;  // 0 or 1

}  // namespace tacse3::dsp
