// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: MJPEG round trip through libturbojpeg (Debian's libturbojpeg0: the codec UVC
// cameras' frames are decoded with on the board, so the simulator compresses like the camera).
#include "tacse3/sim/mjpeg.hpp"

#if TACSE3_SIM_HAS_MJPEG
#include <turbojpeg.h>
#endif

namespace tacse3::sim {

bool mjpeg_available() noexcept {
  return TACSE3_SIM_HAS_MJPEG != 0;
}

MjpegCodec::MjpegCodec() = default;

MjpegCodec::~MjpegCodec() {
  release();
}

void MjpegCodec::release() noexcept {
#if TACSE3_SIM_HAS_MJPEG
  if (compressor_) tjDestroy(compressor_);
  if (decompressor_) tjDestroy(decompressor_);
#endif
  compressor_ = nullptr;
  decompressor_ = nullptr;
}

bool MjpegCodec::build(int width, int height, int quality) {
  release();
#if TACSE3_SIM_HAS_MJPEG
  width_ = width;
  height_ = height;
  quality_ = quality;
  jpeg_.assign(tjBufSize(width, height, TJSAMP_444), 0);
  compressor_ = tjInitCompress();
  decompressor_ = tjInitDecompress();
  if (!compressor_ || !decompressor_) {
    release();
    return false;
  }
  return true;
#else
  (void)width;
  (void)height;
  (void)quality;
  return false;
#endif
}

bool MjpegCodec::roundtrip(std::uint8_t* image, int channels) noexcept {
#if TACSE3_SIM_HAS_MJPEG
  if (!compressor_ || (channels != 1 && channels != 3)) return false;
  const int format = channels == 3 ? TJPF_RGB : TJPF_GRAY;
  const int subsamp = channels == 3 ? TJSAMP_422 : TJSAMP_GRAY;
  unsigned char* buf = jpeg_.data();
  unsigned long size = jpeg_.size();
  if (tjCompress2(compressor_, image, width_, 0, height_, format, &buf, &size, subsamp, quality_,
                  TJFLAG_NOREALLOC) != 0) {
    return false;
  }
  last_size_ = size;
  return tjDecompress2(decompressor_, buf, size, image, width_, 0, height_, format, 0) == 0;
#else
  (void)image;
  (void)channels;
  return false;
#endif
}

}  // namespace tacse3::sim
