// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: SIMD luma with the 2x2 box, or with the [1 3 3 1] filter and 2:1 decimation
// (Google Highway), bit-exact with the scalar paths of luma.cpp.
// Highway compiles this file once per target (foreach_target.h); simd_dispatch.hpp says which.
#include <cstddef>
#include <cstdint>

#include "luma_kernels.hpp"
#include "simd_dispatch.hpp"
#include "tacse3/dsp/luma.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "luma_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace tacse3::dsp::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

#if HWY_TARGET != HWY_SCALAR
// Sums of adjacent byte pairs (2k, 2k+1) as uint16 lanes (<= 510): each uint16 lane holds one
// pair on these little-endian targets.
template <class D16, class V8>
HWY_INLINE hn::Vec<D16> PairSums(D16 d16, V8 v) {
  const auto w = hn::BitCast(d16, v);
  return hn::Add(hn::And(w, hn::Set(d16, 0xFF)), hn::ShiftRight<8>(w));
}
#endif

// One RGB888 output row. Scaling and overflow: per block and channel, two pair sums of bytes
// <= 1020 (uint16); the weighted sum <= 256 * 1020 = 261120 in int32 lanes; (y + 128) >> 8
// <= 1020, so the saturating demotion to uint16 never clips.
void RgbRow(const std::uint8_t* HWY_RESTRICT r0, const std::uint8_t* HWY_RESTRICT r1,
            std::uint16_t* HWY_RESTRICT out) {
  int x = 0;
#if HWY_TARGET != HWY_SCALAR
  const hn::ScalableTag<std::uint8_t> d8;
  const hn::Repartition<std::uint16_t, decltype(d8)> d16;
  const hn::Half<decltype(d16)> dh16;
  const hn::Rebind<std::int32_t, decltype(dh16)> d32;
  const int step = static_cast<int>(hn::Lanes(d16));  // output pixels per iteration
  const auto wr = hn::Set(d32, kLumaWeightR);
  const auto wg = hn::Set(d32, kLumaWeightG);
  const auto wb = hn::Set(d32, kLumaWeightB);
  const auto half = hn::Set(d32, 128);
  for (; x < kWorkWidth - kWorkWidth % step; x += step) {
    hn::Vec<decltype(d8)> ra, ga, ba, rb, gb, bb;
    hn::LoadInterleaved3(d8, r0 + 6 * x, ra, ga, ba);
    hn::LoadInterleaved3(d8, r1 + 6 * x, rb, gb, bb);
    const auto r = hn::Add(PairSums(d16, ra), PairSums(d16, rb));
    const auto g = hn::Add(PairSums(d16, ga), PairSums(d16, gb));
    const auto b = hn::Add(PairSums(d16, ba), PairSums(d16, bb));
    const auto luma = [&](auto rh, auto gh, auto bh) {
      auto y = hn::Mul(hn::PromoteTo(d32, rh), wr);
      y = hn::Add(y, hn::Mul(hn::PromoteTo(d32, gh), wg));
      y = hn::Add(y, hn::Mul(hn::PromoteTo(d32, bh), wb));
      return hn::DemoteTo(dh16, hn::ShiftRight<8>(hn::Add(y, half)));
    };
    hn::StoreU(luma(hn::LowerHalf(dh16, r), hn::LowerHalf(dh16, g), hn::LowerHalf(dh16, b)), dh16,
               out + x);
    hn::StoreU(luma(hn::UpperHalf(dh16, r), hn::UpperHalf(dh16, g), hn::UpperHalf(dh16, b)), dh16,
               out + x + step / 2);
  }
#endif
  for (; x < kWorkWidth; ++x) out[x] = rgb_px(r0, r1, x);
}

// One YUYV output row: the luma bytes sit at 4k and 4k + 2. Scaling: four bytes, sum <= 1020.
void YuyvRow(const std::uint8_t* HWY_RESTRICT r0, const std::uint8_t* HWY_RESTRICT r1,
             std::uint16_t* HWY_RESTRICT out) {
  int x = 0;
#if HWY_TARGET != HWY_SCALAR
  const hn::ScalableTag<std::uint8_t> d8;
  const hn::Repartition<std::uint16_t, decltype(d8)> d16;
  const hn::Repartition<std::uint32_t, decltype(d8)> d32;
  const hn::Half<decltype(d16)> dh16;
  const int step = static_cast<int>(hn::Lanes(d16));  // two loads of Lanes(d32) macropixels
  const int half_step = step / 2;
  // Y bytes of each macropixel as two uint16 lanes, summed into one uint32 lane (<= 510).
  const auto y_pair = [&](const std::uint8_t* p) {
    const auto w =
        hn::BitCast(d32, hn::And(hn::BitCast(d16, hn::LoadU(d8, p)), hn::Set(d16, 0xFF)));
    return hn::Add(hn::And(w, hn::Set(d32, 0xFFFF)), hn::ShiftRight<16>(w));
  };
  const hn::Repartition<std::int32_t, decltype(d8)> di32;
  for (; x < kWorkWidth - kWorkWidth % step; x += step) {
    const auto lo = hn::Add(y_pair(r0 + 4 * x), y_pair(r1 + 4 * x));
    const auto hi = hn::Add(y_pair(r0 + 4 * (x + half_step)), y_pair(r1 + 4 * (x + half_step)));
    hn::StoreU(hn::DemoteTo(dh16, hn::BitCast(di32, lo)), dh16, out + x);
    hn::StoreU(hn::DemoteTo(dh16, hn::BitCast(di32, hi)), dh16, out + x + half_step);
  }
#endif
  for (; x < kWorkWidth; ++x) out[x] = yuyv_px(r0, r1, x);
}

