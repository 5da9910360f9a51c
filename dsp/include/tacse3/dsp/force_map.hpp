// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: calibrated linear maps (𝒢, d, r, k) → normal response f^z and shear (f^x, f^y).
#pragma once

#include <cstdint>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Divergence of a grid vector field, dimensionless (working px per working px).
// Central differences over 2 grid steps (8 working px) where both neighbours are valid, one-sided
// differences over 1 step (4 working px) at the border or next to an invalid neighbour, 0 for an
// axis with no valid neighbour and for invalid points.
// Scaling and overflow: v is Q16 working px (any int32); the differences are formed in int64,
// scaled to Q16/8 and shifted right by 3 with round-half-up; the result saturates to int32 (only
// reachable for |v| near 2^31). Output Q16.
void grid_divergence(const VectorField& v, const GridMask& valid, ScalarField& div) noexcept;

// Paper Sec. IV-B: "calibrated linear maps from 𝒢, d, r, k then yield spatial distributions of
// normal and shear force" (after Eq. nhhd):
//   f^z   = a_G · (−𝒢) + a_div · div(d)
//   shear = s_d · d + s_r · r + s_k · k
// Gains come from Calibration and are converted to Q16 once in configure().
class ForceMap {
 public:
  ForceMap() noexcept;  // configured with Calibration{} defaults

  // kBadCalibration (and the previous gains are kept) if validate(cal) fails.
  Status configure(const Calibration& cal) noexcept;

  // Scaling and overflow: density, d, r, k are Q16 (int32); gains are Q16 in [0, 1e4]
  // (|raw| < 2^30). Each gain·input product is exact in int64 (< 2^61), the up-to-three products
  // are summed in int64 (< 2^63), then shifted right by 16 with round-half-up and saturated to
  // int32. Outputs: fz Q16 f^z units, shear Q16 shear units (working px for unit gains).
  // Invalid points (valid == 0) get fz = 0 and shear = 0, i.e. never contact.
  // fz and shear must not alias any input (fz is used as scratch for div(d)).
  void compute(const ScalarField& density, const VectorField& d, const VectorField& r,
               const VectorField& k, const GridMask& valid, ScalarField& fz,
               VectorField& shear) const noexcept;

  std::int32_t normal_gain_density_q16() const noexcept { return a_density_; }
  std::int32_t normal_gain_divergence_q16() const noexcept { return a_div_; }

 private:
  std::int32_t a_density_ = 0;
  std::int32_t a_div_ = 0;
  std::int32_t s_d_ = 0;
  std::int32_t s_r_ = 0;
  std::int32_t s_k_ = 0;
};

}  // namespace tacse3::dsp
