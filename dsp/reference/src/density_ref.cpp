// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: Gaussian density map G in double precision.
#include "tacse3/dsp_ref/density_ref.hpp"

#include <cmath>
#include <cstddef>

namespace tacse3::dsp_ref {

using dsp::kGridHeight;
using dsp::kGridStride;
using dsp::kGridWidth;

double density_kernel_ref(double r_px, double sigma_px) {
  const double t = 0.5 * r_px * r_px / (sigma_px * sigma_px);
  const double t_cut = 4.5;  // (3 sigma)^2 / 2 sigma^2
  if (t >= t_cut) return 0.0;
  const double k_cut = std::exp(-t_cut);
  return (std::exp(-t) - k_cut) / (1.0 - k_cut);
}

GridScalarD gaussian_density_ref(const GridVectorD& u, const GridMaskD& valid,
                                 const dsp::DensityConfig& config) {
  const double sigma_px = config.sigma_cells * kGridStride;
  const double reach = 3.0 * config.sigma_cells + 0.5;
  const int rmax = static_cast<int>(std::floor(reach));
  GridScalarD g(dsp::kGridCount, 0.0);
  for (int y = 0; y < kGridHeight; ++y) {
    for (int x = 0; x < kGridWidth; ++x) {
      const std::size_t p = static_cast<std::size_t>(y * kGridWidth + x);
      if (valid[p] == 0) continue;
      double dens = 0.0;
      double dens0 = 0.0;
      for (int oy = -rmax; oy <= rmax; ++oy) {
        for (int ox = -rmax; ox <= rmax; ++ox) {
          if (ox * ox + oy * oy > reach * reach) continue;
          const int qx = x + ox;
          const int qy = y + oy;
          if (qx < 0 || qy < 0 || qx >= kGridWidth || qy >= kGridHeight) continue;
          const std::size_t q = static_cast<std::size_t>(qy * kGridWidth + qx);
          if (valid[q] == 0) continue;
          const double bx = ox * kGridStride;
          const double by = oy * kGridStride;
          dens0 += density_kernel_ref(std::hypot(bx, by), sigma_px);
          dens +=
              density_kernel_ref(std::hypot(bx + u.x[q] - u.x[p], by + u.y[q] - u.y[p]), sigma_px);
        }
      }
      g[p] = dens / dens0 - 1.0;
    }
  }
  return g;
}

double density_uniform_scaling_ref(double s, const dsp::DensityConfig& config) {
  const double sigma_px = config.sigma_cells * kGridStride;
  const int rmax = static_cast<int>(std::ceil(3.0 * config.sigma_cells / std::fmin(s, 1.0))) + 1;
  double dens = 0.0;
  double dens0 = 0.0;
  for (int oy = -rmax; oy <= rmax; ++oy) {
    for (int ox = -rmax; ox <= rmax; ++ox) {
      const double r = std::hypot(ox * kGridStride, oy * kGridStride);
      dens0 += density_kernel_ref(r, sigma_px);
      dens += density_kernel_ref(s * r, sigma_px);
    }
  }
  return dens / dens0 - 1.0;
}

}  // namespace tacse3::dsp_ref
