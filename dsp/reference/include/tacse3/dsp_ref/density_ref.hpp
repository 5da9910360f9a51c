// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: Gaussian density map G in double precision.
#pragma once

#include "tacse3/dsp/density.hpp"
#include "tacse3/dsp_ref/smoothing_ref.hpp"

namespace tacse3::dsp_ref {

// The density kernel of dsp::GaussianDensity in double: exp(-r^2 / 2 sigma^2) lowered by its value
// at r_c = 3 sigma, rescaled to K(0) = 1, and 0 from r_c on. r and sigma in working px.
double density_kernel_ref(double r_px, double sigma_px);

// G(p) = D(p) / D0(p) - 1 over the same neighbour offsets as the firmware (|o| <= 3 sigma + 0.5
// cells), valid points only, 0 at invalid points; exact kernel, no quantisation.
GridScalarD gaussian_density_ref(const GridVectorD& displacement, const GridMaskD& valid,
                                 const dsp::DensityConfig& config);

// G of an infinite lattice under a uniform scaling x -> s x (every point has the same G):
// sum_o K(s |o|) / sum_o K(|o|) - 1 over ALL lattice offsets with s |o| < r_c. The analytic value
// the interior of the grid must reproduce; ~ 1/s^2 - 1.
double density_uniform_scaling_ref(double s, const dsp::DensityConfig& config);

}  // namespace tacse3::dsp_ref
