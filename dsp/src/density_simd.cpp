// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: SIMD pair accumulation of the Gaussian density (Google Highway), bit-exact with
// GaussianDensity::kernel_of per pair. simd_dispatch.hpp says which targets are built.
//
// Scaling and overflow (density.hpp): displacements |u| <= 2^20 (Q10), so a component
// o * 4 px + u_q - u_p stays below 2^22 in int32 lanes; it is clamped to +-c (c <= 24576), so
// r^2 = dx^2 + dy^2 <= 2 c^2 < 2^31. The LUT index r^2 >> k is at most 2N (no clamp); the
// interpolation product step * frac < 2^15 * 2^15 = 2^30; D sums stay below 2^23.
#include <cstddef>
#include <cstdint>

#include "density_kernels.hpp"
#include "simd_dispatch.hpp"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "density_simd.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace tacse3::dsp::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

constexpr std::int32_t kCellQ10 = kGridStride << GaussianDensity::kWorkFrac;

// Lanes pairs at a time along a row. A row's last group is aligned to the row end (every row has
// at least 34 pairs, more than any vector's lanes) and the lanes already done are zeroed. The p
// and q groups are read-modify-written one after the other, so groups that overlap (offsets
// (1..7, 0)) accumulate correctly.
void Pairs(const DensityPairs& s) {
  const hn::ScalableTag<std::int32_t> d;
  const int n = static_cast<int>(hn::Lanes(d));
  const int shift = s.lut_shift;
  const int frac_shift = shift > 15 ? shift - 15 : 0;
  const int frac_bits = shift - frac_shift;
  const auto frac_mask = hn::Set(d, (std::int32_t{1} << shift) - 1);
  const auto rnd = hn::Set(d, frac_bits > 0 ? (std::int32_t{1} << (frac_bits - 1)) : 0);
  const auto hi = hn::Set(d, s.limit);
  const auto lo = hn::Neg(hi);
  const auto low16 = hn::Set(d, 0xFFFF);

  const auto kernel = [&](int p, int q, decltype(hi) bx, decltype(hi) by) {
    auto dx = hn::Sub(hn::Add(bx, hn::LoadU(d, s.ux + q)), hn::LoadU(d, s.ux + p));
    auto dy = hn::Sub(hn::Add(by, hn::LoadU(d, s.uy + q)), hn::LoadU(d, s.uy + p));
    dx = hn::Min(hn::Max(dx, lo), hi);
    dy = hn::Min(hn::Max(dy, lo), hi);
    const auto r2 = hn::Add(hn::Mul(dx, dx), hn::Mul(dy, dy));
    const auto e = hn::GatherIndex(d, s.lut, hn::ShiftRightSame(r2, shift));
    const auto frac = hn::ShiftRightSame(hn::And(r2, frac_mask), frac_shift);
    const auto step = hn::ShiftRight<16>(e);
    auto k = hn::Add(hn::And(e, low16),
                     hn::ShiftRightSame(hn::Sub(rnd, hn::Mul(step, frac)), frac_bits));
    if (s.lane_mask != nullptr) {
      k = hn::And(k, hn::And(hn::LoadU(d, s.lane_mask + p), hn::LoadU(d, s.lane_mask + q)));
    }
    return k;
  };
  const auto add = [&](int p, int q, decltype(hi) k) {
    hn::StoreU(hn::Add(hn::LoadU(d, s.density + p), k), d, s.density + p);
    hn::StoreU(hn::Add(hn::LoadU(d, s.density + q), k), d, s.density + q);
  };

  for (int i = 0; i < s.num_offsets; ++i) {
    const DensityOffset& o = s.offsets[i];
    const int x0 = o.ox < 0 ? -o.ox : 0;
    const int x1 = o.ox > 0 ? kGridWidth - o.ox : kGridWidth;
    const int len = x1 - x0;
    const int full = len - len % n;
    const auto tail_keep = hn::Gt(hn::Iota(d, 0), hn::Set(d, n - len % n - 1));
    const auto bx = hn::Set(d, o.ox * kCellQ10);
    const auto by = hn::Set(d, o.oy * kCellQ10);
    const int step = o.oy * kGridWidth + o.ox;
    for (int y = 0; y + o.oy < kGridHeight; ++y) {
      const int p0 = y * kGridWidth + x0;
      for (int p = p0; p < p0 + full; p += n) add(p, p + step, kernel(p, p + step, bx, by));
      if (full != len) {
        const int p = p0 + len - n;
        add(p, p + step, hn::IfThenElseZero(tail_keep, kernel(p, p + step, bx, by)));
      }
    }
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace tacse3::dsp::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace tacse3::dsp::detail {
TACSE3_SIMD_EXPORT(Pairs);

void density_pairs_simd(const DensityPairs& s) noexcept {
  TACSE3_SIMD_CALL(Pairs)(s);
}
}  // namespace tacse3::dsp::detail
#endif
