// SPDX-License-Identifier: Apache-2.0
// tacse3 sim: spreading of the patch's in-plane displacement by an elastic half-space kernel.
#pragma once

#include <cstdint>
#include <vector>

namespace tacse3::sim {

// Outside the contact patch a soft layer much thicker than the patch is an elastic half-space:
// a rigid circular punch of radius a displaced tangentially by U moves the free surface at
// distance delta from its rim by U (2/pi) asin(a / (a + delta)) (the Boussinesq-Cerruti
// rigid-punch solution; 1/r far field). A real gel has a thickness L on a rigid backing, which
// screens that tail: the field is multiplied by exp(-delta / L) and cut at 5 L.
//
// For a general patch, a is the radius of the disc of the same area, delta the distance to the
// nearest rim cell and U the 1/r-weighted mean of the rim cells' displacements seen from the
// cell, so the field is continuous at the rim. build() allocates; apply() does not.
class HalfSpaceSpread {
 public:
  void build(int gw, int gh, double cell_mm, double thickness_mm);
  // Keeps U on cells with contact != 0 and overwrites every other cell.
  void apply(const std::uint8_t* contact, double* ux, double* uy) noexcept;

  // The decay factor above (1 at the rim).
  static double decay(double a_mm, double delta_mm, double thickness_mm) noexcept;
  double window_mm() const noexcept { return rw_ * cell_mm_; }

 private:
  int gw_ = 0, gh_ = 0, rw_ = 0;
  double cell_mm_ = 0.4, thickness_mm_ = 2.0;
  std::vector<double> inv_r_, r_mm_;  // per window offset, (2 rw + 1)^2
  std::vector<double> sx_, sy_, sw_, dmin_;
};

}  // namespace tacse3::sim
