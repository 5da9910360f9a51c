// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: SIMD sums of the normalised-convolution smoothing (Google Highway), bit-exact with
// row_pass + column_pass of smoothing.cpp. simd_dispatch.hpp says which targets are built.
//
// Scaling and overflow (inputs as in smoothing.hpp: w any int32, taps g_i Q15 > 0, sum 2^15):
//  - row pass: R = sum_i g_i m w in int64 lanes (32x32 -> 64-bit products), |R| <= 2^46. R is
//    stored as hi = R >> 16 (|hi| <= 2^30, int32) and lo = R & 0xFFFF (int32, [0, 2^16)), so that
//    the column pass multiplies 32-bit lanes only: R = hi * 2^16 + lo exactly.
//  - column pass: H = sum_j g_j hi_j in int64 lanes (|H| <= 2^45); L = sum_j g_j lo_j in int32
//    lanes, L <= (2^16 - 1) * 2^15 < 2^31 because the taps sum to 2^15; the numerator
//    N = H * 2^16 + L = sum_j g_j R_j, the scalar path's int64 value (|N| <= 2^61).
//  - weights: row sums <= 2^15, column sums <= 2^30, both in int32 lanes.
#include <cstddef>
#include <cstdint>

#include "simd_dispatch.hpp"
#include "smoothing_kernels.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "smoothing_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace tacse3::dsp::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;
using S = SmoothingSums;

inline std::int32_t tap_at(const S& s, int i) {
  return s.taps[i < 0 ? -i : i];
}

// One point of each pass in plain C++: the single-lane target and the tails of the vector rows.
void RowPoint(const S& s, int y, int x) {
  const std::size_t in = static_cast<std::size_t>(y * S::kPadWidth + S::kPad + x);
  const std::size_t out = static_cast<std::size_t>((y + S::kPad) * kGridWidth + x);
  std::int64_t ax = 0;
  std::int64_t ay = 0;
  std::int32_t aw = 0;
  for (int i = -s.radius; i <= s.radius; ++i) {
    const std::int64_t g = tap_at(s, i);
    ax += g * s.in_x[in + static_cast<std::size_t>(i)];
    ay += g * s.in_y[in + static_cast<std::size_t>(i)];
    if (s.weights) aw += static_cast<std::int32_t>(g) * s.in_w[in + static_cast<std::size_t>(i)];
  }
  s.hi_x[out] = static_cast<std::int32_t>(ax >> 16);
  s.lo_x[out] = static_cast<std::int32_t>(ax & 0xFFFF);
  s.hi_y[out] = static_cast<std::int32_t>(ay >> 16);
  s.lo_y[out] = static_cast<std::int32_t>(ay & 0xFFFF);
  s.row_w[out] = aw;
}

void ColumnPoint(const S& s, int y, int x) {
  std::int64_t hx = 0;
  std::int64_t hy = 0;
  std::int32_t lx = 0;
  std::int32_t ly = 0;
  std::int32_t w = 0;
  for (int j = -s.radius; j <= s.radius; ++j) {
    const std::int32_t g = tap_at(s, j);
    const std::size_t q = static_cast<std::size_t>((y + S::kPad + j) * kGridWidth + x);
    hx += static_cast<std::int64_t>(g) * s.hi_x[q];
    hy += static_cast<std::int64_t>(g) * s.hi_y[q];
    lx += g * s.lo_x[q];
    ly += g * s.lo_y[q];
    if (s.weights) w += g * s.row_w[q];
  }
  const std::size_t p = static_cast<std::size_t>(y * kGridWidth + x);
  s.num_x[p] = hx * 65536 + lx;
  s.num_y[p] = hy * 65536 + ly;
  s.num_w[p] = w;
}

#if HWY_TARGET == HWY_SCALAR
void Sums(const S& s) {
  for (int y = 0; y < kGridHeight; ++y) {
    for (int x = 0; x < kGridWidth; ++x) RowPoint(s, y, x);
  }
  for (int y = 0; y < kGridHeight; ++y) {
    for (int x = 0; x < kGridWidth; ++x) ColumnPoint(s, y, x);
  }
}
#else
using D = hn::ScalableTag<std::int32_t>;
using D64 = hn::RepartitionToWide<D>;

// sum_i g_i v_i of the lanes at `p + i`, as int64 sums of the even and the odd lanes.
HWY_INLINE void WideSums(const S& s, const std::int32_t* p, std::ptrdiff_t stride,
                         hn::Vec<D64>& even, hn::Vec<D64>& odd) {
  const D d;
  const D64 d64;
  even = hn::Zero(d64);
  odd = hn::Zero(d64);
  for (int i = -s.radius; i <= s.radius; ++i) {
    const auto g = hn::Set(d, tap_at(s, i));
    const auto v = hn::LoadU(d, p + i * stride);
    even = hn::Add(even, hn::MulEven(v, g));
    odd = hn::Add(odd, hn::MulEven(hn::Shuffle2301(v), g));
  }
}

