// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: Gaussian density map G of the displaced flow grid (local-expansion proxy).
#pragma once

#include <array>
#include <cstdint>

#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Paper Sec. IV-B: "the accumulated Gaussian density map G(m) captures local expansion of w and
// yields a shift-invariant proxy for out-of-plane deformation, with relative height taken
// proportional to -G(m)". Implemented literally on the flow grid:
//
//   D(p)  = sum_{q valid} K(|(x_p + u_p) - (x_q + u_q)|)   density of the displaced points,
//                                                          evaluated at p's displaced position
//   D0(p) = sum_{q valid} K(|x_p - x_q|)                   the same sum, undeformed
//   G(p)  = D(p) / D0(p) - 1                               (0 where p is invalid)
//
// K is a Gaussian exp(-r^2 / 2 sigma^2) lowered by its value at the cut-off r_c = 3 sigma and
// rescaled to K(0) = 1, so it falls continuously to 0 at r_c (a hard cut would make G jump by
// ~0.2 % whenever a point crosses r_c). G depends only on differences of displacements, so a
// uniform shift gives exactly G = 0 (bit-exact: the same integer distances hit the same LUT
// entries). Local expansion spreads the points: D < D0 and G < 0 (height -G > 0); compression
// gives G > 0. For a uniform scaling x -> s x every interior point gets the lattice value
// sum_o K(s|o|) / sum_o K(|o|) - 1, within 3 % of the continuum 1/s^2 - 1 at sigma = 1 cell
// (e.g. s = 1.05: -0.0913 vs -0.0930), i.e. G ~ -2 e for a small linear strain e per axis.
struct DensityConfig {
  // Kernel standard deviation in grid cells (1 cell = 4 working px). Range [0.5, 2]. Below ~1
  // cell the kernel resolves the individual grid points and G stops being a smooth function of
  // sub-cell relative displacements; above, resolution and cost (~sigma^2 pairs) suffer.
  double sigma_cells = 1.0;
};

inline constexpr double kMinDensitySigmaCells = 0.5;
inline constexpr double kMaxDensitySigmaCells = 2.0;

namespace detail {
// A neighbour offset of the pair loop (GaussianDensity, density_simd.cpp).
struct DensityOffset {
  std::int32_t ox = 0;  // grid cells
  std::int32_t oy = 0;
  std::int32_t k0 = 0;  // Q15 kernel at the undeformed distance
};
}  // namespace detail

// Scaling and overflow:
//  - input u: Q16 working px (any int32). Converted once per call to Q10 (round half-up, clamped
//    to +-2^20 = +-1024 px, beyond the 160 px image so the clamp never changes a real distance).
//  - pair distance components dx, dy: Q10 int32 (|.| <= 2^21 + offset), then clamped to +-c with
//    c = ceil(r_c) (12288 = 12 px at sigma 1, <= 24576): a clamped pair is beyond r_c either way,
//    so only zero-weight pairs are affected.
//  - r^2 = dx^2 + dy^2: Q20 px^2 in int32, <= 2 c^2 < 2^31.
//  - LUT: K at r^2 = i * 2^k for i in [0, 2N], Q15 (K(0) = 32768), N = ceil(c^2 / 2^k) <= 4096 with
//    the smallest such k (k = 16, N = 2304 at sigma 1), 0 from the cut-off on, so the index
//    r^2 >> k never needs a clamp. Each entry packs K_i and K_i - K_{i+1} (< 2^15) for linear
//    interpolation on the top 15 bits of the remainder (product < 2^30), round half-up.
//  - D, D0: int32 sums of Q15 terms (<= kMaxOffsets * 2^15 < 2^23).
//  - output G: Q16 int32, (D - D0) * R >> 30 rounded half-up in int64, with R = round(2^46 / D0)
//    cached per mask (D0 >= 2^15 for a valid point, so R <= 2^31 and |product| < 2^53). Within
//    1 LSB of the exactly rounded quotient; exactly 0 when D == D0. Range [-1, kMaxOffsets), no
//    saturation needed.
class GaussianDensity {
 public:
  static constexpr int kMaxOffsets = 160;   // neighbour offsets within 3 sigma + 0.5 cells
  static constexpr int kMaxLutHalf = 4096;  // N: LUT entries up to the cut-off
  static constexpr int kMaxLut = 2 * kMaxLutHalf + 1;  // entries 0 .. 2N (r^2 <= 2 c^2)
  static constexpr int kWorkFrac = 10;                 // Q10 working px for distances
  static constexpr int kKernelFrac = 15;               // Q15 kernel values

  GaussianDensity() noexcept;  // default DensityConfig

  // Builds the offset list and the LUT (double maths at init time). Out-of-range/NaN sigma returns
  // kBadArgument and keeps the previous configuration.
  Status configure(const DensityConfig& config) noexcept;

  // g = G(p) in Q16 for every valid p, 0 for invalid p. Cost: O(kGridCount * offsets / 2)
  // (each unordered pair is evaluated once and added to both points). `g` must not alias the
  // inputs' storage (it is a different type anyway). The pair loop runs on the best SIMD target
  // (simd.hpp).
  void compute(const VectorField& displacement, const GridMask& valid, ScalarField& g) noexcept;

  // The scalar path of compute: the same result, bit for bit, with kernel_of per pair (tests,
  // benchmarks).
  void compute_scalar(const VectorField& displacement, const GridMask& valid,
                      ScalarField& g) noexcept;

  const DensityConfig& config() const noexcept { return config_; }
  // Kernel value in Q15 at distance r (working px), through the same integer LUT path as the
  // per-pair evaluation (r rounded to Q10). For tests and docs.
  std::int32_t kernel_q15(double r_px) const noexcept;
  // The per-pair kernel from Q10 distance components (each clamped to +-c, c = ceil(r_c)).
  std::int32_t kernel_of(std::int32_t dx_q10, std::int32_t dy_q10) const noexcept;
  // Number of unordered neighbour offsets (excluding the point itself).
  int pair_offsets() const noexcept { return num_offsets_; }
  // Undeformed and deformed densities of the last call (Q15 sums), for tests and diagnostics.
  const GridArray<std::int32_t>& density() const noexcept { return density_; }
  const GridArray<std::int32_t>& density_undeformed() const noexcept { return density0_; }

 private:
  using Offset = detail::DensityOffset;
  DensityConfig config_{};
  int lut_shift_ = 0;                 // LUT step is 2^lut_shift_ in Q20 px^2
  std::int32_t component_limit_ = 0;  // c = ceil(r_c) in Q10
  int num_offsets_ = 0;
  std::array<std::int32_t, kMaxLut> lut_{};
  std::array<Offset, kMaxOffsets / 2> offsets_{};
  void update_undeformed(const GridMask& valid) noexcept;
  void compute_with(bool simd, const VectorField& displacement, const GridMask& valid,
                    ScalarField& g) noexcept;
  template <bool kMasked>
  void accumulate_pairs_scalar() noexcept;

  GridArray<std::int32_t> ux_{};  // Q10 displacements of the current call
  GridArray<std::int32_t> uy_{};
  GridArray<std::int32_t> lane_mask_{};  // -1 valid, 0 invalid (for branch-free SIMD masking)
  GridArray<std::int32_t> density_{};
  // D0 and 2^46 / D0 depend only on the mask: recomputed when the mask or the config changes.
  GridArray<std::int32_t> density0_{};
  GridArray<std::int64_t> inv_density0_{};
  GridMask cached_mask_{};
  bool undeformed_ready_ = false;
};

}  // namespace tacse3::dsp
