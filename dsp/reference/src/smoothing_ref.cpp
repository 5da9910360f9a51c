// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: double-precision grid fields and Gaussian smoothing of the flow.
#include "tacse3/dsp_ref/smoothing_ref.hpp"

#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <utility>

#include "tacse3/dsp/fixed.hpp"

namespace tacse3::dsp_ref {

using dsp::kGridCount;
using dsp::kGridHeight;
using dsp::kGridWidth;

GridVectorD grid_vector_from_q16(const dsp::VectorField& f) {
  GridVectorD out;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    out.x[i] = dsp::from_q<dsp::kFieldFrac>(f.x.v[i]);
    out.y[i] = dsp::from_q<dsp::kFieldFrac>(f.y.v[i]);
  }
  return out;
}

GridScalarD grid_scalar_from_q16(const dsp::ScalarField& f) {
  GridScalarD out(kGridCount);
  for (std::size_t i = 0; i < kGridCount; ++i) out[i] = dsp::from_q<dsp::kFieldFrac>(f.v[i]);
  return out;
}

GridMaskD grid_mask_from(const dsp::GridMask& m) {
  GridMaskD out(kGridCount);
  for (std::size_t i = 0; i < kGridCount; ++i) out[i] = m.v[i] != 0 ? 1 : 0;
  return out;
}

dsp::VectorField grid_vector_to_q16(const GridVectorD& f) {
  dsp::VectorField out;
  for (std::size_t i = 0; i < kGridCount; ++i) {
    out.x.v[i] = dsp::to_q32<dsp::kFieldFrac>(f.x[i]);
    out.y.v[i] = dsp::to_q32<dsp::kFieldFrac>(f.y[i]);
  }
  return out;
}

dsp::GridMask grid_mask_to(const GridMaskD& m) {
  dsp::GridMask out;
  for (std::size_t i = 0; i < kGridCount; ++i) out.v[i] = m[i] != 0 ? 1 : 0;
  return out;
}

void smooth_ref(const GridVectorD& in, const GridMaskD& valid, const dsp::SmoothingConfig& config,
                GridVectorD& out, GridMaskD& out_valid) {
  dsp::FlowSmoother firmware;
  (void)firmware.configure(config);
  const int radius = firmware.radius();
  const double sigma = config.sigma_cells;
  std::vector<double> g(static_cast<std::size_t>(radius) + 1);
  double sum = 0.0;
  for (int i = 0; i <= radius; ++i) {
    g[static_cast<std::size_t>(i)] = std::exp(-0.5 * i * i / (sigma * sigma));
    sum += (i == 0 ? 1.0 : 2.0) * g[static_cast<std::size_t>(i)];
  }
  for (double& v : g) v /= sum;

  GridVectorD res;
  GridMaskD res_valid(kGridCount, 0);
  for (int y = 0; y < kGridHeight; ++y) {
    for (int x = 0; x < kGridWidth; ++x) {
      double nx = 0.0;
      double ny = 0.0;
      double wt = 0.0;
      for (int j = -radius; j <= radius; ++j) {
        for (int i = -radius; i <= radius; ++i) {
          const int qx = x + i;
          const int qy = y + j;
          if (qx < 0 || qy < 0 || qx >= kGridWidth || qy >= kGridHeight) continue;
          const std::size_t q = static_cast<std::size_t>(qy * kGridWidth + qx);
          if (valid[q] == 0) continue;
          const double k =
              g[static_cast<std::size_t>(std::abs(i))] * g[static_cast<std::size_t>(std::abs(j))];
          nx += k * in.x[q];
          ny += k * in.y[q];
          wt += k;
        }
      }
      const std::size_t p = static_cast<std::size_t>(y * kGridWidth + x);
      if (wt >= config.min_support && wt > 0.0) {
        res.x[p] = nx / wt;
        res.y[p] = ny / wt;
        res_valid[p] = 1;
      }
    }
  }
  out = std::move(res);
  out_valid = std::move(res_valid);
}

}  // namespace tacse3::dsp_ref
