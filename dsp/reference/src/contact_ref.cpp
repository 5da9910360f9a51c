// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp reference: double-precision contact mask (filter, hysteresis, area) and 3D points.
#include "tacse3/dsp_ref/contact_ref.hpp"

#include <algorithm>

#include "tacse3/dsp/fixed.hpp"
#include "tacse3/dsp/geometry.hpp"

namespace tacse3::dsp_ref {
namespace {
using dsp::kGridCount;
using dsp::kGridHeight;
using dsp::kGridWidth;
std::size_t idx(int gx, int gy) {
  return static_cast<std::size_t>(gy * kGridWidth + gx);
}
}  // namespace

ContactDetectorRef::ContactDetectorRef(const dsp::Calibration& cal)
    : cal_(cal), prev_(static_cast<std::size_t>(kGridCount), 0) {}

void ContactDetectorRef::reset() {
  std::fill(prev_.begin(), prev_.end(), std::uint8_t{0});
}

ContactSetRef ContactDetectorRef::detect(const std::vector<double>& fz, const dsp::VectorField& w,
                                         const dsp::GridMask& valid, const dsp::GridMask* follow) {
  const auto n = static_cast<std::size_t>(kGridCount);
  ContactSetRef out;
  out.mask.assign(n, 0);
  out.fz_filtered.assign(n, 0.0);
  out.q.assign(n, Eigen::Vector3d::Zero());
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      if (valid(gx, gy) == 0) continue;
      double num = 0.0, den = 0.0;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = gx + dx, y = gy + dy;
          if (x < 0 || x >= kGridWidth || y < 0 || y >= kGridHeight || valid(x, y) == 0) continue;
          const double wgt = (dx == 0 ? 2.0 : 1.0) * (dy == 0 ? 2.0 : 1.0);
          num += wgt * fz[idx(x, y)];
          den += wgt;
        }
      }
      out.fz_filtered[idx(gx, gy)] = num / den;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double f = out.fz_filtered[i];
    out.mask[i] = (valid.v[i] != 0 &&
                   (f > cal_.contact_tau_on || (prev_[i] != 0 && f > cal_.contact_tau_off)))
                      ? 1
                      : 0;
    // A followed cell that this chain's flow did not track has filter(f^z) = 0 here, so its
    // height is 0: harmless when the flow's validity is followed too (then the two agree).
    if (follow != nullptr) out.mask[i] = follow->v[i] != 0 ? 1 : 0;
  }
  // A followed mask is already past the minimum-area rule.
  const int min_area = follow != nullptr ? 0 : cal_.contact_min_area_cells;
  // Connected components (4-neighbourhood), flood fill with an explicit stack.
  std::vector<std::uint8_t> seen(n, 0);
  for (int seed = 0; seed < kGridCount; ++seed) {
    if (out.mask[static_cast<std::size_t>(seed)] == 0 || seen[static_cast<std::size_t>(seed)])
      continue;
    std::vector<int> comp, stack{seed};
    seen[static_cast<std::size_t>(seed)] = 1;
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      comp.push_back(c);
      const int cx = c % kGridWidth, cy = c / kGridWidth;
      const int nb[4][2] = {{cx - 1, cy}, {cx + 1, cy}, {cx, cy - 1}, {cx, cy + 1}};
      for (const auto& p : nb) {
        if (p[0] < 0 || p[0] >= kGridWidth || p[1] < 0 || p[1] >= kGridHeight) continue;
        const std::size_t j = idx(p[0], p[1]);
        if (out.mask[j] == 0 || seen[j]) continue;
        seen[j] = 1;
        stack.push_back(static_cast<int>(j));
      }
    }
    if (static_cast<int>(comp.size()) < min_area) {
      for (int c : comp) out.mask[static_cast<std::size_t>(c)] = 0;
    } else {
      ++out.components;
      out.count += static_cast<int>(comp.size());
    }
  }
  const double px = cal_.pixel_pitch_m, py = cal_.pixel_pitch_m * cal_.pixel_aspect_y;
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const std::size_t i = idx(gx, gy);
      if (out.mask[i] == 0) continue;
      // Current sensor-pixel position of the material point, relative to the pad centre.
      const double si = dsp::grid_sensor_x(gx) + dsp::kWorkScale * dsp::from_q<16>(w.x(gx, gy));
      const double sj = dsp::grid_sensor_y(gy) + dsp::kWorkScale * dsp::from_q<16>(w.y(gx, gy));
      const double z =
          std::min(cal_.height_gain_m * std::max(out.fz_filtered[i], 0.0), cal_.height_max_m);
      out.q[i] = Eigen::Vector3d((si - dsp::kPadCentreX) * px, (sj - dsp::kPadCentreY) * py, z);
    }
  }
  prev_ = out.mask;
  return out;
}

}  // namespace tacse3::dsp_ref
