// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: Gaussian density map G of the displaced flow grid (local-expansion proxy).
#include "tacse3/dsp/density.hpp"

#include <cmath>
#include <cstring>

#include "density_kernels.hpp"
#include "tacse3/dsp/fixed.hpp"

namespace tacse3::dsp {
namespace {

constexpr std::int32_t kCellQ10 = kGridStride << GaussianDensity::kWorkFrac;  // 4 px in Q10
constexpr std::int32_t kMaxDisplacementQ10 = std::int32_t{1} << 20;
constexpr double kCutoffSigmas = 3.0;
constexpr double kOffsetMarginCells = 0.5;

// Four int32 lanes as a GCC generic vector (SSE2 / NEON / scalar fallback), unaligned access.
using V4 = std::int32_t __attribute__((vector_size(16)));
inline V4 load4(const std::int32_t* p) noexcept {
  V4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline void store4(std::int32_t* p, V4 v) noexcept {
  std::memcpy(p, &v, sizeof v);
}
inline V4 splat4(std::int32_t a) noexcept {
  return V4{a, a, a, a};
}

}  // namespace

GaussianDensity::GaussianDensity() noexcept {
  (void)configure(DensityConfig{});
}

Status GaussianDensity::configure(const DensityConfig& config) noexcept {
  const double sigma = config.sigma_cells;
  if (!(sigma >= kMinDensitySigmaCells && sigma <= kMaxDensitySigmaCells)) {
    return Status::kBadArgument;
  }
  // Components are clamped to c = ceil(r_c) (Q10), so r^2 <= 2 c^2. The LUT samples K at
  // r^2 = i * 2^k (Q20 px^2) for i in [0, 2N], N = ceil(c^2 / 2^k) <= 4096 with the smallest such
  // k, so no index ever needs clamping. Entry i packs K_i (Q15, bits 0-15) and the step
  // K_i - K_{i+1} (bits 16-30) for the interpolation: one table read per pair.
  const double sigma_px = sigma * kGridStride;
  const double scale = static_cast<double>(std::int64_t{1} << (2 * kWorkFrac));  // Q20
  const double r_cut_q10 = kCutoffSigmas * sigma_px * static_cast<double>(1 << kWorkFrac);
  const std::int32_t c = static_cast<std::int32_t>(std::ceil(r_cut_q10));
  const double c2 = static_cast<double>(c) * c;
  int shift = 0;
  while (std::ceil(c2 / std::ldexp(1.0, shift)) > kMaxLutHalf) ++shift;
  const int n = static_cast<int>(std::ceil(c2 / std::ldexp(1.0, shift)));
  const int entries = 2 * n + 1;  // indices 0 .. 2N
  const double t_cut = 0.5 * kCutoffSigmas * kCutoffSigmas;
  const double k_cut = std::exp(-t_cut);
  const auto k_at = [&](int i) -> std::int32_t {
    const double r2 = std::ldexp(static_cast<double>(i), shift) / scale;  // px^2
    const double t = r2 / (2.0 * sigma_px * sigma_px);
    return t >= t_cut ? 0 : to_q32<kKernelFrac>((std::exp(-t) - k_cut) / (1.0 - k_cut));
  };
  std::array<std::int32_t, kMaxLut> lut{};
  std::int32_t k_next = k_at(0);
  for (int i = 0; i < entries; ++i) {
    const std::int32_t k = k_next;
    k_next = i + 1 < entries ? k_at(i + 1) : 0;
    const std::int32_t step = k - k_next;  // >= 0: K decreases; < 80 LSB for every sigma
    if (step < 0 || step >= (1 << 15)) return Status::kBadArgument;  // unreachable by design
    lut[static_cast<std::size_t>(i)] = k | (step << 16);
  }

  config_ = config;
  undeformed_ready_ = false;
  lut_shift_ = shift;
  component_limit_ = c;
  lut_ = lut;

  // Neighbour offsets in the upper half plane (each unordered pair once). The margin lets points
  // that start just beyond the cut-off and move inside it under compression still count (their
  // weight is near zero there because K falls continuously to 0).
  const double reach = kCutoffSigmas * sigma + kOffsetMarginCells;
  const int rmax = static_cast<int>(std::floor(reach));
  num_offsets_ = 0;
  for (int oy = 0; oy <= rmax; ++oy) {
    for (int ox = -rmax; ox <= rmax; ++ox) {
      if (oy == 0 && ox <= 0) continue;
      if (ox * ox + oy * oy > reach * reach) continue;
      if (num_offsets_ >= kMaxOffsets / 2) continue;  // cannot happen for sigma <= 2
      Offset& o = offsets_[static_cast<std::size_t>(num_offsets_++)];
      o.ox = ox;
      o.oy = oy;
      // Exactly what the pair loop computes for zero relative displacement.
      o.k0 = kernel_of(ox * kCellQ10, oy * kCellQ10);
    }
  }
  return Status::kOk;
}

std::int32_t GaussianDensity::kernel_of(std::int32_t dx_q10, std::int32_t dy_q10) const noexcept {
  const std::int32_t c = component_limit_;
  dx_q10 = dx_q10 > c ? c : (dx_q10 < -c ? -c : dx_q10);
  dy_q10 = dy_q10 > c ? c : (dy_q10 < -c ? -c : dy_q10);
  const std::int32_t r2 = dx_q10 * dx_q10 + dy_q10 * dy_q10;  // <= 2 c^2 < 2^31
  // Interpolate on the top 15 bits of the remainder so step * frac < 2^30.
  const int frac_shift = lut_shift_ > 15 ? lut_shift_ - 15 : 0;
  const int frac_bits = lut_shift_ - frac_shift;
  const std::int32_t frac = (r2 & ((std::int32_t{1} << lut_shift_) - 1)) >> frac_shift;
  const std::int32_t e = lut_[static_cast<std::size_t>(r2 >> lut_shift_)];
  const std::int32_t rnd = frac_bits > 0 ? (std::int32_t{1} << (frac_bits - 1)) : 0;
  return (e & 0xFFFF) + ((rnd - (e >> 16) * frac) >> frac_bits);
}

std::int32_t GaussianDensity::kernel_q15(double r_px) const noexcept {
  if (!(r_px >= 0.0)) r_px = 0.0;
  const double q = std::fmin(r_px * (1 << kWorkFrac), 32767.0);
  return kernel_of(static_cast<std::int32_t>(std::lround(q)), 0);
}

void GaussianDensity::update_undeformed(const GridMask& valid) noexcept {
  for (std::size_t p = 0; p < kGridCount; ++p) {
    density0_.v[p] = valid.v[p] != 0 ? (std::int32_t{1} << kKernelFrac) : 0;
  }
  for (int n = 0; n < num_offsets_; ++n) {
    const Offset& o = offsets_[static_cast<std::size_t>(n)];
    const int x0 = o.ox < 0 ? -o.ox : 0;
    const int x1 = o.ox > 0 ? kGridWidth - o.ox : kGridWidth;
    const int step = o.oy * kGridWidth + o.ox;
    for (int y = 0; y + o.oy < kGridHeight; ++y) {
      for (int x = x0; x < x1; ++x) {
        const std::size_t p = static_cast<std::size_t>(y * kGridWidth + x);
        const std::size_t q = static_cast<std::size_t>(y * kGridWidth + x + step);
        if ((valid.v[p] & valid.v[q]) == 0) continue;
        density0_.v[p] += o.k0;
        density0_.v[q] += o.k0;
      }
    }
  }
  for (std::size_t p = 0; p < kGridCount; ++p) {
    const std::int64_t d0 = density0_.v[p];
    inv_density0_.v[p] = d0 > 0 ? ((std::int64_t{1} << 46) + d0 / 2) / d0 : 0;
    cached_mask_.v[p] = valid.v[p] != 0 ? 1 : 0;
  }
  undeformed_ready_ = true;
}

// The scalar path of the pair loop: D(p) += K(p, q) and D(q) += K(p, q) for every unordered pair
// (p, q = p + offset), K from kernel_of. kMasked: pairs with an invalid end contribute 0.
template <bool kMasked>
void GaussianDensity::accumulate_pairs_scalar() noexcept {
  for (int n = 0; n < num_offsets_; ++n) {
    const Offset& o = offsets_[static_cast<std::size_t>(n)];
    const int x0 = o.ox < 0 ? -o.ox : 0;
    const int x1 = o.ox > 0 ? kGridWidth - o.ox : kGridWidth;
    const int step = o.oy * kGridWidth + o.ox;
    for (int y = 0; y + o.oy < kGridHeight; ++y) {
      for (int x = x0; x < x1; ++x) {
        const std::size_t p = static_cast<std::size_t>(y * kGridWidth + x);
        const std::size_t q = p + static_cast<std::size_t>(step);
        if (kMasked && (lane_mask_.v[p] & lane_mask_.v[q]) == 0) continue;
        const std::int32_t k =
            kernel_of(o.ox * kCellQ10 + ux_.v[q] - ux_.v[p], o.oy * kCellQ10 + uy_.v[q] - uy_.v[p]);
        density_.v[p] += k;
        density_.v[q] += k;
      }
    }
  }
}

void GaussianDensity::compute(const VectorField& displacement, const GridMask& valid,
                              ScalarField& g) noexcept {
  compute_with(true, displacement, valid, g);
}

void GaussianDensity::compute_scalar(const VectorField& displacement, const GridMask& valid,
                                     ScalarField& g) noexcept {
  compute_with(false, displacement, valid, g);
}

void GaussianDensity::compute_with(bool simd, const VectorField& displacement,
                                   const GridMask& valid, ScalarField& g) noexcept {
  bool same_mask = undeformed_ready_;
  for (std::size_t p = 0; p < kGridCount && same_mask; ++p) {
    same_mask = (valid.v[p] != 0) == (cached_mask_.v[p] != 0);
  }
  if (!same_mask) update_undeformed(valid);

  // Q16 -> Q10 working px, round half-up as (v >> 6) + bit 5 (= floor((v + 32) / 64) without the
  // overflow of v + 32), clamped to +-2^20 px far outside any real displacement (so differences
  // fit int32). Four points at a time; kGridCount is a multiple of 4.
  static_assert(kGridCount % 4 == 0);
  const V4 dlim = splat4(kMaxDisplacementQ10);
  const V4 one = splat4(1);
  const V4 self = splat4(std::int32_t{1} << kKernelFrac);
  constexpr int kShift = kFieldFrac - kWorkFrac;
  for (std::size_t p = 0; p < kGridCount; p += 4) {
    const V4 vx = load4(displacement.x.v.data() + p);
    const V4 vy = load4(displacement.y.v.data() + p);
    V4 qx = (vx >> kShift) + ((vx >> (kShift - 1)) & one);
    V4 qy = (vy >> kShift) + ((vy >> (kShift - 1)) & one);
    qx = qx > dlim ? dlim : (qx < -dlim ? -dlim : qx);
    qy = qy > dlim ? dlim : (qy < -dlim ? -dlim : qy);
    store4(ux_.v.data() + p, qx);
    store4(uy_.v.data() + p, qy);
    const V4 ok = V4{valid.v[p], valid.v[p + 1], valid.v[p + 2], valid.v[p + 3]} != 0;
    store4(lane_mask_.v.data() + p, ok);
    store4(density_.v.data() + p, self & ok);  // the point itself, K(0) = 1
  }

  bool all_valid = true;
  for (std::size_t p = 0; p < kGridCount; ++p) all_valid = all_valid && valid.v[p] != 0;
  if (simd) {
    detail::DensityPairs s;
    s.lut = lut_.data();
    s.lut_shift = lut_shift_;
    s.limit = component_limit_;
    s.offsets = offsets_.data();
    s.num_offsets = num_offsets_;
    s.ux = ux_.v.data();
    s.uy = uy_.v.data();
    s.lane_mask = all_valid ? nullptr : lane_mask_.v.data();
    s.density = density_.v.data();
    detail::density_pairs_simd(s);
  } else if (all_valid) {
    accumulate_pairs_scalar<false>();
  } else {
    accumulate_pairs_scalar<true>();
  }

  for (std::size_t p = 0; p < kGridCount; ++p) {
    if (valid.v[p] == 0) {
      g.v[p] = 0;
      continue;
    }
    const std::int64_t diff = static_cast<std::int64_t>(density_.v[p]) - density0_.v[p];
    g.v[p] = sat32(rshift_round(diff * inv_density0_.v[p], 46 - kFieldFrac));
  }
}

}  // namespace tacse3::dsp
