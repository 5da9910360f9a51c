// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: MJPEG round trip of a rendered frame (a UVC camera delivers JPEG frames).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

namespace tacse3::sim {

// True when this build links libturbojpeg (else MJPEG cameras are rejected by validate()).
bool mjpeg_available() noexcept;

// JPEG-compresses a frame at a fixed quality (4:2:2 chroma subsampling for RGB, as UVC MJPEG
// cameras send, 4:0:0 for grey) and decodes it back in place. build() creates the libturbojpeg
// handles and the compressed-frame buffer; roundtrip() makes no C++ heap allocation (libjpeg's
// per-image work pools are its own malloc/free inside each call).
class MjpegCodec {
 public:
  MjpegCodec();
  ~MjpegCodec();
  MjpegCodec(const MjpegCodec&) = delete;
  MjpegCodec& operator=(const MjpegCodec&) = delete;

  // quality in [1, 100]. False if libturbojpeg is missing or cannot start.
  bool build(int width, int height, int quality);
  // image: width x height x channels (3 = RGB888, 1 = grey), replaced by its decoded JPEG.
  bool roundtrip(std::uint8_t* image, int channels) noexcept;
  bool ready() const noexcept { return compressor_ != nullptr; }
  // Size in bytes of the last compressed frame.
  unsigned long last_size() const noexcept { return last_size_; }

 private:
  void release() noexcept;
  void* compressor_ = nullptr;
  void* decompressor_ = nullptr;
  std::vector<unsigned char> jpeg_;
  int width_ = 0, height_ = 0, quality_ = 90;
  unsigned long last_size_ = 0;
};

}  // namespace tacse3::sim
