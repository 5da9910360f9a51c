// SPDX-License-Identifier: Apache-2.0
// tacse3 fuzz: the MJPEG decoder of the V4L2 backend (hal/camera MjpegDecoder, libjpeg-turbo).
// Input: [size/format byte][JPEG bytes]. A frame is decoded or refused as corrupt; a decoded
// frame fills exactly the caller's buffer, which ASan guards on both sides.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "tacse3/hal/camera/mjpeg_decoder.hpp"

namespace th = tacse3::hal;
using tacse3::dsp::PixelFormat;

namespace {
struct Size {
  int width, height;
};
// The seeds' sizes (fuzz/make_seeds.py) and the sensor's own.
constexpr Size kSizes[] = {{16, 8}, {32, 24}, {320, 240}, {8, 8}};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const Size sz = kSizes[data[0] & 3];
  const PixelFormat pf = (data[0] & 4) ? PixelFormat::kRgb888 : PixelFormat::kGrey;
  th::MjpegDecoder dec;
  if (!dec.init(sz.width, sz.height, pf).ok()) __builtin_trap();
  std::vector<std::uint8_t> dst(dec.output_bytes());
  tacse3::dsp::FrameView out{};
  const th::CameraStatus st = dec.decode(data + 1, size - 1, dst.data(), dst.size(), out);
  if (st.ok()) {
    if (out.data != dst.data() || out.size_bytes != dst.size() || out.width != sz.width ||
        out.height != sz.height || out.format != pf) {
      __builtin_trap();
    }
  } else if (st.code != th::CameraError::kCorruptFrame) {
    __builtin_trap();  // a bad frame is a corrupt frame, nothing else
  }
  return 0;
}
