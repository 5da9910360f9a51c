// SPDX-License-Identifier: Apache-2.0
// tacse3 hal: MJPEG frame -> GREY/RGB888 FrameView with libjpeg-turbo, into caller-owned memory.
#include "tacse3/hal/camera/mjpeg_decoder.hpp"

#include "tacse3/hal/camera/formats.hpp"

#if TACSE3_HAL_HAS_TURBOJPEG
#include <turbojpeg.h>
#endif

namespace tacse3::hal {

bool MjpegDecoder::available() noexcept {
  return TACSE3_HAL_HAS_TURBOJPEG != 0;
}

MjpegDecoder::~MjpegDecoder() {
#if TACSE3_HAL_HAS_TURBOJPEG
  if (handle_ != nullptr) tjDestroy(static_cast<tjhandle>(handle_));
#endif
}

std::size_t MjpegDecoder::output_bytes() const noexcept {
  return static_cast<std::size_t>(output_stride()) * static_cast<std::size_t>(height_);
}

int MjpegDecoder::output_stride() const noexcept {
  return packed_row_bytes(output_, width_);
}

CameraStatus MjpegDecoder::init(int width, int height, dsp::PixelFormat output) noexcept {
  if (width <= 0 || height <= 0 || width > 8192 || height > 8192) {
    return CameraStatus::error(CameraError::kBadConfig, "MJPEG decoder: bad size %dx%d", width,
                               height);
  }
  if (output != dsp::PixelFormat::kGrey && output != dsp::PixelFormat::kRgb888) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "MJPEG decoder: output must be GREY or RGB888, not %s",
                               to_string(output));
  }
  width_ = width;
  height_ = height;
  output_ = output;
#if TACSE3_HAL_HAS_TURBOJPEG
  if (handle_ == nullptr) handle_ = tjInitDecompress();
  if (handle_ == nullptr) {
    return CameraStatus::error(CameraError::kIo, "MJPEG decoder: tjInitDecompress failed: %s",
                               tjGetErrorStr2(nullptr));
  }
  return CameraStatus::success();
#else
  return CameraStatus::error(CameraError::kUnavailable,
                             "MJPEG decoding not compiled in (libturbojpeg0-dev was not found "
                             "when tacse3 was configured)");
#endif
}

CameraStatus MjpegDecoder::decode(const std::uint8_t* jpeg, std::size_t jpeg_bytes,
                                  std::uint8_t* dst, std::size_t dst_bytes,
                                  dsp::FrameView& out) noexcept {
#if TACSE3_HAL_HAS_TURBOJPEG
  if (handle_ == nullptr) {
    return CameraStatus::error(CameraError::kBadState, "MJPEG decoder used before init()");
  }
  if (jpeg == nullptr || jpeg_bytes < 4 || jpeg[0] != 0xff || jpeg[1] != 0xd8) {
    return CameraStatus::error(CameraError::kCorruptFrame,
                               "MJPEG frame of %zu bytes has no JPEG start marker", jpeg_bytes);
  }
  if (dst == nullptr || dst_bytes < output_bytes()) {
    return CameraStatus::error(CameraError::kBadConfig,
                               "MJPEG decoder: output buffer %zu bytes, need %zu", dst_bytes,
                               output_bytes());
  }
  auto h = static_cast<tjhandle>(handle_);
  int w = 0;
  int ht = 0;
  int subsamp = 0;
  int colorspace = 0;
  const auto size = static_cast<unsigned long>(jpeg_bytes);
  if (tjDecompressHeader3(h, jpeg, size, &w, &ht, &subsamp, &colorspace) != 0) {
    return CameraStatus::error(CameraError::kCorruptFrame, "MJPEG header: %s", tjGetErrorStr2(h));
  }
  if (w != width_ || ht != height_) {
    return CameraStatus::error(CameraError::kCorruptFrame, "MJPEG frame is %dx%d, expected %dx%d",
                               w, ht, width_, height_);
  }
  const int pf = output_ == dsp::PixelFormat::kGrey ? TJPF_GRAY : TJPF_RGB;
  if (tjDecompress2(h, jpeg, size, dst, width_, output_stride(), height_, pf, TJFLAG_LIMITSCANS) !=
      0) {
    if (tjGetErrorCode(h) != TJERR_WARNING) {
      return CameraStatus::error(CameraError::kCorruptFrame, "MJPEG decode: %s", tjGetErrorStr2(h));
    }
    ++warnings_;
  }
  out.data = dst;
  out.size_bytes = output_bytes();
  out.width = width_;
  out.height = height_;
  out.stride_bytes = output_stride();
  out.format = output_;
  return CameraStatus::success();
#else
  (void)jpeg;
  (void)jpeg_bytes;
  (void)dst;
  (void)dst_bytes;
  (void)out;
  return CameraStatus::error(CameraError::kUnavailable, "MJPEG decoding not compiled in");
#endif
}

}  // namespace tacse3::hal
