// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: separable Gaussian smoothing of the grid flow by normalised convolution.
#pragma once

#include <array>
#include <cstdint>

#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Paper Sec. IV-B: the dense planar flow w(m) of Eq. (dense_flow) "is smoothed with an isotropic
// Gaussian kernel of covariance sigma^2 I". The grid flow is smoothed here, before the Gaussian
// density (density.hpp) and the NHHD (nhhd.hpp, Eq. (nhhd)).
struct SmoothingConfig {
  // Standard deviation of the Gaussian in grid cells (1 cell = kGridStride = 4 working px).
  // Valid range [kMinSigmaCells, kMaxSigmaCells]. 1.0 removes the block-flow noise without blurring
  // a contact (a few cells wide) away.
  double sigma_cells = 1.0;
  // An output sample is valid when the valid input points under the kernel carry at least this
  // fraction of the full kernel mass (range (0, 1]). 0.25 keeps every valid point whose own
  // neighbourhood is mostly valid (a grid corner keeps 0.49 of the mass) and fills an invalid
  // point surrounded by valid ones (0.84), but drops an isolated valid point (0.16 at sigma 1).
  double min_support = 0.25;
};

inline constexpr double kMinSigmaCells = 0.3;
inline constexpr double kMaxSigmaCells = 3.0;

// Normalised convolution (Knutsson & Westin): with m the validity mask and g the Gaussian,
//   out = (g * (m w)) / (g * m),  support = (g * m) / (g * 1_infinite)
// both computed separably (rows, then columns). Invalid points and points outside the grid carry
// zero weight, so they are ignored instead of being treated as zero displacement.
//
// Edge handling: the grid is NOT extended (no zero padding, no mirroring). Near an edge the kernel
// is truncated and renormalised by the mass that remains, exactly as around an invalid point; an
// edge sample is therefore the weighted mean of the valid samples around it and is not pulled
// towards zero. Consequence: a field that is affine across the kernel support is reproduced exactly
// in the interior but only to first order at an edge (the one-sided mean of a slope is biased by
// the slope times the centroid offset of the truncated kernel, 0.52 cells at sigma 1).
//
// Scaling and overflow (Q formats, see fixed.hpp):
//  - input  w: Q16 int32 (any value, full int32 range accepted), mask 0/1 (non-zero = valid).
//  - taps  g_i: Q15, positive, symmetric, sum exactly 2^15 (the centre tap absorbs the rounding),
//    radius R = min(ceil(3 sigma), kMaxRadius); taps that would round to 0 shorten R.
//  - row pass: sum_i g_i m w in int64 (|.| <= 2^15 * 2^31 = 2^46), weight sum_i g_i m in int32
//    (<= 2^15).
//  - column pass: int64 numerator (|.| <= 2^61), int64 weight (<= 2^30, = 2^30 exactly when the
//    whole support is valid and inside the grid).
//  - output = round_half_up(numerator / weight), a convex combination of inputs, so it never leaves
//    the input range and needs no saturation (a final sat32 guards the invariant). In the fully
//    supported case the division is an exact shift by 30 with the same rounding.
//  - support threshold: weight >= round(min_support * 2^30), else output 0 and invalid.
// Exactness: a constant field is reproduced bit-exactly wherever the output is valid.
class FlowSmoother {
 public:
  static constexpr int kMaxRadius = 9;
  static constexpr int kTapFrac = 15;

  FlowSmoother() noexcept;  // default SmoothingConfig

  // Precomputes the Q15 taps (double maths, init time only). Out-of-range or NaN values return
  // kBadArgument and leave the previous configuration in place.
  Status configure(const SmoothingConfig& config) noexcept;

  // Smooths `in` over the valid points. `out` may alias `in` and `out_valid` may alias `valid`
  // (the rows are buffered internally). Cost: O(kGridCount * (2R+1)), no allocation.
  // Runs on the best SIMD target (simd.hpp).
  void apply(const VectorField& in, const GridMask& valid, VectorField& out,
             GridMask& out_valid) noexcept;

  // The scalar path of apply: the same result, bit for bit (tests, benchmarks).
  void apply_scalar(const VectorField& in, const GridMask& valid, VectorField& out,
                    GridMask& out_valid) noexcept;

  const SmoothingConfig& config() const noexcept { return config_; }
  int radius() const noexcept { return radius_; }
  // Tap i (|i| <= radius()) in Q15.
  std::int32_t tap(int i) const noexcept;

 private:
  SmoothingConfig config_{};
  int radius_ = 0;
  std::int64_t min_weight_ = 0;                      // Q30
  std::array<std::int32_t, kMaxRadius + 1> taps_{};  // taps_[|i|], Q15
  std::array<std::int32_t, kGridWidth> edge_wx_{};   // in-grid kernel mass per column, Q15
  std::array<std::int32_t, kGridHeight> edge_wy_{};  // in-grid kernel mass per row, Q15
  // Masked copies of the input (value, or 0 where invalid; weight 1/0) and the row-pass results,
  // kept between the passes (and so `out` may alias `in`).
  std::array<std::int32_t, kGridCount> masked_x_{};
  std::array<std::int32_t, kGridCount> masked_y_{};
  std::array<std::int32_t, kGridCount> masked_w_{};
  std::array<std::int64_t, kGridCount> row_x_{};
  std::array<std::int64_t, kGridCount> row_y_{};
  std::array<std::int32_t, kGridCount> row_w_{};

  // The SIMD path (smoothing_simd.cpp): the masked input with kMaxRadius zero columns either side,
  // the row sums split into 16-bit halves with kMaxRadius zero rows above and below (the zero
  // margins are never written); its numerators and weights go to row_x_, row_y_, row_w_.
  static constexpr int kPadWidth = kGridWidth + 2 * kMaxRadius;
  static constexpr int kPadHeight = kGridHeight + 2 * kMaxRadius;
  std::array<std::int32_t, kGridHeight * kPadWidth> pad_x_{};
  std::array<std::int32_t, kGridHeight * kPadWidth> pad_y_{};
  std::array<std::int32_t, kGridHeight * kPadWidth> pad_w_{};
  std::array<std::int32_t, kPadHeight * kGridWidth> hi_x_{};
  std::array<std::int32_t, kPadHeight * kGridWidth> lo_x_{};
  std::array<std::int32_t, kPadHeight * kGridWidth> hi_y_{};
  std::array<std::int32_t, kPadHeight * kGridWidth> lo_y_{};
  std::array<std::int32_t, kPadHeight * kGridWidth> sum_w_{};
};

}  // namespace tacse3::dsp
