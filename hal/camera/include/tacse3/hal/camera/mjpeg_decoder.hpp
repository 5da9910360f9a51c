// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: MJPEG frame -> GREY/RGB888 FrameView with libjpeg-turbo, into caller-owned memory.
#pragma once

#include <cstddef>
#include <cstdint>

#include "tacse3/dsp/types.hpp"
#include "tacse3/hal/camera.hpp"

namespace tacse3::hal {

// Decodes one JPEG per call into a buffer the caller allocated once (output_bytes() long).
// GREY output decodes the luma component only (no chroma upsampling or colour conversion).
// Built without libturbojpeg (TACSE3_HAL_HAS_TURBOJPEG == 0), init() returns kUnavailable.
class MjpegDecoder {
 public:
  MjpegDecoder() = default;
  ~MjpegDecoder();
  MjpegDecoder(const MjpegDecoder&) = delete;
  MjpegDecoder& operator=(const MjpegDecoder&) = delete;

  static bool available() noexcept;

  // Frames must be width x height; output is kGrey or kRgb888, tightly packed.
  CameraStatus init(int width, int height, dsp::PixelFormat output) noexcept;
  std::size_t output_bytes() const noexcept;
  int output_stride() const noexcept;
  dsp::PixelFormat output_format() const noexcept { return output_; }

  // Decodes `jpeg` into dst and points `out` at it. A JPEG of another size, or one libjpeg
  // cannot decode, is kCorruptFrame. libjpeg warnings (e.g. trailing garbage after the EOI marker,
  // common with UVC) still produce a whole image: the call succeeds and warnings() counts them.
  CameraStatus decode(const std::uint8_t* jpeg, std::size_t jpeg_bytes, std::uint8_t* dst,
                      std::size_t dst_bytes, dsp::FrameView& out) noexcept;

  std::uint64_t warnings() const noexcept { return warnings_; }

 private:
  void* handle_ = nullptr;  // tjhandle
  int width_ = 0;
  int height_ = 0;
  dsp::PixelFormat output_ = dsp::PixelFormat::kGrey;
  std::uint64_t warnings_ = 0;
};

}  // namespace tacse3::hal