// One GREY output row. Scaling: two pair sums <= 510 each, total <= 1020 in uint16 lanes.
void GreyRow(const std::uint8_t* HWY_RESTRICT r0, const std::uint8_t* HWY_RESTRICT r1,
             std::uint16_t* HWY_RESTRICT out) {
  int x = 0;
#if HWY_TARGET != HWY_SCALAR
  const hn::ScalableTag<std::uint8_t> d8;
  const hn::Repartition<std::uint16_t, decltype(d8)> d16;
  const int step = static_cast<int>(hn::Lanes(d16));
  for (; x < kWorkWidth - kWorkWidth % step; x += step) {
    const auto s =
        hn::Add(PairSums(d16, hn::LoadU(d8, r0 + 2 * x)), PairSums(d16, hn::LoadU(d8, r1 + 2 * x)));
    hn::StoreU(s, d16, out + x);
  }
#endif
  for (; x < kWorkWidth; ++x) out[x] = grey_px(r0, r1, x);
}

void LumaImage(PixelFormat format, const std::uint8_t* data, std::size_t stride,
               std::uint16_t* out) {
  for (int y = 0; y < kWorkHeight; ++y) {
    const std::uint8_t* r0 = data + stride * static_cast<std::size_t>(2 * y);
    const std::uint8_t* r1 = r0 + stride;
    std::uint16_t* o = out + static_cast<std::size_t>(y) * kWorkWidth;
    switch (format) {
      case PixelFormat::kRgb888:
        RgbRow(r0, r1, o);
        break;
      case PixelFormat::kYuyv:
        YuyvRow(r0, r1, o);
        break;
      case PixelFormat::kGrey:
        GreyRow(r0, r1, o);
        break;
    }
  }
}

// kBinomial.
// One sensor row's Q8 luma (y[0 .. kSensorWidth)). Scaling and overflow: every product and
// the RGB sum are <= 65280, so the uint16 lanes never wrap.
void LumaRowQ8(PixelFormat format, const std::uint8_t* HWY_RESTRICT row,
               std::uint16_t* HWY_RESTRICT y) {
  int i = 0;
#if HWY_TARGET != HWY_SCALAR
  const hn::ScalableTag<std::uint16_t> d16;
  const hn::Rebind<std::uint8_t, decltype(d16)> d8;         // one byte per uint16 lane
  const hn::Repartition<std::uint8_t, decltype(d16)> d8x2;  // two bytes per uint16 lane
  const int step = static_cast<int>(hn::Lanes(d16));
  const int end = kSensorWidth - kSensorWidth % step;
  switch (format) {
    case PixelFormat::kRgb888: {
      const auto wr = hn::Set(d16, kLumaWeightR);
      const auto wg = hn::Set(d16, kLumaWeightG);
      const auto wb = hn::Set(d16, kLumaWeightB);
      for (; i < end; i += step) {
        hn::Vec<decltype(d8)> r, g, b;
        hn::LoadInterleaved3(d8, row + 3 * i, r, g, b);
        auto v = hn::Mul(hn::PromoteTo(d16, r), wr);
        v = hn::Add(v, hn::Mul(hn::PromoteTo(d16, g), wg));
        hn::StoreU(hn::Add(v, hn::Mul(hn::PromoteTo(d16, b), wb)), d16, y + i);
      }
      break;
    }
    case PixelFormat::kYuyv:  // Y0 U Y1 V: the low byte of each little-endian uint16 is a Y
      for (; i < end; i += step) {
        const auto w = hn::BitCast(d16, hn::LoadU(d8x2, row + 2 * i));
        hn::StoreU(hn::ShiftLeft<8>(w), d16, y + i);
      }
      break;
    case PixelFormat::kGrey:
      for (; i < end; i += step) {
        hn::StoreU(hn::ShiftLeft<8>(hn::PromoteTo(d16, hn::LoadU(d8, row + i))), d16, y + i);
      }
      break;
  }
#endif
  for (; i < kSensorWidth; ++i) y[i] = luma_q8(format, row, i);
}

