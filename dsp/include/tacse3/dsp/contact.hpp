// SPDX-License-Identifier: Apache-2.0
// tacse3 dsp: contact mask Ω with hysteresis and minimum area, and the 3D contact points q.
#pragma once

#include <array>
#include <cstdint>

#include "tacse3/dsp/calibration.hpp"
#include "tacse3/dsp/types.hpp"

namespace tacse3::dsp {

// Contact points are integers in nanometres (LSB 1e-9 m) in the SENSOR frame S
// (x, y = image axes, z into the gel). |x|, |y| are clamped to kMaxPointNm (33.5 mm, well beyond
// the 24 x 18 mm pad), z to [0, height_max_m] ≤ 1e7 nm. These bounds keep every moment sum of
// motion.hpp inside int64 (see there).
inline constexpr std::int32_t kMaxPointNm = (std::int32_t{1} << 25) - 1;

// Output of ContactDetector::detect. Arrays are indexed like every grid field.
struct ContactSet {
  GridMask mask;                 // Ω_t (1 = contact)
  ScalarField fz_filtered;       // filter(f^z), Q16 f^z units, 0 at invalid points
  GridArray<std::int32_t> x_nm;  // q_x at the point's CURRENT position (0 outside Ω)
  GridArray<std::int32_t> y_nm;  // q_y
  GridArray<std::int32_t> z_nm;  // q_z = g(filter(f^z)) ≥ 0
  int count = 0;                 // |Ω_t|
  int components = 0;            // 4-connected components kept (each ≥ min area)
  int cells_dropped = 0;         // cells above threshold removed by the minimum-area rule
  bool contact = false;          // count > 0
};

// Paper Sec. IV-B: Ω_c = {(x, y) | f_filter(f^z(x, y)) > τ} and
// q_ij = ((i − i0)/κx, (j − j0)/κy, g(f^z_ij)).
//  - f_filter: 3x3 binomial ([1 2 1]ᵀ[1 2 1]/16), normalised over valid neighbours, so invalid
//    points and the grid border do not pull the response down.
//  - hysteresis: a cell enters Ω when filter(f^z) > τ_on, and a cell of last frame's Ω stays while
//    filter(f^z) > τ_off (τ_off ≤ τ_on). "Last frame's Ω" is the reported (post-area) mask.
//  - minimum area: 4-connected components smaller than contact_min_area_cells are dropped
//    (speckle rejection without losing a second, real contact).
//  - (i, j) is the sensor-pixel position of the material point's CURRENT location,
//    (8gx + 3.5 + 2 w.x, 8gy + 3.5 + 2 w.y), and (i0, j0) = (159.5, 119.5) the pad centre.
//  - g(f^z) = min(height_gain_m · max(f^z, 0), height_max_m), monotone non-decreasing.
// State: last frame's mask (hysteresis) plus scratch for the filter. Size ≈ 16 KB; no heap.
class ContactDetector {
 public:
  ContactDetector() noexcept;  // configured with Calibration{} defaults
  // kBadCalibration (previous configuration kept) if validate(cal) fails. Does not reset state.
  Status configure(const Calibration& cal) noexcept;
  // Forget the hysteresis state (call on tare).
  void reset() noexcept;

  // Scaling and overflow:
  //  - fz Q16; the 3x3 filter sums 16 · |fz| < 2^35 in int64 and divides by the valid weight sum
  //    (round half away from zero); the result fits int32 since it is a weighted mean.
  //  - w Q16 working px; the current position relative to the pad centre is formed in int64 in
  //    Q16 sensor px, clamped to ±1024 px, multiplied by the Q16 pitch in nm (≤ 2e5 nm/px,
  //    < 2^34), shifted right by 32 with round-half-up and clamped to ±kMaxPointNm.
  //  - z: max(f^z, 0) (< 2^31) × height gain in integer nm per f^z unit (≤ 1e9 < 2^30), shifted
  //    right by 16 with round-half-up, clamped to height_max_m in nm.
  void detect(const ScalarField& fz, const VectorField& w, const GridMask& valid,
              ContactSet& out) noexcept;

  const GridMask& previous_mask() const noexcept { return prev_; }

 private:
  std::int32_t tau_on_q16_ = 0;
  std::int32_t tau_off_q16_ = 0;
  int min_area_ = 1;
  std::int64_t pitch_x_nm_q16_ = 0;
  std::int64_t pitch_y_nm_q16_ = 0;
  std::int64_t height_nm_per_unit_ = 0;
  std::int32_t height_max_nm_ = 0;
  GridMask prev_;
  GridMask visited_;
  std::array<std::int64_t, kGridCount> row_num_{};  // horizontal [1 2 1] pass of valid f^z
  std::array<std::uint8_t, kGridCount> row_den_{};  // its weight sum (0..4)
  std::array<std::uint16_t, kGridCount> queue_{};
};

}  // namespace tacse3::dsp