// sum_i g_i v_i in int32 lanes (the caller's bound keeps it below 2^31).
HWY_INLINE hn::Vec<D> NarrowSum(const S& s, const std::int32_t* p, std::ptrdiff_t stride) {
  const D d;
  auto acc = hn::Zero(d);
  for (int i = -s.radius; i <= s.radius; ++i) {
    acc = hn::Add(acc, hn::Mul(hn::LoadU(d, p + i * stride), hn::Set(d, tap_at(s, i))));
  }
  return acc;
}

// Row sums R (even and odd lanes) stored as hi = R >> 16 and lo = R & 0xFFFF, lanes in order.
HWY_INLINE void StoreSplit(hn::Vec<D64> even, hn::Vec<D64> odd, std::int32_t* hi,
                           std::int32_t* lo) {
  const D d;
  const D64 d64;
  const auto mask = hn::Set(d64, 0xFFFF);
  const auto join = [&](hn::Vec<D64> e, hn::Vec<D64> o) {
    return hn::OddEven(hn::BitCast(d, hn::ShiftLeft<32>(o)), hn::BitCast(d, e));
  };
  hn::StoreU(join(hn::ShiftRight<16>(even), hn::ShiftRight<16>(odd)), d, hi);
  hn::StoreU(join(hn::And(even, mask), hn::And(odd, mask)), d, lo);
}

void Sums(const S& s) {
  const D d;
  const D64 d64;
  const int n = static_cast<int>(hn::Lanes(d));
  const int vec_end = kGridWidth - kGridWidth % n;
  for (int y = 0; y < kGridHeight; ++y) {
    const std::size_t in_row = static_cast<std::size_t>(y * S::kPadWidth + S::kPad);
    const std::size_t out_row = static_cast<std::size_t>((y + S::kPad) * kGridWidth);
    for (int x = 0; x < vec_end; x += n) {
      const std::size_t i = in_row + static_cast<std::size_t>(x);
      const std::size_t o = out_row + static_cast<std::size_t>(x);
      hn::Vec<D64> even, odd;
      WideSums(s, s.in_x + i, 1, even, odd);
      StoreSplit(even, odd, s.hi_x + o, s.lo_x + o);
      WideSums(s, s.in_y + i, 1, even, odd);
      StoreSplit(even, odd, s.hi_y + o, s.lo_y + o);
      if (s.weights) hn::StoreU(NarrowSum(s, s.in_w + i, 1), d, s.row_w + o);
    }
    for (int x = vec_end; x < kGridWidth; ++x) RowPoint(s, y, x);
  }
  const auto low32 = hn::Set(d64, 0xFFFFFFFF);
  // N = H * 2^16 + L; L >= 0, so its odd lanes shift down unchanged.
  const auto join = [&](hn::Vec<D64> h, hn::Vec<D> l, bool odd) {
    const auto wide = hn::BitCast(d64, l);
    return hn::Add(hn::ShiftLeft<16>(h), odd ? hn::ShiftRight<32>(wide) : hn::And(wide, low32));
  };
  for (int y = 0; y < kGridHeight; ++y) {
    const std::size_t row = static_cast<std::size_t>((y + S::kPad) * kGridWidth);
    for (int x = 0; x < vec_end; x += n) {
      const std::size_t q = row + static_cast<std::size_t>(x);
      const std::size_t p = static_cast<std::size_t>(y * kGridWidth + x);
      hn::Vec<D64> even, odd;
      WideSums(s, s.hi_x + q, kGridWidth, even, odd);
      auto l = NarrowSum(s, s.lo_x + q, kGridWidth);
      hn::StoreInterleaved2(join(even, l, false), join(odd, l, true), d64, s.num_x + p);
      WideSums(s, s.hi_y + q, kGridWidth, even, odd);
      l = NarrowSum(s, s.lo_y + q, kGridWidth);
      hn::StoreInterleaved2(join(even, l, false), join(odd, l, true), d64, s.num_y + p);
      if (s.weights) hn::StoreU(NarrowSum(s, s.row_w + q, kGridWidth), d, s.num_w + p);
    }
    for (int x = vec_end; x < kGridWidth; ++x) ColumnPoint(s, y, x);
  }
}
#endif

}  // namespace HWY_NAMESPACE
}  // namespace tacse3::dsp::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace tacse3::dsp::detail {
TACSE3_SIMD_EXPORT(Sums);

void smoothing_sums_simd(const SmoothingSums& s) noexcept {
  TACSE3_SIMD_CALL(Sums)(s);
}
}  // namespace tacse3::dsp::detail
#endif
