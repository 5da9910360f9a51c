// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: calibrated linear maps (𝒢, d, r, k) → normal response f^z and shear (f^x, f^y).
#include "tacse3/dsp/force_map.hpp"

#include "tacse3/dsp/fixed.hpp"

namespace tacse3::dsp {
namespace {

bool valid_at(const GridMask& m, int gx, int gy) noexcept {
  return gx >= 0 && gx < kGridWidth && gy >= 0 && gy < kGridHeight && m(gx, gy) != 0;
}

// One axis of the divergence at (gx, gy), in units of Q16/8 (so central and one-sided
// differences share one final shift). (dx, dy) is the unit step along the axis.
std::int64_t axis_derivative_q19(const GridArray<std::int32_t>& c, const GridMask& valid, int gx,
                                 int gy, int dx, int dy) noexcept {
  const bool lo = valid_at(valid, gx - dx, gy - dy);
  const bool hi = valid_at(valid, gx + dx, gy + dy);
  const std::int64_t centre = c(gx, gy);
  if (lo && hi) {  // (c[+1] − c[−1]) / 8 px  →  ×1 in Q16/8
    return static_cast<std::int64_t>(c(gx + dx, gy + dy)) - c(gx - dx, gy - dy);
  }
  if (hi) {  // (c[+1] − c[0]) / 4 px  →  ×2 in Q16/8
    return 2 * (static_cast<std::int64_t>(c(gx + dx, gy + dy)) - centre);
  }
  if (lo) {
    return 2 * (centre - c(gx - dx, gy - dy));
  }
  return 0;
}

}  // namespace

void grid_divergence(const VectorField& v, const GridMask& valid, ScalarField& div) noexcept {
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const auto i = static_cast<std::size_t>(gy * kGridWidth + gx);
      if (valid.v[i] == 0) {
        div.v[i] = 0;
        continue;
      }
      std::int64_t sum;
      const bool interior = gx > 0 && gx + 1 < kGridWidth && gy > 0 && gy + 1 < kGridHeight &&
                            valid.v[i - 1] != 0 && valid.v[i + 1] != 0 &&
                            valid.v[i - kGridWidth] != 0 && valid.v[i + kGridWidth] != 0;
      if (interior) {  // the common case: both central differences
        sum = static_cast<std::int64_t>(v.x.v[i + 1]) - v.x.v[i - 1] +
              static_cast<std::int64_t>(v.y.v[i + kGridWidth]) - v.y.v[i - kGridWidth];
      } else {
        sum = axis_derivative_q19(v.x, valid, gx, gy, 1, 0) +
              axis_derivative_q19(v.y, valid, gx, gy, 0, 1);
      }
      // Grid step = kGridStride (4) working px: central /8, one-sided /4 (×2 in Q16/8).
      div.v[i] = sat32(rshift_round(sum, 3));
    }
  }
}

ForceMap::ForceMap() noexcept {
  (void)configure(Calibration{});
}

Status ForceMap::configure(const Calibration& cal) noexcept {
  const Status s = validate(cal);
  if (s != Status::kOk) return s;
  a_density_ = to_q32<kFieldFrac>(cal.normal_gain_density);
  a_div_ = to_q32<kFieldFrac>(cal.normal_gain_divergence);
  s_d_ = to_q32<kFieldFrac>(cal.shear_gain_d);
  s_r_ = to_q32<kFieldFrac>(cal.shear_gain_r);
  s_k_ = to_q32<kFieldFrac>(cal.shear_gain_k);
  return Status::kOk;
}

void ForceMap::compute(const ScalarField& density, const VectorField& d, const VectorField& r,
                       const VectorField& k, const GridMask& valid, ScalarField& fz,
                       VectorField& shear) const noexcept {
  // The divergence term costs a pass over d; skip it when its gain is zero (the default).
  if (a_div_ != 0) {
    grid_divergence(d, valid, fz);  // fz temporarily holds div(d), Q16
  }
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    if (valid.v[i] == 0) {
      fz.v[i] = 0;
      shear.x.v[i] = 0;
      shear.y.v[i] = 0;
      continue;
    }
    // Q16 gain × Q16 field = Q32 in int64; one rounding shift back to Q16.
    std::int64_t n = -static_cast<std::int64_t>(density.v[i]) * a_density_;
    if (a_div_ != 0) n += static_cast<std::int64_t>(fz.v[i]) * a_div_;
    fz.v[i] = sat32(rshift_round(n, kFieldFrac));
    const std::int64_t sx = static_cast<std::int64_t>(d.x.v[i]) * s_d_ +
                            static_cast<std::int64_t>(r.x.v[i]) * s_r_ +
                            static_cast<std::int64_t>(k.x.v[i]) * s_k_;
    const std::int64_t sy = static_cast<std::int64_t>(d.y.v[i]) * s_d_ +
                            static_cast<std::int64_t>(r.y.v[i]) * s_r_ +
                            static_cast<std::int64_t>(k.y.v[i]) * s_k_;
    shear.x.v[i] = sat32(rshift_round(sx, kFieldFrac));
    shear.y.v[i] = sat32(rshift_round(sy, kFieldFrac));
  }
}

}  // namespace tacse3::dsp
