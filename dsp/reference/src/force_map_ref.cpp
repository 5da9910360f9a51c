// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: double-precision force maps (𝒢, d, r, k) → f^z and shear.
#include "tacse3/dsp_ref/force_map_ref.hpp"

#include "tacse3/dsp/fixed.hpp"

namespace tacse3::dsp_ref {
namespace {

using dsp::kGridCount;
using dsp::kGridHeight;
using dsp::kGridWidth;

double q16(std::int32_t raw) {
  return dsp::from_q<dsp::kFieldFrac>(raw);
}

bool ok(const dsp::GridMask& m, int gx, int gy) {
  return gx >= 0 && gx < kGridWidth && gy >= 0 && gy < kGridHeight && m(gx, gy) != 0;
}

double derivative(const dsp::GridArray<std::int32_t>& c, const dsp::GridMask& m, int gx, int gy,
                  int dx, int dy) {
  const double step = dsp::kGridStride;  // working px between grid points
  const bool lo = ok(m, gx - dx, gy - dy), hi = ok(m, gx + dx, gy + dy);
  if (lo && hi) return (q16(c(gx + dx, gy + dy)) - q16(c(gx - dx, gy - dy))) / (2.0 * step);
  if (hi) return (q16(c(gx + dx, gy + dy)) - q16(c(gx, gy))) / step;
  if (lo) return (q16(c(gx, gy)) - q16(c(gx - dx, gy - dy))) / step;
  return 0.0;
}

}  // namespace

std::vector<double> grid_divergence_ref(const dsp::VectorField& v, const dsp::GridMask& valid) {
  std::vector<double> out(static_cast<std::size_t>(kGridCount), 0.0);
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      if (valid(gx, gy) == 0) continue;
      out[static_cast<std::size_t>(gy * kGridWidth + gx)] =
          derivative(v.x, valid, gx, gy, 1, 0) + derivative(v.y, valid, gx, gy, 0, 1);
    }
  }
  return out;
}

ForceFieldsRef force_map_ref(const dsp::Calibration& cal, const dsp::ScalarField& density,
                             const dsp::VectorField& d, const dsp::VectorField& r,
                             const dsp::VectorField& k, const dsp::GridMask& valid) {
  const auto n = static_cast<std::size_t>(kGridCount);
  ForceFieldsRef out{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0),
                     std::vector<double>(n, 0.0)};
  const std::vector<double> div = grid_divergence_ref(d, valid);
  for (std::size_t i = 0; i < n; ++i) {
    if (valid.v[i] == 0) continue;
    out.fz[i] = cal.normal_gain_density * -q16(density.v[i]) + cal.normal_gain_divergence * div[i];
    out.fx[i] = cal.shear_gain_d * q16(d.x.v[i]) + cal.shear_gain_r * q16(r.x.v[i]) +
                cal.shear_gain_k * q16(k.x.v[i]);
    out.fy[i] = cal.shear_gain_d * q16(d.y.v[i]) + cal.shear_gain_r * q16(r.y.v[i]) +
                cal.shear_gain_k * q16(k.y.v[i]);
  }
  return out;
}

}  // namespace tacse3::dsp_ref
