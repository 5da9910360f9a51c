// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: NHHD in double (same V-cycle Jacobi scheme) and the free-space Green's
// function decomposition it approximates.
#include "tacse3/dsp_ref/nhhd_ref.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <numbers>
#include <utility>

namespace tacse3::dsp_ref {
namespace {

using dsp::kGridCount;
using dsp::kGridHeight;
using dsp::kGridWidth;

constexpr int kOriginX = dsp::kNhhdPadLeft + 1;
constexpr int kOriginY = dsp::kNhhdPadTop + 1;

// Derivative along one axis from valid neighbours only, as in dsp::Nhhd (there it is doubled).
double derivative(const std::vector<double>& f, const GridMaskD& valid, std::size_t p,
                  std::size_t step, bool has_prev, bool has_next) {
  const bool prev = has_prev && valid[p - step] != 0;
  const bool next = has_next && valid[p + step] != 0;
  if (prev && next) return 0.5 * (f[p + step] - f[p - step]);
  if (next) return f[p + step] - f[p];
  if (prev) return f[p] - f[p - step];
  return 0.0;
}

}  // namespace

void nhhd_sources_ref(const GridVectorD& w, const GridMaskD& valid, GridScalarD& div,
                      GridScalarD& curl) {
  div.assign(kGridCount, 0.0);
  curl.assign(kGridCount, 0.0);
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const std::size_t p = static_cast<std::size_t>(gy * kGridWidth + gx);
      if (valid[p] == 0) continue;
      const bool west = gx > 0;
      const bool east = gx + 1 < kGridWidth;
      const bool north = gy > 0;
      const bool south = gy + 1 < kGridHeight;
      const std::size_t row = kGridWidth;
      const double dxx = derivative(w.x, valid, p, 1, west, east);
      const double dxy = derivative(w.y, valid, p, 1, west, east);
      const double dyx = derivative(w.x, valid, p, row, north, south);
      const double dyy = derivative(w.y, valid, p, row, north, south);
      div[p] = dxx + dyy;
      curl[p] = dxy - dyx;
    }
  }
}

NhhdRef::NhhdRef(const dsp::NhhdConfig& config) : config_(config) {
  for (Potential* p : {&phi_, &psi_}) {
    for (int l = 0; l < dsp::kNhhdMaxLevels; ++l) {
      Level& lv = (*p)[static_cast<std::size_t>(l)];
      lv.nx = dsp::kNhhdLevelNx[static_cast<std::size_t>(l)];
      lv.ny = dsp::kNhhdLevelNy[static_cast<std::size_t>(l)];
      const std::size_t n = static_cast<std::size_t>((lv.nx + 2) * (lv.ny + 2));
      lv.u.assign(n, 0.0);
      lv.tmp.assign(n, 0.0);
      lv.f.assign(n, 0.0);
    }
  }
}

void NhhdRef::reset() {
  for (Potential* p : {&phi_, &psi_}) {
    for (Level& lv : *p) {
      std::fill(lv.u.begin(), lv.u.end(), 0.0);
      std::fill(lv.tmp.begin(), lv.tmp.end(), 0.0);
      std::fill(lv.f.begin(), lv.f.end(), 0.0);
    }
  }
}

double NhhdRef::phi(int gx, int gy) const {
  const Level& lv = phi_[0];
  return lv.u[static_cast<std::size_t>((gy + kOriginY) * (lv.nx + 2) + gx + kOriginX)];
}
double NhhdRef::psi(int gx, int gy) const {
  const Level& lv = psi_[0];
  return lv.u[static_cast<std::size_t>((gy + kOriginY) * (lv.nx + 2) + gx + kOriginX)];
}

