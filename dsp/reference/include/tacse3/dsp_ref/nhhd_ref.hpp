// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: NHHD in double (same V-cycle Jacobi scheme) and the free-space Green's
// function decomposition it approximates.
#pragma once

#include <array>
#include <vector>

#include "tacse3/dsp/nhhd.hpp"
#include "tacse3/dsp_ref/smoothing_ref.hpp"

namespace tacse3::dsp_ref {

// Sources of Eq. (nhhd) exactly as dsp::Nhhd forms them (before quantisation): div w and curl w
// from differences between valid points (central / one-sided / none), 0 at invalid points.
void nhhd_sources_ref(const GridVectorD& w, const GridMaskD& valid, GridScalarD& div,
                      GridScalarD& curl);

// dsp::Nhhd in double: same padded levels, multipole (or zero) ring, damped Jacobi V-cycles,
// warm start, d = grad phi, r = grad-perp psi, k = w - d - r. No rounding, no saturation.
class NhhdRef {
 public:
  explicit NhhdRef(const dsp::NhhdConfig& config = {});
  void reset();
  void decompose(const GridVectorD& w, const GridMaskD& valid, GridVectorD& d, GridVectorD& r,
                 GridVectorD& k);
  // Potentials at a grid point (px * cell).
  double phi(int gx, int gy) const;
  double psi(int gx, int gy) const;

 private:
  struct Level {
    int nx = 0;
    int ny = 0;
    std::vector<double> u;
    std::vector<double> tmp;
    std::vector<double> f;
  };
  using Potential = std::array<Level, dsp::kNhhdMaxLevels>;
  void set_ring(Potential& p, const GridScalarD& src);
  void solve(Potential& p);
  void sweeps(Level& lv, int count, bool damped);

  dsp::NhhdConfig config_;
  Potential phi_;
  Potential psi_;
};

// The natural HHD by the free-space Green's function G = ln(r) / 2 pi on the same discrete
// sources (nhhd_sources_ref): phi = G * div w, psi = G * curl w as sums over the grid cells
// (unit area), and d, r from the analytic gradient of G,
//   d(x) = sum_y (x - y) / (2 pi |x - y|^2) div w(y),   r(x) = perp of the same sum over curl w,
// the y = x term being 0 by symmetry. k = w - d - r. O(kGridCount^2); tests only.
void green_decompose_ref(const GridVectorD& w, const GridMaskD& valid, GridVectorD& d,
                         GridVectorD& r, GridVectorD& k);

}  // namespace tacse3::dsp_ref
