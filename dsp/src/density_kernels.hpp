// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp (private): the SIMD pair accumulation of GaussianDensity (density_simd.cpp).
#pragma once

#include <cstdint>

#include "tacse3/dsp/density.hpp"

namespace tacse3::dsp::detail {

// Inputs and output of density_pairs_simd, all owned by GaussianDensity.
struct DensityPairs {
  const std::int32_t* lut = nullptr;  // packed K_i | (K_i - K_{i+1}) << 16
  int lut_shift = 0;                  // LUT step 2^lut_shift in Q20 px^2
  std::int32_t limit = 0;             // c: distance components clamped to +-c (Q10)
  const DensityOffset* offsets = nullptr;
  int num_offsets = 0;
  const std::int32_t* ux = nullptr;  // Q10 displacements, kGridCount
  const std::int32_t* uy = nullptr;
  const std::int32_t* lane_mask = nullptr;  // -1 valid, 0 invalid; nullptr: every point valid
  std::int32_t* density = nullptr;          // D, accumulated in place
};

// D(p) += K(p, q) and D(q) += K(p, q) for every unordered pair (p, q = p + offset): the same
// integers as GaussianDensity::kernel_of per pair (the scalar path).
void density_pairs_simd(const DensityPairs& s) noexcept;

}  // namespace tacse3::dsp::detail
