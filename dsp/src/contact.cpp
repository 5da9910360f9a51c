// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: contact mask Ω with hysteresis and minimum area, and the 3D contact points q.
#include "tacse3/dsp/contact.hpp"

#include <cmath>

#include "tacse3/dsp/fixed.hpp"

namespace tacse3::dsp {
namespace {

// Q16 sensor-pixel position of a grid point relative to the pad centre, before displacement:
// (8 g + 3.5 − centre) · 2^16, with centre 159.5 (x) / 119.5 (y); both are integers · 2^16.
constexpr std::int64_t kOne = std::int64_t{1} << kFieldFrac;
constexpr std::int64_t base_x_q16(int gx) noexcept {
  return (8 * static_cast<std::int64_t>(gx) - 156) * kOne;
}
constexpr std::int64_t base_y_q16(int gy) noexcept {
  return (8 * static_cast<std::int64_t>(gy) - 116) * kOne;
}
static_assert(kGridStride * kWorkScale == 8, "base_*_q16 assume 8 sensor px per grid step");

constexpr std::int64_t kMaxRelPxQ16 = std::int64_t{1024} * kOne;

std::int64_t clamp64(std::int64_t v, std::int64_t lo, std::int64_t hi) noexcept {
  return v < lo ? lo : (v > hi ? hi : v);
}

// Rounded integer division, den > 0, round half away from zero.
std::int64_t div_round(std::int64_t num, std::int64_t den) noexcept {
  return num >= 0 ? (num + den / 2) / den : -((-num + den / 2) / den);
}

std::int32_t position_nm(std::int64_t base_q16, std::int32_t w_q16,
                         std::int64_t pitch_nm_q16) noexcept {
  // Sensor px = 2 · working px (kWorkScale).
  const std::int64_t rel = clamp64(base_q16 + kWorkScale * static_cast<std::int64_t>(w_q16),
                                   -kMaxRelPxQ16, kMaxRelPxQ16);
  const std::int64_t nm = rshift_round(rel * pitch_nm_q16, 2 * kFieldFrac);
  return static_cast<std::int32_t>(clamp64(nm, -kMaxPointNm, kMaxPointNm));
}

}  // namespace

ContactDetector::ContactDetector() noexcept {
  (void)configure(Calibration{});
}

Status ContactDetector::configure(const Calibration& cal) noexcept {
  const Status s = validate(cal);
  if (s != Status::kOk) return s;
  tau_on_q16_ = to_q32<kFieldFrac>(cal.contact_tau_on);
  tau_off_q16_ = to_q32<kFieldFrac>(cal.contact_tau_off);
  min_area_ = cal.contact_min_area_cells;
  const double q16 = static_cast<double>(kOne);
  pitch_x_nm_q16_ = std::llround(cal.pixel_pitch_m * 1e9 * q16);
  pitch_y_nm_q16_ = std::llround(cal.pixel_pitch_m * cal.pixel_aspect_y * 1e9 * q16);
  height_nm_per_unit_ = std::llround(cal.height_gain_m * 1e9);
  height_max_nm_ = static_cast<std::int32_t>(std::llround(cal.height_max_m * 1e9));
  return Status::kOk;
}

void ContactDetector::reset() noexcept {
  prev_.fill(0);
}

void ContactDetector::detect(const ScalarField& fz, const VectorField& w, const GridMask& valid,
                             ContactSet& out) noexcept {
  // 1. f_filter: normalised 3x3 binomial over valid points, as two separable [1 2 1] passes of
  //    the masked values and of the mask weights (so the normalisation is exact).
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const auto i = static_cast<std::size_t>(gy * kGridWidth + gx);
      const bool lo = gx > 0 && valid.v[i - 1] != 0;
      const bool hi = gx + 1 < kGridWidth && valid.v[i + 1] != 0;
      const bool mid = valid.v[i] != 0;
      std::int64_t num = mid ? 2 * static_cast<std::int64_t>(fz.v[i]) : 0;
      if (lo) num += fz.v[i - 1];
      if (hi) num += fz.v[i + 1];
      row_num_[i] = num;
      row_den_[i] = static_cast<std::uint8_t>((mid ? 2 : 0) + (lo ? 1 : 0) + (hi ? 1 : 0));
    }
  }
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      const auto i = static_cast<std::size_t>(gy * kGridWidth + gx);
      if (valid.v[i] == 0) {
        out.fz_filtered.v[i] = 0;
        continue;
      }
      std::int64_t num = 2 * row_num_[i];
      std::int64_t den = 2 * row_den_[i];
      if (gy > 0) {
        num += row_num_[i - kGridWidth];
        den += row_den_[i - kGridWidth];
      }
      if (gy + 1 < kGridHeight) {
        num += row_num_[i + kGridWidth];
        den += row_den_[i + kGridWidth];
      }
      // den ≥ 4 (the point itself is valid); 16 in the interior of the valid region, where the
      // constant divisor compiles to a shift.
      // Same rounding as div_round(num, 16), spelled as shifts so no 64-bit divide is emitted.
      const std::int64_t q =
          den == 16 ? (num >= 0 ? (num + 8) >> 4 : -((-num + 8) >> 4)) : div_round(num, den);
      out.fz_filtered.v[i] = static_cast<std::int32_t>(q);
    }
  }

  // 2. Hysteresis against the previous reported mask.
  for (std::size_t i = 0; i < static_cast<std::size_t>(kGridCount); ++i) {
    const std::int32_t f = out.fz_filtered.v[i];
    const bool on = valid.v[i] != 0 && (f > tau_on_q16_ || (prev_.v[i] != 0 && f > tau_off_q16_));
    out.mask.v[i] = on ? 1 : 0;
  }

  // 3. Minimum area per 4-connected component (breadth-first, queue doubles as the member list).
  visited_.fill(0);
  out.components = 0;
  out.cells_dropped = 0;
  out.count = 0;
  for (int seed = 0; seed < kGridCount; ++seed) {
    const auto s = static_cast<std::size_t>(seed);
    if (out.mask.v[s] == 0 || visited_.v[s] != 0) continue;
    int head = 0;
    int tail = 0;
    queue_[static_cast<std::size_t>(tail++)] = static_cast<std::uint16_t>(seed);
    visited_.v[s] = 1;
    while (head < tail) {
      const int c = queue_[static_cast<std::size_t>(head++)];
      const int cx = c % kGridWidth;
      const int cy = c / kGridWidth;
      const int nbr[4][2] = {{cx - 1, cy}, {cx + 1, cy}, {cx, cy - 1}, {cx, cy + 1}};
      for (const auto& n : nbr) {
        if (n[0] < 0 || n[0] >= kGridWidth || n[1] < 0 || n[1] >= kGridHeight) continue;
        const auto ni = static_cast<std::size_t>(n[1] * kGridWidth + n[0]);
        if (out.mask.v[ni] == 0 || visited_.v[ni] != 0) continue;
        visited_.v[ni] = 1;
        queue_[static_cast<std::size_t>(tail++)] = static_cast<std::uint16_t>(ni);
      }
    }
    if (tail < min_area_) {
      for (int q = 0; q < tail; ++q) out.mask.v[queue_[static_cast<std::size_t>(q)]] = 0;
      out.cells_dropped += tail;
    } else {
      ++out.components;
      out.count += tail;
    }
  }
  out.contact = out.count > 0;

  // 4. 3D contact points at the current (displaced) positions, sensor frame, nm.
  for (int gy = 0; gy < kGridHeight; ++gy) {
    for (int gx = 0; gx < kGridWidth; ++gx) {
      if (out.mask(gx, gy) == 0) {
        out.x_nm(gx, gy) = 0;
        out.y_nm(gx, gy) = 0;
        out.z_nm(gx, gy) = 0;
        continue;
      }
      out.x_nm(gx, gy) = position_nm(base_x_q16(gx), w.x(gx, gy), pitch_x_nm_q16_);
      out.y_nm(gx, gy) = position_nm(base_y_q16(gy), w.y(gx, gy), pitch_y_nm_q16_);
      const std::int64_t f = out.fz_filtered(gx, gy) > 0 ? out.fz_filtered(gx, gy) : 0;
      const std::int64_t z = rshift_round(f * height_nm_per_unit_, kFieldFrac);
      out.z_nm(gx, gy) = static_cast<std::int32_t>(z > height_max_nm_ ? height_max_nm_ : z);
    }
  }

  prev_ = out.mask;
}

}  // namespace tacse3::dsp
