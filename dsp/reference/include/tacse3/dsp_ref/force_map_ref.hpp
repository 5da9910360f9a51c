// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: double-precision force maps (𝒢, d, r, k) → f^z and shear.
#pragma once

#include <vector>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp_ref {

// Inputs are the fixed-point pipeline's own Q16 fields (exact in double), so a comparison
// isolates the arithmetic of the stage. Outputs are real values (f^z units, shear units),
// row-major like the grid.
struct ForceFieldsRef {
  std::vector<double> fz;
  std::vector<double> fx;
  std::vector<double> fy;
};

// Same rule as dsp::grid_divergence (central / one-sided / zero), in double.
std::vector<double> grid_divergence_ref(const dsp::VectorField& v, const dsp::GridMask& valid);

ForceFieldsRef force_map_ref(const dsp::Calibration& cal, const dsp::ScalarField& density,
                             const dsp::VectorField& d, const dsp::VectorField& r,
                             const dsp::VectorField& k, const dsp::GridMask& valid);

}  // namespace tacse3::dsp_ref
