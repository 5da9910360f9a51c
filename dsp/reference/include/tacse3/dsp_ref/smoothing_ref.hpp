// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: double-precision grid fields and Gaussian smoothing of the flow.
#pragma once

#include <cstdint>
#include <vector>

#include "tacse3/dsp/smoothing.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp_ref {

// A grid vector field in double, row-major (gy * kGridWidth + gx), same units as the Q16 fields
// (working px). Shared by the smoothing, density and NHHD references.
struct GridVectorD {
  std::vector<double> x = std::vector<double>(dsp::kGridCount, 0.0);
  std::vector<double> y = std::vector<double>(dsp::kGridCount, 0.0);
};
using GridScalarD = std::vector<double>;
using GridMaskD = std::vector<std::uint8_t>;  // 0 / 1, row-major

// Conversions between the Q16 firmware fields and the double fields.
GridVectorD grid_vector_from_q16(const dsp::VectorField& f);
GridScalarD grid_scalar_from_q16(const dsp::ScalarField& f);
GridMaskD grid_mask_from(const dsp::GridMask& m);
// Rounds to nearest and saturates (test inputs are built in double, then quantised).
dsp::VectorField grid_vector_to_q16(const GridVectorD& f);
dsp::GridMask grid_mask_to(const GridMaskD& m);

// Normalised Gaussian convolution, the same maths as dsp::FlowSmoother in double: exact Gaussian
// taps normalised to sum 1 over the same radius, invalid points and points outside the grid carry
// zero weight, output = weighted mean where the weight >= min_support, else 0 and invalid.
// The radius is the firmware's (dsp::FlowSmoother{config}.radius()) so both truncate identically.
void smooth_ref(const GridVectorD& in, const GridMaskD& valid, const dsp::SmoothingConfig& config,
                GridVectorD& out, GridMaskD& out_valid);

}  // namespace tacse3::dsp_ref