void NhhdRef::set_ring(Potential& p, const GridScalarD& src) {
  // Free-space potential truncated after the quadrupole: (1/2pi)[M0 ln|z| - Re(M1/z) -
  // Re(M2/z^2)/2] about the grid centre.
  std::complex<double> m1 = 0.0;
  std::complex<double> m2 = 0.0;
  double m0 = 0.0;
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const double s = src[static_cast<std::size_t>(gy * kGridWidth + gx)];
      const std::complex<double> z(gx - dsp::kNhhdCentreX, gy - dsp::kNhhdCentreY);
      m0 += s;
      m1 += s * z;
      m2 += s * z * z;
    }
  }
  Level& lv = p[0];
  const int s = lv.nx + 2;
  const double pi = std::numbers::pi;
  for (int j = 0; j <= lv.ny + 1; ++j) {
    for (int i = 0; i <= lv.nx + 1; ++i) {
      if (j != 0 && j != lv.ny + 1 && i != 0 && i != lv.nx + 1) continue;
      double v = 0.0;
      if (config_.far_boundary == dsp::NhhdFarBoundary::kMultipole) {
        const std::complex<double> z((i - kOriginX) - dsp::kNhhdCentreX,
                                     (j - kOriginY) - dsp::kNhhdCentreY);
        v = (m0 * std::log(std::abs(z)) - (m1 / z).real() - 0.5 * (m2 / (z * z)).real()) /
            (2.0 * pi);
      }
      lv.u[static_cast<std::size_t>(j * s + i)] = v;
      lv.tmp[static_cast<std::size_t>(j * s + i)] = v;
    }
  }
}

void NhhdRef::sweeps(Level& lv, int count, bool damped) {
  const int s = lv.nx + 2;
  for (int n = 0; n < count; ++n) {
    for (int j = 1; j <= lv.ny; ++j) {
      for (int i = 1; i <= lv.nx; ++i) {
        const std::size_t q = static_cast<std::size_t>(j * s + i);
        const double t = 0.25 * (lv.u[q - 1] + lv.u[q + 1] + lv.u[q - static_cast<std::size_t>(s)] +
                                 lv.u[q + static_cast<std::size_t>(s)] - lv.f[q]);
        lv.tmp[q] = damped ? lv.u[q] + 0.75 * (t - lv.u[q]) : t;
      }
    }
    std::swap(lv.u, lv.tmp);
  }
}

void NhhdRef::solve(Potential& p) {
  const int levels = config_.levels;
  for (int c = 0; c < config_.cycles; ++c) {
    if (levels == 1) {
      sweeps(p[0], config_.coarsest_sweeps, false);
      continue;
    }
    for (int l = 0; l + 1 < levels; ++l) {
      Level& fine = p[static_cast<std::size_t>(l)];
      Level& coarse = p[static_cast<std::size_t>(l) + 1];
      sweeps(fine, config_.pre_sweeps, true);
      const int s = fine.nx + 2;
      std::vector<double> res(fine.u.size(), 0.0);
      for (int j = 1; j <= fine.ny; ++j) {
        for (int i = 1; i <= fine.nx; ++i) {
          const std::size_t q = static_cast<std::size_t>(j * s + i);
          const std::size_t ss = static_cast<std::size_t>(s);
          res[q] = fine.f[q] - (fine.u[q - 1] + fine.u[q + 1] + fine.u[q - ss] + fine.u[q + ss] -
                                4.0 * fine.u[q]);
        }
      }
      const int cs = coarse.nx + 2;
      for (int jc = 1; jc <= coarse.ny; ++jc) {
        for (int ic = 1; ic <= coarse.nx; ++ic) {
          const std::size_t q = static_cast<std::size_t>(2 * jc * s + 2 * ic);
          const std::size_t ss = static_cast<std::size_t>(s);
          const double sum = 4.0 * res[q] +
                             2.0 * (res[q - 1] + res[q + 1] + res[q - ss] + res[q + ss]) +
                             res[q - ss - 1] + res[q - ss + 1] + res[q + ss - 1] + res[q + ss + 1];
          coarse.f[static_cast<std::size_t>(jc * cs + ic)] = 0.25 * sum;
        }
      }
      std::fill(coarse.u.begin(), coarse.u.end(), 0.0);
      std::fill(coarse.tmp.begin(), coarse.tmp.end(), 0.0);
    }
    sweeps(p[static_cast<std::size_t>(levels) - 1], config_.coarsest_sweeps, false);
    for (int l = levels - 2; l >= 0; --l) {
      Level& fine = p[static_cast<std::size_t>(l)];
      const Level& coarse = p[static_cast<std::size_t>(l) + 1];
      const int s = fine.nx + 2;
      const int cs = coarse.nx + 2;
      for (int j = 1; j <= fine.ny; ++j) {
        for (int i = 1; i <= fine.nx; ++i) {
          const std::size_t b = static_cast<std::size_t>((j >> 1) * cs + (i >> 1));
          const std::size_t ccs = static_cast<std::size_t>(cs);
          double corr;
          if ((i & 1) != 0) {
            corr = (j & 1) != 0 ? 0.25 * (coarse.u[b] + coarse.u[b + 1] + coarse.u[b + ccs] +
                                          coarse.u[b + ccs + 1])
                                : 0.5 * (coarse.u[b] + coarse.u[b + 1]);
          } else {
            corr = (j & 1) != 0 ? 0.5 * (coarse.u[b] + coarse.u[b + ccs]) : coarse.u[b];
          }
          fine.u[static_cast<std::size_t>(j * s + i)] += corr;
        }
      }
      sweeps(fine, config_.post_sweeps, true);
    }
  }
}

