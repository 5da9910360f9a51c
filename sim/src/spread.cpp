// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: elastic half-space spreading of the patch displacement (rigid-punch decay).
#include "tacse3/sim/spread.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace tacse3::sim {

void HalfSpaceSpread::build(int gw, int gh, double cell_mm, double thickness_mm) {
  gw_ = gw;
  gh_ = gh;
  cell_mm_ = cell_mm;
  thickness_mm_ = thickness_mm;
  rw_ = std::max(1, static_cast<int>(std::ceil(5.0 * thickness_mm / cell_mm)));
  const int side = 2 * rw_ + 1;
  inv_r_.assign(static_cast<std::size_t>(side) * static_cast<std::size_t>(side), 0.0);
  r_mm_.assign(inv_r_.size(), 0.0);
  for (int dj = -rw_; dj <= rw_; ++dj) {
    for (int di = -rw_; di <= rw_; ++di) {
      const std::size_t k = static_cast<std::size_t>(dj + rw_) * static_cast<std::size_t>(side) +
                            static_cast<std::size_t>(di + rw_);
      const double r = std::hypot(di, dj) * cell_mm;
      r_mm_[k] = r;
      inv_r_[k] = r > 0.0 ? 1.0 / r : 0.0;
    }
  }
  const auto n = static_cast<std::size_t>(gw) * static_cast<std::size_t>(gh);
  sx_.assign(n, 0.0);
  sy_.assign(n, 0.0);
  sw_.assign(n, 0.0);
  dmin_.assign(n, 0.0);
}

double HalfSpaceSpread::decay(double a_mm, double delta_mm, double thickness_mm) noexcept {
  const double d = std::max(0.0, delta_mm);
  return (2.0 / std::numbers::pi) * std::asin(a_mm / (a_mm + d)) * std::exp(-d / thickness_mm);
}

void HalfSpaceSpread::apply(const std::uint8_t* contact, double* ux, double* uy) noexcept {
  const int gw = gw_, gh = gh_, side = 2 * rw_ + 1;
  const double inf = std::numeric_limits<double>::infinity();
  std::fill(sx_.begin(), sx_.end(), 0.0);
  std::fill(sy_.begin(), sy_.end(), 0.0);
  std::fill(sw_.begin(), sw_.end(), 0.0);
  std::fill(dmin_.begin(), dmin_.end(), inf);
  const auto at = [gw](int i, int j) {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(gw) + static_cast<std::size_t>(i);
  };
  int area = 0;
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      const std::size_t k = at(i, j);
      if (!contact[k]) continue;
      ++area;
      // A rim cell has a free 4-neighbour; only the rim carries the field outward.
      const bool rim = (i > 0 && !contact[k - 1]) || (i + 1 < gw && !contact[k + 1]) ||
                       (j > 0 && !contact[k - static_cast<std::size_t>(gw)]) ||
                       (j + 1 < gh && !contact[k + static_cast<std::size_t>(gw)]);
      if (!rim) continue;
      const double u = ux[k], v = uy[k];
      const int j0 = std::max(0, j - rw_), j1 = std::min(gh - 1, j + rw_);
      const int i0 = std::max(0, i - rw_), i1 = std::min(gw - 1, i + rw_);
      for (int jj = j0; jj <= j1; ++jj) {
        const std::size_t row =
            static_cast<std::size_t>(jj - j + rw_) * static_cast<std::size_t>(side);
        for (int ii = i0; ii <= i1; ++ii) {
          const std::size_t t = at(ii, jj);
          if (contact[t]) continue;
          const std::size_t w = row + static_cast<std::size_t>(ii - i + rw_);
          sx_[t] += inv_r_[w] * u;
          sy_[t] += inv_r_[w] * v;
          sw_[t] += inv_r_[w];
          dmin_[t] = std::min(dmin_[t], r_mm_[w]);
        }
      }
    }
  }
  const double a = std::sqrt(area * cell_mm_ * cell_mm_ / std::numbers::pi);
  const double cut = window_mm();
  for (std::size_t k = 0; k < sx_.size(); ++k) {
    if (contact[k]) continue;
    if (area == 0 || !(dmin_[k] <= cut) || sw_[k] <= 0.0) {
      ux[k] = 0.0;
      uy[k] = 0.0;
      continue;
    }
    // dmin is measured between cell centres; the rim itself lies half a cell out.
    const double f = decay(a, dmin_[k] - 0.5 * cell_mm_, thickness_mm_) / sw_[k];
    ux[k] = sx_[k] * f;
    uy[k] = sy_[k] * f;
  }
}

}  // namespace tacse3::sim