// The [1 3 3 1] filter and 2:1 decimation along x (luma_kernels.hpp's decimate_px). Lane j of
// the two pair loads at y + 2x and y + 2x + 2 holds Y(2(x + j) - 1), Y(2(x + j)) and
// Y(2(x + j) + 1), Y(2(x + j) + 2) through the pad. Scaling: sums <= 522240 in uint32 lanes.
void DecimateRow(const std::uint16_t* HWY_RESTRICT y, std::uint32_t* HWY_RESTRICT h) {
  int x = 0;
#if HWY_TARGET != HWY_SCALAR
  const hn::ScalableTag<std::uint16_t> d16;
  const hn::Half<decltype(d16)> dh16;
  const hn::Rebind<std::uint32_t, decltype(dh16)> d32;
  const int step = static_cast<int>(hn::Lanes(d16));
  const auto three = hn::Set(d32, 3u);
  const auto sum = [&](auto m1, auto a, auto b, auto c) {
    const auto w = [&](auto v) { return hn::PromoteTo(d32, v); };
    return hn::Add(hn::Add(w(m1), w(c)), hn::Mul(hn::Add(w(a), w(b)), three));
  };
  for (; x < kWorkWidth - kWorkWidth % step; x += step) {
    hn::Vec<decltype(d16)> m1, a, b, c;
    hn::LoadInterleaved2(d16, y + 2 * x, m1, a);
    hn::LoadInterleaved2(d16, y + 2 * x + 2, b, c);
    hn::StoreU(sum(hn::LowerHalf(dh16, m1), hn::LowerHalf(dh16, a), hn::LowerHalf(dh16, b),
                   hn::LowerHalf(dh16, c)),
               d32, h + x);
    hn::StoreU(sum(hn::UpperHalf(dh16, m1), hn::UpperHalf(dh16, a), hn::UpperHalf(dh16, b),
                   hn::UpperHalf(dh16, c)),
               d32, h + x + step / 2);
  }
#endif
  for (; x < kWorkWidth; ++x) h[x] = decimate_px(y, x);
}

// The [1 3 3 1] filter along y and the one rounding (vertical_px). Scaling: sums <= 4177920 in
// uint32 lanes; the result <= 1020, so the saturating demotion to uint16 never clips.
void VerticalRow(const std::uint32_t* HWY_RESTRICT m1, const std::uint32_t* HWY_RESTRICT a,
                 const std::uint32_t* HWY_RESTRICT b, const std::uint32_t* HWY_RESTRICT c,
                 std::uint16_t* HWY_RESTRICT out) {
  int x = 0;
#if HWY_TARGET != HWY_SCALAR
  const hn::ScalableTag<std::int32_t> di32;
  const hn::Rebind<std::uint32_t, decltype(di32)> d32;
  const hn::Rebind<std::uint16_t, decltype(di32)> d16;
  const int step = static_cast<int>(hn::Lanes(d32));
  const auto three = hn::Set(d32, 3u);
  const auto half = hn::Set(d32, 2048u);
  for (; x < kWorkWidth - kWorkWidth % step; x += step) {
    auto s = hn::Add(hn::LoadU(d32, m1 + x), hn::LoadU(d32, c + x));
    s = hn::Add(s, hn::Mul(hn::Add(hn::LoadU(d32, a + x), hn::LoadU(d32, b + x)), three));
    s = hn::ShiftRight<12>(hn::Add(s, half));
    hn::StoreU(hn::DemoteTo(d16, hn::BitCast(di32, s)), d16, out + x);
  }
#endif
  for (; x < kWorkWidth; ++x) out[x] = vertical_px(m1, a, b, c, x);
}

void LumaBinomialImage(PixelFormat format, const std::uint8_t* data, std::size_t stride,
                       std::uint16_t* out) {
  filter_frame(
      data, stride, out,
      [format](const std::uint8_t* row, std::uint16_t* y) { LumaRowQ8(format, row, y); },
      DecimateRow, VerticalRow);
}

}  // namespace HWY_NAMESPACE
}  // namespace tacse3::dsp::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace tacse3::dsp::detail {
TACSE3_SIMD_EXPORT(LumaImage);
TACSE3_SIMD_EXPORT(LumaBinomialImage);

void luma_image_simd(PixelFormat format, const std::uint8_t* data, std::size_t stride,
                     std::uint16_t* out) noexcept {
  TACSE3_SIMD_CALL(LumaImage)(format, data, stride, out);
}

void luma_binomial_simd(PixelFormat format, const std::uint8_t* data, std::size_t stride,
                        std::uint16_t* out) noexcept {
  TACSE3_SIMD_CALL(LumaBinomialImage)(format, data, stride, out);
}
}  // namespace tacse3::dsp::detail
#endif