void NhhdRef::decompose(const GridVectorD& w, const GridMaskD& valid, GridVectorD& d,
                        GridVectorD& r, GridVectorD& k) {
  GridScalarD div;
  GridScalarD curl;
  nhhd_sources_ref(w, valid, div, curl);
  for (Potential* p : {&phi_, &psi_}) {
    const GridScalarD& src = p == &phi_ ? div : curl;
    Level& lv = (*p)[0];
    std::fill(lv.f.begin(), lv.f.end(), 0.0);
    for (int gy = 0; gy < kGridHeight; ++gy) {
      for (int gx = 0; gx < kGridWidth; ++gx) {
        lv.f[static_cast<std::size_t>((gy + kOriginY) * (lv.nx + 2) + gx + kOriginX)] =
            src[static_cast<std::size_t>(gy * kGridWidth + gx)];
      }
    }
    set_ring(*p, src);
    solve(*p);
  }
  const Level& ph = phi_[0];
  const Level& ps = psi_[0];
  const std::size_t s = static_cast<std::size_t>(ph.nx + 2);
  GridVectorD dd;
  GridVectorD rr;
  GridVectorD kk;
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const std::size_t p = static_cast<std::size_t>(gy * kGridWidth + gx);
      const std::size_t i =
          static_cast<std::size_t>(gy + kOriginY) * s + static_cast<std::size_t>(gx + kOriginX);
      dd.x[p] = 0.5 * (ph.u[i + 1] - ph.u[i - 1]);
      dd.y[p] = 0.5 * (ph.u[i + s] - ph.u[i - s]);
      rr.x[p] = -0.5 * (ps.u[i + s] - ps.u[i - s]);
      rr.y[p] = 0.5 * (ps.u[i + 1] - ps.u[i - 1]);
      kk.x[p] = w.x[p] - dd.x[p] - rr.x[p];
      kk.y[p] = w.y[p] - dd.y[p] - rr.y[p];
    }
  }
  d = std::move(dd);
  r = std::move(rr);
  k = std::move(kk);
}

void green_decompose_ref(const GridVectorD& w, const GridMaskD& valid, GridVectorD& d,
                         GridVectorD& r, GridVectorD& k) {
  GridScalarD div;
  GridScalarD curl;
  nhhd_sources_ref(w, valid, div, curl);
  const double inv2pi = 0.5 / std::numbers::pi;
  GridVectorD dd;
  GridVectorD rr;
  GridVectorD kk;
  for (int y = 0; y < kGridHeight; ++y) {
    for (int x = 0; x < kGridWidth; ++x) {
      double ax = 0.0;
      double ay = 0.0;
      double bx = 0.0;
      double by = 0.0;
      for (int v = 0; v < kGridHeight; ++v) {
        for (int u = 0; u < kGridWidth; ++u) {
          if (u == x && v == y) continue;
          const std::size_t q = static_cast<std::size_t>(v * kGridWidth + u);
          const double ex = x - u;
          const double ey = y - v;
          const double g = inv2pi / (ex * ex + ey * ey);
          ax += g * ex * div[q];
          ay += g * ey * div[q];
          // grad psi = sum g e curl; r = (-d_y psi, d_x psi)
          bx -= g * ey * curl[q];
          by += g * ex * curl[q];
        }
      }
      const std::size_t p = static_cast<std::size_t>(y * kGridWidth + x);
      dd.x[p] = ax;
      dd.y[p] = ay;
      rr.x[p] = bx;
      rr.y[p] = by;
      kk.x[p] = w.x[p] - ax - bx;
      kk.y[p] = w.y[p] - ay - by;
    }
  }
  d = std::move(dd);
  r = std::move(rr);
  k = std::move(kk);
}

}  // namespace tacse3::dsp_ref
