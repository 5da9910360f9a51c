// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: camera frame to U8.2 working image (luma, then the 2x2 box or the 4x4 binomial
// and 2:1 decimation).
#include "tacse3/dsp/luma.hpp"

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "luma_kernels.hpp"

namespace tacse3::dsp {
namespace {

bool known_format(PixelFormat f) noexcept {
  return f == PixelFormat::kRgb888 || f == PixelFormat::kYuyv || f == PixelFormat::kGrey;
}

// kBox's scalar path: one output row from two input rows. Each kernel is a plain counted loop over
// contiguous bytes so that g++ -O2 can vectorise it.
void grey_row(const std::uint8_t* __restrict r0, const std::uint8_t* __restrict r1,
              std::uint16_t* __restrict out) noexcept {
  for (int x = 0; x < kWorkWidth; ++x) {
    out[x] = static_cast<std::uint16_t>(r0[2 * x] + r0[2 * x + 1] + r1[2 * x] + r1[2 * x + 1]);
  }
}

// YUYV: Y0 U Y1 V -> the two luma bytes of a macropixel are exactly one 2-pixel column pair.
// On little-endian targets a macropixel is read as one 32-bit word (Y0 = bits 0-7, Y1 = bits
// 16-23), which vectorises as 32-bit lanes; the byte loop is the portable fallback.
void yuyv_row(const std::uint8_t* __restrict r0, const std::uint8_t* __restrict r1,
              std::uint16_t* __restrict out) noexcept {
  if constexpr (std::endian::native == std::endian::little) {
    for (int x = 0; x < kWorkWidth; ++x) {
      std::uint32_t a, b;
      std::memcpy(&a, r0 + 4 * x, sizeof a);
      std::memcpy(&b, r1 + 4 * x, sizeof b);
      out[x] = static_cast<std::uint16_t>((a & 0xFFu) + ((a >> 16) & 0xFFu) + (b & 0xFFu) +
                                          ((b >> 16) & 0xFFu));
    }
  } else {
    for (int x = 0; x < kWorkWidth; ++x) {
      out[x] = static_cast<std::uint16_t>(r0[4 * x] + r0[4 * x + 2] + r1[4 * x] + r1[4 * x + 2]);
    }
  }
}

// Two passes: the vertical pair sums of all 960 bytes (contiguous, vectorised), then the
// weighted horizontal pairs (stride 6 bytes). Scaling: pair sums <= 510 (uint16); the weighted
// block sum <= 256 * 1020 = 261120 (int32); rounded half-up once.
void rgb_row(const std::uint8_t* __restrict r0, const std::uint8_t* __restrict r1,
             std::uint16_t* __restrict out) noexcept {
  std::array<std::uint16_t, 3 * kSensorWidth> v{};
  for (int k = 0; k < 3 * kSensorWidth; ++k) {
    v[static_cast<std::size_t>(k)] = static_cast<std::uint16_t>(r0[k] + r1[k]);
  }
  for (int x = 0; x < kWorkWidth; ++x) {
    const std::uint16_t* p = v.data() + 6 * x;
    const std::int32_t y =
        kLumaWeightR * (p[0] + p[3]) + kLumaWeightG * (p[1] + p[4]) + kLumaWeightB * (p[2] + p[5]);
    out[x] = static_cast<std::uint16_t>((y + 128) >> 8);
  }
}

// kBinomial's scalar steps: plain counted loops that g++ -O2 may vectorise.
void luma_row(PixelFormat format, const std::uint8_t* __restrict row,
              std::uint16_t* __restrict y) noexcept {
  for (int i = 0; i < kSensorWidth; ++i) y[i] = detail::luma_q8(format, row, i);
}

void decimate_row(const std::uint16_t* __restrict y, std::uint32_t* __restrict h) noexcept {
  for (int x = 0; x < kWorkWidth; ++x) h[x] = detail::decimate_px(y, x);
}

void vertical_row(const std::uint32_t* m1, const std::uint32_t* a, const std::uint32_t* b,
                  const std::uint32_t* c, std::uint16_t* __restrict out) noexcept {
  for (int x = 0; x < kWorkWidth; ++x) out[x] = detail::vertical_px(m1, a, b, c, x);
}

std::size_t frame_stride(const FrameView& in) noexcept {
  return static_cast<std::size_t>(in.stride_bytes == 0 ? packed_row_bytes(in.format)
                                                       : in.stride_bytes);
}

}  // namespace

Status check_frame(const FrameView& in) noexcept {
  if (in.data == nullptr) return Status::kNullFrame;
  if (!known_format(in.format)) return Status::kBadPixelFormat;
  if (in.width != kSensorWidth || in.height != kSensorHeight) return Status::kBadFrameSize;
  const int row_bytes = packed_row_bytes(in.format);
  if (in.stride_bytes != 0 && in.stride_bytes < row_bytes) return Status::kBadFrameSize;
  const std::size_t stride =
      static_cast<std::size_t>(in.stride_bytes == 0 ? row_bytes : in.stride_bytes);
  const std::size_t needed =
      stride * static_cast<std::size_t>(kSensorHeight - 1) + static_cast<std::size_t>(row_bytes);
  if (in.size_bytes < needed) return Status::kBadFrameSize;
  return Status::kOk;
}

Status frame_to_work_image(const FrameView& in, WorkImage& out, WorkImageFilter filter) noexcept {
  const Status s = check_frame(in);
  if (s != Status::kOk) return s;
  if (filter == WorkImageFilter::kBinomial) {
    detail::luma_binomial_simd(in.format, in.data, frame_stride(in), out.px.data());
  } else {
    detail::luma_image_simd(in.format, in.data, frame_stride(in), out.px.data());
  }
  return Status::kOk;
}

Status frame_to_work_image_scalar(const FrameView& in, WorkImage& out,
                                  WorkImageFilter filter) noexcept {
  const Status s = check_frame(in);
  if (s != Status::kOk) return s;
  const std::size_t stride = frame_stride(in);
  if (filter == WorkImageFilter::kBinomial) {
    const PixelFormat format = in.format;
    detail::filter_frame(
        in.data, stride, out.px.data(),
        [format](const std::uint8_t* row, std::uint16_t* y) { luma_row(format, row, y); },
        decimate_row, vertical_row);
    return Status::kOk;
  }
  for (int y = 0; y < kWorkHeight; ++y) {
    const std::uint8_t* r0 = in.data + stride * static_cast<std::size_t>(2 * y);
    const std::uint8_t* r1 = r0 + stride;
    std::uint16_t* o = out.px.data() + static_cast<std::size_t>(y) * kWorkWidth;
    switch (in.format) {
      case PixelFormat::kRgb888:
        rgb_row(r0, r1, o);
        break;
      case PixelFormat::kYuyv:
        yuyv_row(r0, r1, o);
        break;
      case PixelFormat::kGrey:
        grey_row(r0, r1, o);
        break;
    }
  }
  return Status::kOk;
}

}  // namespace tacse3::dsp
